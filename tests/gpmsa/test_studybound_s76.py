"""A study's posterior piled against a bound of the emulator's domain (``gpmsa.mcmc.bounds``,
the rule of ``gpmsa.calibrate``), and ``gpmsa calibrate``'s report of it.

Before: ``calibrate_study`` and ``fit_study`` said nothing (a shared t of 0.9972 +- 0.0034 on
[0, 1], its truth 1.03, read as a confident estimate) and ``study.posterior.info`` had no
"at_bound"; ``gpmsa calibrate`` printed c with median 0.9975 on [0.1, 1] (truth 1.045) and no
word of the bound, in its text and --json alike."""

from __future__ import annotations

import json
import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa.calibration.posterior import GridMarginal
from gpmsa.mcmc.bounds import at_bound
from tests.gpmsa._study_cases import emulator, observations, sim_data

RUN = {"n_samples": 600, "n_burn": 200, "seed": 5, "tune_rounds": 5}


def _calibrate(truths, emus=None, **kw) -> tuple[gpmsa.Study, list]:
    """A calibration study of ``truths`` (one model each, four observations of sd 0.02) and
    its AtBoundWarnings."""
    rng = np.random.default_rng(4)
    data = [observations(th, 4, 0.02, rng) for th in truths]
    emus = emus or [emulator(None)] * len(truths)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        study = gpmsa.calibrate_study(emus, [d[0] for d in data], [d[1] for d in data],
                                      labels=list("abc")[: len(truths)],
                                      **{**RUN, **kw})  # fmt: skip
    return study, [w for w in caught if issubclass(w.category, gpmsa.AtBoundWarning)]


@pytest.mark.parametrize(("truth", "side", "bound"), [(1.03, "upper", "1"), (-0.06, "lower", "0")])
def test_calibrate_study_flags_a_shared_parameter_piled_at_a_bound(truth, side, bound):
    study, caught = _calibrate((truth, truth), shared=["t"])
    assert study.posterior.info["at_bound"] == {"t": side}
    assert len(caught) == 1
    text = str(caught[0].message)
    assert text.startswith("gpmsa.calibrate_study: the posterior piles up")
    assert f"t at its {side} bound {bound} (domain [0, 1]" in text
    assert "study.posterior.info['at_bound'] records it" in text
    assert caught[0].filename == __file__  # the user's call
    assert study.member_posterior("a").info["at_bound"] == {"t": side}


@pytest.mark.parametrize("kind", ["shared", "hierarchical"])
def test_a_truth_inside_the_design_is_not_flagged(kind):
    study, caught = _calibrate((0.4, 0.6), **{kind: ["t"]})
    assert study.posterior.info["at_bound"] == {} and not caught
    assert study.member_posterior("b").info["at_bound"] == {}


def test_hierarchical_elements_and_the_group_mean_are_judged_on_the_group_range(tmp_path):
    """Three models just beyond t = 1: each element, and the mean (its prior stops at the same
    range), flagged under the posterior's names, in one warning; the sd and lam are not."""
    study, caught = _calibrate((1.03, 1.05, 1.02), hierarchical=["t"])
    flagged = {"t[a]": "upper", "t[b]": "upper", "t[c]": "upper", "t.mu": "upper"}
    assert study.posterior.info["at_bound"] == flagged
    assert len(caught) == 1
    text = str(caught[0].message)
    assert all(f"{name} at its upper bound 1 (domain [0, 1]" in text for name in flagged)
    assert study.member_posterior("c").info["at_bound"] == {"t": "upper"}
    # a study read back is judged anew (the same), silently
    path = study.save(tmp_path / "s.gpmsa")
    with warnings.catch_warnings(record=True) as loaded:
        warnings.simplefilter("always")
        back = gpmsa.load_study(path)
    assert back.posterior.info["at_bound"] == flagged
    assert not [w for w in loaded if issubclass(w.category, gpmsa.AtBoundWarning)]


