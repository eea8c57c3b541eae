"""A separable design and parallel tempering in an emulator file (session 72 follow-ups).

``gpmsa info`` printed ``swap_every`` with the flat settings but neither the ladder nor the
swap rates (lists were skipped), and no word of a separable declaration (file array
kron_factor); it prints both now (``--json`` prints the raw manifest: settings "temperatures",
"swap_every", "swap_rate" and the kron_factor array's entry are in it as they were). A
kron_factor whose grouping does not match the design was refused as "inconsistent content
(GPMSAError: separable: ...)": the error now names arrays/kron_factor.
"""

import json
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main
from gpmsa.errors import EmulatorFileError
from gpmsa.io.container import MAX_MANIFEST_DEPTH


def _sim():
    """x: 5 points, t: 6 points of 2 columns, the runs their product in C order."""
    rng = np.random.default_rng(0)
    xs, ts = np.linspace(0.0, 1.0, 5), rng.random((6, 2))
    x, t = np.repeat(xs, 6)[:, None], np.tile(ts, (5, 1))
    y = np.sin(3 * x[:, 0]) + t[:, 0] ** 2 + 0.3 * t[:, 1]
    return gpmsa.SimData(x=x, t=t, y=y, separable=[[0], [1, 2]], x_names=["v"],
                         t_names=["a", "b"])  # fmt: skip


@pytest.fixture(scope="module")
def tempered_file(tmp_path_factory):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)  # 2 x 30 sweeps
        emu = gpmsa.fit(_sim(), n_iter=30, n_chains=2, n_jobs=1, seed=0, tune=False,
                        temperatures=[1, 3], swap_every=2)  # fmt: skip
    return emu, str(emu.save(tmp_path_factory.mktemp("emu") / "sep.gpmsa"))


def test_info_prints_the_separable_factors_and_the_tempering(tempered_file, capsys):
    emu, path = tempered_file
    assert main(["info", path]) == 0
    out = capsys.readouterr().out
    assert "separable:       [v] (5 points) x [a, b] (6 points), the first varying slowest" in out
    rates = emu.settings["swap_rate"]
    shown = "; ".join(", ".join(f"{r:.3f}" for r in chain) for chain in rates)
    assert (f"tempering:       2 temperatures [1, 3], a swap round every 2 sweep(s); swap "
            f"rates [{shown}] (per chain; per neighbour pair") in out  # fmt: skip
    assert main(["info", "--json", path]) == 0  # the raw manifest holds them as they were
    manifest = json.loads(capsys.readouterr().out)
    assert manifest["settings"]["temperatures"] == [1.0, 3.0]
    assert manifest["settings"]["swap_rate"] == rates and "kron_factor" in manifest["arrays"]


def test_a_plain_file_has_neither_line(tmp_path, capsys):
    sim = _sim()
    prm = {"betaU": np.ones((3, 1)), "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
    dense = gpmsa.SimData(x=sim.x, t=sim.t, y=sim.y)
    assert main(["info", str(gpmsa.Emulator.from_params(dense, prm).save(tmp_path / "d"))]) == 0
    out = capsys.readouterr().out
    assert "separable:" not in out and "tempering:" not in out


def test_hostile_tempering_records_are_printed_escaped(tempered_file):
    from gpmsa.cli.text import tempering_text as _tempering_text

    text = _tempering_text({"temperatures": ["\x1b[2J", {"a": 1}], "swap_every": "\x1b",
                            "swap_rate": [[1e400, None], "x" * 2000]})  # fmt: skip
    assert "\x1b" not in text and len(text) < 700
    _tempering_text({"temperatures": 3, "swap_rate": None})
    deep = []
    for _ in range(MAX_MANIFEST_DEPTH):  # the reader refuses a deeper manifest
        deep = [deep]
    _tempering_text({"temperatures": [1, 2], "swap_rate": deep})


def _record():
    prm = {"betaU": np.ones((3, 1)), "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
    return gpmsa.Emulator.from_params(_sim(), prm).to_record()


@pytest.mark.parametrize(
    ("codes", "why"),
    [([0, 0, 1], "the design is not the product"), ([1, 0, 0], "run 1 has \\[a, b\\]")],
)
def test_a_kron_factor_that_does_not_match_the_design_is_named(codes, why):
    manifest, arrays = _record()
    assert arrays["kron_factor"].tolist() == [0, 1, 1]
    arrays = {**arrays, "kron_factor": np.array(codes, dtype=arrays["kron_factor"].dtype)}
    with pytest.raises(EmulatorFileError, match=rf"^arrays/kron_factor: .*does not match "
                       rf"the design: separable: {why}"):  # fmt: skip
        gpmsa.Emulator.from_record(manifest, arrays)


def test_a_kron_factor_with_a_mean_basis_is_named():
    manifest, arrays = _record()
    manifest["model"]["mean_basis"] = "linear"
    with pytest.raises(EmulatorFileError, match=r"^arrays/kron_factor: a separable design "
                       r"declared with a mean basis"):  # fmt: skip
        gpmsa.Emulator.from_record(manifest, arrays)
