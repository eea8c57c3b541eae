"""``gpmsa info`` tells an infinite R-hat from one not computable (session 85).

An emulator file stores every non-finite diagnostic as null, so ``gpmsa info`` printed the
R-hat of chains stuck apart (each chain constant, the chains at different values: R-hat inf)
as "nan" beside other elements, and as nothing at all ("R-hat []") for a one-element
parameter: a reader could not tell "the chains disagree completely" from "not computable".
The file's convergence record flags such an element "R-hat inf"; the line now prints "inf"
there, and ``--json`` keeps the null (strict JSON) and lists those positions under
"rhat_inf" (a study's rows: true or false).
"""

import re
import warnings

import numpy as np
import pytest
from _study_cases import emulator, observations
from test_infodisp_s76 import _strict

import gpmsa
from gpmsa.cli.main import main
from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw
from gpmsa.mcmc import diagnostics
from tests.gpmsa._emulator_edit import replaced

SHAPES = {"betaU": (2, 1), "lamUz": (1,), "lamWs": (1,), "lamWOs": (1,)}


@pytest.fixture(scope="module")
def stuck_file(tmp_path_factory):
    """A two-chain fit whose record says: betaU[0,0] constant (one value: R-hat NaN),
    betaU[1,0] and lamUz stuck apart (R-hat inf), as ``gpmsa.fit`` records them."""
    x = np.linspace(0.0, 1.0, 12)[:, None]
    t = np.random.default_rng(0).random((12, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x[:, 0]) + t[:, 0] ** 2, x_names=["v"],
                        t_names=["a"])  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        emu = gpmsa.fit(sim, n_iter=30, n_chains=2, n_jobs=1, seed=0, tune=False)
    per = emu.convergence["n_draws"]
    apart = np.stack([np.full((per, 1), 1.0), np.full((per, 1), 2.0)])  # chain c at c + 1
    betau = np.concatenate([np.full((2, per, 1, 1), 3.0), apart[:, :, None]], axis=2)
    summary = {**emu.diagnostics,
               **diagnostics.summarize({"lamUz": apart, "betaU": betau})}  # fmt: skip
    assert summary["lamUz"]["rhat"] == [np.inf] and np.isnan(summary["betaU"]["rhat"][0])
    record = diagnostics.convergence(summary, SHAPES, 2, per)
    emu = replaced(emu, diagnostics=summary, convergence=record)
    return str(emu.save(tmp_path_factory.mktemp("emu") / "stuck.gpmsa"))


def test_info_prints_an_infinite_rhat_as_inf_and_an_uncomputable_one_as_nan(stuck_file, capsys):
    assert main(["info", stuck_file]) == 0
    lines = capsys.readouterr().out.splitlines()
    post = {ln.split(":")[0]: ln for ln in lines if ln.startswith("posterior ")}
    assert post["posterior lamUz"].endswith("R-hat [inf]"), post  # before: "R-hat []"
    assert post["posterior betaU"].endswith("R-hat [nan, inf]"), post
    assert re.fullmatch(r"\[\d\.\d{3}\]", post["posterior lamWs"].split("R-hat ")[1]), post


def test_info_json_keeps_null_and_lists_the_infinite_positions(stuck_file, capsys):
    assert main(["info", "--json", stuck_file]) == 0
    out = _strict(capsys.readouterr().out)["posterior"]
    assert out["lamUz"]["rhat"] == [None] and out["lamUz"]["rhat_inf"] == [0]
    assert out["betaU"]["rhat"] == [None, None] and out["betaU"]["rhat_inf"] == [1]
    assert out["lamWs"]["rhat_inf"] == []


def test_a_study_row_says_whether_its_null_rhat_is_infinite(tmp_path, capsys):
    """A study's text computes R-hat from the draws (it printed "inf" already); its JSON wrote
    null for inf and NaN alike."""
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains: not converged
        study = gpmsa.calibrate_study(
            [emulator(None)] * 2, [d[0] for d in data], [d[1] for d in data], labels=["a", "b"],
            n_chains=2, fixed=[{"lamOs": 1.0}, None], n_samples=20, n_burn=0, tune=False, seed=0,
        )  # fmt: skip
    path = study.save(tmp_path / "s.gpmsastudy")
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    theta = arrays["theta"].copy()
    theta[:, :, 0] = [[0.3], [0.4]]  # t[a]: each chain constant, the chains apart
    write_raw(path, {k: v for k, v in manifest.items() if k not in ENVELOPE},
              {**arrays, "theta": theta}, fmt=STUDY_FORMAT)  # fmt: skip
    assert main(["info", str(path)]) == 0
    assert "posterior t[a]: mean 0.35 sd" in (text := capsys.readouterr().out), text
    assert next(ln for ln in text.splitlines() if "t[a]: mean" in ln).endswith("R-hat inf")
    assert main(["info", "--json", str(path)]) == 0
    out = _strict(capsys.readouterr().out)["posterior"]
    assert out["t[a]"]["rhat"] is None and out["t[a]"]["rhat_inf"] is True
    assert out["lamOs[a]"]["rhat"] is None and out["lamOs[a]"]["rhat_inf"] is False  # held
    assert out["t[b]"]["rhat_inf"] is False