def test_each_model_own_parameter_is_judged_on_its_own_domain():
    """t = 1.03 in both models, each its own t: flagged in a (t in [0, 1]), not in b (t in
    [0, 2], which holds the truth)."""
    study, caught = _calibrate((1.03, 1.03), emus=[emulator(None), emulator(None, 0.0, 2.0)])
    assert study.posterior.info["at_bound"] == {"t[a]": "upper"}
    assert len(caught) == 1 and "t[a] at its upper bound 1" in str(caught[0].message)
    assert "t[b]" not in str(caught[0].message)


def test_a_held_element_is_not_judged():
    study, caught = _calibrate((1.03, 1.03), shared=["t"], fixed={"theta": {"t": 0.999}})
    assert np.all(study.posterior.samples["t"] == 0.999)  # inside the upper band
    assert study.posterior.info["at_bound"] == {} and not caught


def test_a_categorical_element_is_not_judged():
    """A shared categorical kind mostly at its top level (2) is no bound."""
    rng = np.random.default_rng(2)
    x = rng.random((45, 1))
    t = np.column_stack([rng.uniform(0, 1, 45), np.arange(45) % 3])
    t[:2, 0] = 0.0, 1.0
    sim = gpmsa.SimData(x, t, np.sin(3 * x[:, 0]) + t[:, 0] + 0.5 * t[:, 1],
                        t_names=["k", "kind"], t_categorical=["kind"])  # fmt: skip
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[1.0], [1.0], [1.0]], "lamUz": [1.0],
                                           "lamWs": [5000.0], "lamWOs": [5000.0]})  # fmt: skip
    xo = [np.linspace(0.1, 0.9, 5)[:, None]] * 2
    yo = [np.sin(3 * v) + 0.5 + 0.5 * 2 + 0.01 * rng.standard_normal((5, 1)) for v in xo]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        study = gpmsa.calibrate_study([emu, emu], xo, yo, shared=["kind"], n_samples=300,
                                      n_burn=100, seed=1, tune_rounds=3)  # fmt: skip
    kind = study.posterior.samples["kind"]
    assert np.mean(kind == 2.0) > 0.5  # judged as a continuous one, it would be flagged
    assert at_bound({"kind": kind}, ["kind"], [0.0], [2.0]) == {"kind": "upper"}
    assert study.posterior.info["at_bound"] == {}
    assert not [w for w in caught if issubclass(w.category, gpmsa.AtBoundWarning)]


@pytest.mark.parametrize(("truth", "flagged"), [(1.04, {"t": "upper"}), (0.5, {})])
def test_fit_study_flags_it_too(truth, flagged):
    rng = np.random.default_rng(4)
    obs = [gpmsa.ObsData(*observations(truth, 4, 0.02, rng)) for _ in range(2)]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        study = gpmsa.fit_study([sim_data()] * 2, obs, labels=["a", "b"], shared=["t"],
                                n_iter=300, seed=3, tune_rounds=5, tune_levels=5)  # fmt: skip
    bound = [w for w in caught if issubclass(w.category, gpmsa.AtBoundWarning)]
    assert study.posterior.info["at_bound"] == flagged
    assert len(bound) == len(flagged)
    if flagged:
        assert str(bound[0].message).startswith("gpmsa.fit_study: the posterior piles up")


# gpmsa calibrate: a 12-value functional output (lamOs estimated), c in [0.1, 1]
S = np.linspace(0.0, 1.0, 12)


def _f(x: float, c: float) -> np.ndarray:
    return (1.0 + c) * np.sin(np.pi * S * (0.5 + x)) + 0.3 * c


