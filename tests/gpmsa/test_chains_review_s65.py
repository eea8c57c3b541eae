"""Session 65, several chains as a user runs them: the convergence verdict shows the figures that
fail it, says when chains lie apart, and ``calibrate`` (and a study) takes a Generator seed and
records the seed it ran with, as ``fit`` does."""

import numpy as np
import pytest
from _study_cases import emulator as study_emulator

import gpmsa
from gpmsa.cli.info import _convergence_line
from gpmsa.mcmc import diagnostics


def _record(rhat: float, ess: float) -> dict:
    summary = {"t": {"rhat": [rhat], "ess": [ess]}}
    return diagnostics.convergence(summary, {"t": ()}, n_chains=4, n_draws=800)


# --- the figures shown are the ones that fail ---------------------------------------------------
def test_a_flagged_figure_is_shown_beyond_its_limit_not_rounded_onto_it():
    # R-hat 1.01018 was shown "1.010" beside "need R-hat <= 1.01", an ESS of 99.6 "100"
    rec = _record(1.01018, 99.6)
    assert rec["flagged"] == {"t": "R-hat 1.0102, ESS 99.6"}
    assert _record(1.0234, 42.4)["flagged"] == {"t": "R-hat 1.023, ESS 42"}  # as before
    line = _convergence_line(rec)  # gpmsa info's line
    assert "max R-hat 1.0102 (t), min bulk ESS 99.6 (t)" in line
    assert "max R-hat 1.004 (t), min bulk ESS 100 (t); converged" in _convergence_line(
        _record(1.0041, 100.4)
    )
    assert diagnostics.beyond(float("inf"), 1.01, 3) == "inf"
    assert diagnostics.beyond(1.01 + 1e-15, 1.01, 3) == "1.01000000000"  # gives up: no endless loop


def test_chains_that_lie_apart_are_told_longer_chains_may_not_mend_it():
    # five calibration chains, one in the other mode of a symmetric posterior: R-hat 1.44
    with pytest.warns(gpmsa.ConvergenceWarning) as got:
        diagnostics.warn_unconverged(_record(1.443, 10.0), "gpmsa.calibrate", length="n_samples")
    text = str(got[0].message)
    assert "t: R-hat 1.443, ESS 10. Run longer chains (n_samples)" in text
    assert "R-hat 1.443 (t) says the chains lie apart" in text
    assert "several modes" in text and "gpmsa.plots.traces" in text
    stuck = _record(float("inf"), 2.0)  # chains stuck at different values
    with pytest.warns(gpmsa.ConvergenceWarning, match=r"R-hat inf \(t\) says the chains lie"):
        diagnostics.warn_unconverged(stuck, "gpmsa.fit")
    with pytest.warns(gpmsa.ConvergenceWarning, match=r"R-hat 1\.1004 \(t\) says the chains lie"):
        diagnostics.warn_unconverged(_record(1.1004, 50.0), "gpmsa.fit")  # not "1.100"
    with pytest.warns(gpmsa.ConvergenceWarning) as got:  # merely short: no such line
        diagnostics.warn_unconverged(_record(1.05, 50.0), "gpmsa.fit")
    assert "apart" not in str(got[0].message)


# --- seeds: a Generator, and the seed a run used is recorded ------------------------------------
@pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")
def test_calibrate_takes_a_generator_and_records_the_seed_it_ran_with():
    emu = study_emulator()
    kw = {"x_obs": [[0.5]], "y_obs": [[1.0]], "n_samples": 40, "n_burn": 10, "n_chains": 2,
          "tune": False, "n_jobs": 1}  # fmt: skip
    drawn = int(np.random.default_rng(9).integers(2**63))  # what fit draws from a Generator
    a = gpmsa.calibrate(emu, seed=np.random.default_rng(9), **kw)  # a GPMSAError before
    b = gpmsa.calibrate(emu, seed=drawn, **kw)
    assert a.info["seed"] == b.info["seed"] == drawn
    np.testing.assert_array_equal(a.chains["t"], b.chains["t"])
    fresh = gpmsa.calibrate(emu, **kw)  # seed None: fresh entropy, and still repeatable
    again = gpmsa.calibrate(emu, seed=fresh.info["seed"], **kw)
    np.testing.assert_array_equal(fresh.chains["t"], again.chains["t"])
    short = {**kw, "n_samples": 12, "n_burn": 2}
    assert gpmsa.calibrate(emu, seed=5, fast=False, **short).info["seed"] == 5  # backend path
    with pytest.raises(gpmsa.GPMSAError, match="seed must be None, an integer or a numpy Gen"):
        gpmsa.calibrate(emu, seed=np.random.RandomState(0), **kw)


@pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")
def test_a_study_takes_a_generator_seed_as_fit_does():
    emus = [study_emulator(), study_emulator()]
    kw = {"labels": ["a", "b"], "shared": ["t"], "n_samples": 30, "n_burn": 5, "tune": False}
    xs, ys = [[[0.5]], [[0.7]]], [[[1.0]], [[1.4]]]
    a = gpmsa.calibrate_study(emus, xs, ys, seed=np.random.default_rng(4), **kw)  # refused
    b = gpmsa.calibrate_study(emus, xs, ys, seed=a.settings["seed"], **kw)
    assert a.settings["seed"] == int(np.random.default_rng(4).integers(2**63))
    np.testing.assert_array_equal(a.posterior.samples["t"], b.posterior.samples["t"])


def test_a_calibrator_takes_a_generator_seed_as_calibrate_does():
    from _calib_cases import road_emulator, road_obs

    emu, (x, y) = road_emulator(), road_obs()
    drawn = int(np.random.default_rng(6).integers(2**63))
    a = gpmsa.Calibrator(emu, seed=np.random.default_rng(6)).update(x, y)
    b = gpmsa.Calibrator(emu, seed=drawn).update(x, y)
    np.testing.assert_array_equal(a.samples["GD"], b.samples["GD"])
    c = gpmsa.Calibrator(emu).update(x, y, seed=np.random.default_rng(6))  # an update's seed
    np.testing.assert_array_equal(c.samples["GD"], gpmsa.Calibrator(emu).update(
        x, y, seed=drawn).samples["GD"])  # fmt: skip
