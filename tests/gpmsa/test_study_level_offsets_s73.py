"""Session 73: a study's joint level move (``gpmsa.studies.sampler``) is recorded, as
``gpmsa.calibrate`` and a joint ``gpmsa.fit`` record theirs (test_level_offsets_record_s73.py).
``study.settings["level_offsets"]`` (in ``study.posterior.info`` too, kept by the study file,
printed by ``gpmsa info``) holds per categorical study element its "levels", the "shifted"
continuous elements by study element name (of every model that uses it) and per chain their
conditional "modes" at each level (native units); a ``fit_study`` member records the same under
its own t_name. Before, ``calibrate_study`` and ``fit_study`` recorded nothing of the move. A
study without a categorical parameter records nothing (its settings and draws as before)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _level_cases import level_function, level_sim

import gpmsa
from gpmsa.cli.main import main


@pytest.fixture(scope="module")
def case():
    """kind 0 at k = 0.9 fits as kind 1 at k = 0.4 (_level_cases), 36 runs, fixed emulator
    parameters; two experiments, one per model."""
    rng = np.random.default_rng(2)
    sim = level_sim(rng, 36)
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[4.0], [1.0], [0.5]], "lamUz": [1.0],
                                           "lamWs": [1e5], "lamWOs": [1e5]})  # fmt: skip
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    yo = level_function(xo, np.column_stack([np.full(6, 0.4), np.full(6, 1)]))
    yo = yo + rng.normal(0, 0.05, 6)
    return sim, emu, (xo, yo), (xo[:4], yo[:4])


def _modes(record, shifted, n_chains, tol):
    assert set(record) == {"kind"}
    rec = record["kind"]
    assert rec["levels"] == [0, 1, 2] and rec["shifted"] == shifted
    modes = np.asarray(rec["modes"])
    assert modes.shape == (n_chains, 3, len(shifted))
    np.testing.assert_allclose(modes[:, 1] - modes[:, 0], -0.5, atol=tol)  # kind 0 -> 1: k down
    return modes


def _info_lines(path, capsys, start="level moves:"):
    assert main(["info", str(path)]) == 0
    return [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith(start)]


def test_calibrate_study_records_the_move_keeps_it_in_its_file_and_info_prints_it(
    case, tmp_path, capsys
):
    _, emu, a, b = case
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # 2 short chains: unconverged
        study = gpmsa.calibrate_study([emu, emu], [a[0], b[0]], [a[1], b[1]], shared=["kind"],
                                      n_samples=60, n_burn=10, seed=1, n_chains=2,
                                      tune=False)  # fmt: skip
        hot = gpmsa.calibrate_study([emu, emu], [a[0], b[0]], [a[1], b[1]], shared=["kind"],
                                    n_samples=20, n_burn=5, seed=1, tune=False,
                                    temperatures=2)  # fmt: skip
    shifted = ["k[model0]", "k[model1]"]
    modes = _modes(study.settings["level_offsets"], shifted, 2, 0.1)
    _modes(hot.settings["level_offsets"], shifted, 1, 0.1)
    assert study.posterior.info["level_offsets"] == study.settings["level_offsets"]
    path = tmp_path / "cal.gpmsa"
    study.save(path)
    back = gpmsa.load_study(path)
    assert back.settings["level_offsets"] == study.settings["level_offsets"]

    def level(c, r):
        return f"{r} -> ({modes[c, r, 0]:.4g}, {modes[c, r, 1]:.4g})"

    chains = "; ".join(f"chain {c + 1}: " + ", ".join(level(c, r) for r in range(3))
                       for c in range(2))  # fmt: skip
    assert _info_lines(path, capsys) == [
        f"level moves:     kind shifts k[model0], k[model1] between their modes at each level "
        f"({chains}) (native units)"
    ]


def test_fit_study_records_it_in_the_study_and_its_members(case, tmp_path, capsys):
    sim, _, a, b = case
    obs = [gpmsa.ObsData(x=a[0], y=a[1][:, None]), gpmsa.ObsData(x=b[0], y=b[1][:, None])]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        study = gpmsa.fit_study([sim, sim], obs, shared=["kind", "k"], n_iter=20, seed=0,
                                n_chains=2, tune=False)  # fmt: skip
    record = study.settings["level_offsets"]
    _modes(record, ["k"], 2, 0.25)  # short chains move the emulators' parameters too
    for member in study.members:
        assert member.settings["level_offsets"] == record  # kind is each member's t_name
    path = tmp_path / "fit.gpmsa"
    study.save(path)
    back = gpmsa.load_study(path)
    assert back.members[1].settings["level_offsets"] == record
    study_line = _info_lines(path, capsys)
    assert len(study_line) == 1 and study_line[0].startswith("level moves:     kind shifts k ")
    assert _info_lines(tmp_path / "fit.model1.gpmsa", capsys) == study_line


def test_a_study_without_a_categorical_parameter_records_nothing(case, tmp_path, capsys):
    sim, _, a, b = case
    plain = gpmsa.SimData(sim.x, sim.t[:, :1], sim.y, x_names=["s"], t_names=["k"])
    emu = gpmsa.Emulator.from_params(plain, {"betaU": [[4.0], [1.0]], "lamUz": [1.0],
                                             "lamWs": [1e5], "lamWOs": [1e5]})  # fmt: skip
    study = gpmsa.calibrate_study([emu, emu], [a[0], b[0]], [a[1], b[1]], shared=["k"],
                                  n_samples=20, n_burn=5, seed=1, tune=False)  # fmt: skip
    assert "level_offsets" not in study.settings
    assert "level_offsets" not in study.posterior.info
    study.save(tmp_path / "plain.gpmsa")
    assert _info_lines(tmp_path / "plain.gpmsa", capsys) == []