@cache
def _functional() -> gpmsa.Emulator:
    xg, cg = np.meshgrid(np.linspace(0, 1, 6), np.linspace(0.1, 1.0, 8), indexing="ij")
    x, c = xg.reshape(-1), cg.reshape(-1)
    y = np.array([_f(a, b) for a, b in zip(x, c, strict=True)])
    sim = gpmsa.SimData(x=x[:, None], t=c[:, None], y=y, index=S, x_names=["x"], t_names=["c"])
    n_pc = 3  # the PCA's: 99.5 % of the variance
    params = {"betaU": np.ones((2, n_pc)), "lamUz": np.ones(n_pc), "lamWs": np.full(n_pc, 1e4),
              "lamWOs": [1e4]}  # fmt: skip
    return gpmsa.Emulator.from_params(sim, params)


def _observed(c_unit: float) -> np.ndarray:
    """One observation (12,) at x = 0.4 of c at ``c_unit`` of the domain's width."""
    noise = 0.01 * np.random.default_rng(0).standard_normal(12)
    return _f(0.4, 0.1 + 0.9 * c_unit) + noise


@pytest.mark.parametrize(("c_unit", "flagged"), [(1.05, {"c": "upper"}), (-0.03, {"c": "lower"}),
                                                 (0.5, {}), (0.97, {})])  # fmt: skip
def test_grid_marginal_and_draws_give_the_same_verdict(c_unit, flagged):
    """The CLI's grid path judges the exact marginal (its CDF, no draws): the same verdict as
    the grid's draws and as the MCMC path's."""
    emu = _functional()
    lo, hi = emu.standardizer.t_min, emu.standardizer.t_max
    for method in ("grid", "mcmc"):
        with warnings.catch_warnings():  # outside: an OutsideEmulatorWarning too
            warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
            post = gpmsa.Calibrator(emu, method=method, seed=1).update([[0.4]], _observed(c_unit))
        assert at_bound({"c": post.samples["c"]}, ["c"], lo, hi) == flagged
        if method == "grid":
            assert at_bound(post.grids, ["c"], lo, hi) == flagged


def test_at_bound_reads_a_marginal_mass_as_the_share_of_draws():
    """A density rising linearly on [0, 1] (median 0.7071) in a domain [lo, 1]: the band
    0.01 (1 - lo) holds half its mass from lo = -28.29 on (1 - 0.7071 = 0.2929)."""
    ramp = GridMarginal.from_log_density(np.linspace(0.0, 1.0, 101),
                                         np.log(np.linspace(1e-300, 1.0, 101)))  # fmt: skip
    draws = ramp.ppf((np.arange(2000) + 0.5) / 2000)  # its mass as draws
    for lo, flagged in ((-28.2, {}), (-28.4, {"c": "upper"}), (0.0, {})):
        assert at_bound({"c": ramp}, ["c"], [lo], [1.0]) == flagged
        assert at_bound({"c": draws}, ["c"], [lo], [1.0]) == flagged


@pytest.fixture(scope="module")
def functional_file(tmp_path_factory):
    return str(_functional().save(tmp_path_factory.mktemp("emu") / "f.gpmsa"))


@pytest.mark.parametrize("method", ["grid", "mcmc"])
def test_cli_names_a_parameter_piled_against_a_bound(functional_file, tmp_path, capsys, method):
    from gpmsa.cli.main import main

    out = {}
    for c_unit in (1.05, 0.5):
        path = tmp_path / f"y{c_unit}.csv"
        np.savetxt(path, _observed(c_unit))
        args = ["calibrate", functional_file, "--x", "x=0.4", "--y-csv", str(path), "--seed",
                "1", "--method", method]  # fmt: skip
        assert main(args) == 0
        text = capsys.readouterr().out
        assert main([*args, "--json"]) == 0
        out[c_unit] = text, json.loads(capsys.readouterr().out)
    text, record = out[1.05]
    what = "posterior" if method == "grid" else "draws"
    assert ("c: piled against the emulator's domain at its upper bound 1 (domain [0.1, 1]; "
            in text and f"% of the {what} within 1% of its width of it" in text)  # fmt: skip
    assert "outside the simulation design" in text
    assert record["at_bound"] == {"c": "upper"}
    text, record = out[0.5]
    assert "piled" not in text and record["at_bound"] == {}
