"""Session 73: the joint level move's offsets (``gpmsa.mcmc.level_moves``) are recorded. Per
categorical theta name: its "levels", the "shifted" continuous elements and, per chain, their
conditional "modes" at each level in theta's native units (the move from level a to b shifts
them by modes[b] - modes[a]); in ``Posterior.info`` (calibrate: the fast sampler, the numpy
backend, torch) and a joint fit's ``settings`` (kept by the emulator file, printed by
``gpmsa info``). Before, nothing said what the move did. A model without a categorical theta
records nothing (its file and draws as before)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _level_cases import level_function, level_sim

import gpmsa
from gpmsa.cli.main import main
from gpmsa.cli.text import level_moves_text as _level_moves_text


@pytest.fixture(scope="module")
def case():
    """The case of _level_cases (kind 0 at k = 0.9 fits as kind 1 at k = 0.4) on 36 runs, at
    fixed emulator parameters."""
    rng = np.random.default_rng(2)
    sim = level_sim(rng, 36)
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[4.0], [1.0], [0.5]], "lamUz": [1.0],
                                           "lamWs": [1e5], "lamWOs": [1e5]})  # fmt: skip
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    yo = level_function(xo, np.column_stack([np.full(6, 0.4), np.full(6, 1)]))
    return sim, emu, xo, yo + rng.normal(0, 0.05, 6)


def _check(record, n_chains, tol=0.1):
    assert set(record) == {"kind"}
    rec = record["kind"]
    assert rec["levels"] == [0, 1, 2] and rec["shifted"] == ["k"]
    modes = np.asarray(rec["modes"])
    assert modes.shape == (n_chains, 3, 1)
    # kind 0 -> 1 moves k down by about 0.5 (k's native range is about [0.02, 0.97]; a joint
    # fit's short chains move the emulator's parameters too: a wider tolerance)
    np.testing.assert_allclose(modes[:, 1, 0] - modes[:, 0, 0], -0.5, atol=tol)


@pytest.mark.parametrize("how", [{}, {"fast": False}, {"backend": "torch"}])
def test_calibrate_records_the_offsets_per_chain(case, how):
    if how.get("backend") == "torch":
        pytest.importorskip("torch")
    _, emu, xo, yo = case
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # 2 short chains: unconverged
        post = gpmsa.calibrate(emu, xo, yo, n_samples=60, n_burn=10, seed=1, n_chains=2,
                               tune=False, **how)  # fmt: skip
    _check(post.info["level_offsets"], 2)


def test_a_joint_fit_keeps_them_in_its_file_and_info_prints_them(case, tmp_path, capsys):
    sim, _, xo, yo = case
    obs = gpmsa.ObsData(x=xo, y=yo[:, None])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=20, tune=False, seed=0, n_chains=2)
        hot = gpmsa.fit(sim, obs, n_iter=10, tune=False, seed=0, n_chains=1, temperatures=2)
    _check(emu.settings["level_offsets"], 2, 0.25)
    _check(hot.settings["level_offsets"], 1, 0.25)
    path = tmp_path / "lv.gpmsa"
    emu.save(path)
    back = gpmsa.load(path)
    assert back.settings["level_offsets"] == emu.settings["level_offsets"]
    assert back.model_sha256 == emu.model_sha256
    assert main(["info", str(path)]) == 0
    line = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("level moves:")]
    modes = emu.settings["level_offsets"]["kind"]["modes"]
    assert line == [
        f"level moves:     kind shifts k between their modes at each level (chain 1: "
        f"0 -> {modes[0][0][0]:.4g}, 1 -> {modes[0][1][0]:.4g}, 2 -> "
        f"{modes[0][2][0]:.4g}; chain 2: 0 -> {modes[1][0][0]:.4g}, 1 -> "
        f"{modes[1][1][0]:.4g}, 2 -> {modes[1][2][0]:.4g}) (native units)"
    ]


def test_no_categorical_theta_records_nothing_and_bad_records_print_as_they_are():
    rng = np.random.default_rng(0)
    x, t = rng.random((20, 1)), rng.random((20, 1))
    sim = gpmsa.SimData(x, t, np.sin(3 * x) + t, x_names=["s"], t_names=["k"])
    obs = gpmsa.ObsData(x=[[0.3], [0.6]], y=[[0.8], [1.3]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=10, tune=False, seed=0)
        post = gpmsa.calibrate(emu, [[0.3]], [[0.8]], n_samples=20, n_burn=5, seed=0)
    assert "level_offsets" not in emu.settings and "level_offsets" not in post.info
    assert _level_moves_text({"kind": 3}) == "kind: 3 (native units)"
    assert _level_moves_text([1]) == "[1]"
