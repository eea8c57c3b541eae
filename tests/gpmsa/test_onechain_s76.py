"""A one-chain fit (GPM/SA's usual, the default n_chains=1) is judged for convergence as several
chains are, by its split R-hat (the chain's halves) and bulk ESS: a default short one-chain fit
with split R-hat 1.09 and ESS 26 was silent and kept no record. The Calibrator's online updates
stay unjudged (fast, silent); loading a file judges nothing."""

import warnings
from functools import cache

import numpy as np
import pytest
from _calib_cases import one_t_emulator

import gpmsa

ONE_CHAIN = "One chain's split R-hat compares the chain's halves"


@cache
def _sim() -> gpmsa.SimData:
    """30 runs of y = sin(2x) k / 10 (x in [1, 3] m, k in [10, 15]), a little noise."""
    rng = np.random.default_rng(1)
    z = (np.argsort(rng.random((30, 2)), axis=0) + rng.random((30, 2))) / 30
    x, t = 1 + 2 * z[:, :1], 10 + 5 * z[:, 1:]
    y = np.sin(2 * x) * t / 10 + 0.01 * rng.standard_normal((30, 1))
    return gpmsa.SimData(x=x, t=t, y=y, x_names=["x"], t_names=["k"], x_units=["m"])


def _convergence_warnings(caught) -> list[str]:
    return [str(w.message) for w in caught if issubclass(w.category, gpmsa.ConvergenceWarning)]


def test_a_short_one_chain_fit_warns_in_one_chain_words_and_records_it():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        emu = gpmsa.fit(_sim(), n_iter=200, seed=3)  # 160 kept draws: split R-hat 1.09, ESS 26
    texts = _convergence_warnings(caught)
    assert len(texts) == 1
    assert "over 1 chain x 160 draws" in texts[0]
    assert ONE_CHAIN in texts[0] and "independent chains agree" in texts[0]
    assert "a longer chain (n_iter) or n_chains >= 2" in texts[0]
    rec = emu.convergence
    assert rec["n_chains"] == 1 and rec["n_draws"] == 160 and not rec["converged"]
    assert rec["max_rhat"][1] > 1.05 and rec["min_ess"][1] < 50
    assert rec["rhat"]["lamUz"] == emu.diagnostics["lamUz"]["rhat"]  # the split R-hat stored
    assert "lamUz[0]" in rec["flagged"] and "lamUz[0]" in texts[0]


def test_a_long_one_chain_fit_of_an_easy_problem_is_converged_and_silent():
    with warnings.catch_warnings():
        warnings.simplefilter("error", gpmsa.ConvergenceWarning)
        emu = gpmsa.fit(_sim(), n_iter=6000, seed=1, n_keep=200)
    rec = emu.convergence
    assert rec["converged"] and not rec["flagged"] and rec["n_chains"] == 1
    assert rec["max_rhat"][1] <= 1.01 and rec["min_ess"][1] >= 100


def test_the_one_chain_record_round_trips_and_loading_does_not_warn(tmp_path, capsys):
    from gpmsa.cli.main import main

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        emu = gpmsa.fit(_sim(), n_iter=60, seed=2, tune=False)
    assert emu.convergence["n_chains"] == 1 and not emu.convergence["converged"]
    path = emu.save(tmp_path / "one.gpmsa")
    with warnings.catch_warnings():
        warnings.simplefilter("error", gpmsa.ConvergenceWarning)  # judged at fit time only
        back = gpmsa.load(path)
    assert back.convergence == emu.convergence
    capsys.readouterr()
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    line = next(ln for ln in out.splitlines() if ln.startswith("convergence:"))
    assert "1 chain x 48 draws; max split R-hat" in line and "NOT converged" in line


def test_shipped_one_chain_files_load_without_a_record_or_a_warning():
    for name in ("jackal_A", "jackal_B"):  # flagged by the check if refitted (docs/robot.md)
        with warnings.catch_warnings():
            warnings.simplefilter("error", gpmsa.ConvergenceWarning)
            shipped = gpmsa.load(f"control/emulators/{name}.gpmsa")
        assert shipped.settings["n_chains"] == 1 and shipped.convergence is None


def test_calibrate_judges_one_chain_and_a_calibrator_update_does_not():
    emu, x_obs, y_obs = one_t_emulator()
    with pytest.warns(gpmsa.ConvergenceWarning, match=r"over 1 chain x 30 draws.*\(n_samples\)"):
        post = gpmsa.calibrate(emu, x_obs, y_obs, n_samples=40, n_burn=10, seed=0)
    assert post.info["convergence"]["n_chains"] == 1 and not post.info["convergence"]["converged"]
    cal = gpmsa.Calibrator(emu, method="mcmc", mcmc_options={"n_samples": 40, "n_burn": 10},
                           seed=0)  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("error", gpmsa.ConvergenceWarning)
        online = cal.update(x_obs, y_obs)
    assert "convergence" not in online.info and "diagnostics" not in online.info


def test_a_one_chain_calibrate_study_is_judged_by_its_split_r_hat():
    emu, x_obs, y_obs = one_t_emulator()
    with pytest.warns(gpmsa.ConvergenceWarning, match=ONE_CHAIN) as rec:
        study = gpmsa.calibrate_study([emu], [x_obs], [y_obs], n_samples=60, n_burn=10, seed=0)
    texts = _convergence_warnings(rec)
    assert len(texts) == 1 and texts[0].startswith("gpmsa.calibrate_study: ")
    assert "(n_samples) or n_chains >= 2" in texts[0]
    assert study.convergence["n_chains"] == 1 and not study.convergence["converged"]
