"""The adaptive ladder of parallel tempering (session 73: ``adapt_ladder=True``, numpy ``fit``,
``calibrate(fast=False)``, ``calibrate_study``, ``fit_study``; ``tempering.adapt_ladder``).

During an extra tuning phase each chain moves its interior temperatures (T_0 = 1 and the
hottest fixed) towards equal neighbour swap rates, then freezes the ladder before the widths'
tuning and the draws. Checked: on copies that sample x ~ N(0, T I) exactly (the optimal ladder
is geometric), a bad ladder is carried near the geometric one; the ladder does not move during
the draws; the records, seeding and refusals of the entry points.
"""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.mcmc import tempering
from tests.gpmsa.test_study_tempering_s73 import _models, _study
from tests.gpmsa.test_tempering_s72 import _case

LADDER = [1.0, 4.0, 16.0, 64.0]


class _Gauss:
    """A copy whose sweep draws x ~ N(0, I / beta) exactly; log L = -|x|^2 / 2."""

    def __init__(self, rng, d):
        self.rng, self.d, self.beta = rng, d, 1.0
        self.x = rng.standard_normal(d)

    @property
    def loglik(self):
        return -0.5 * float(self.x @ self.x)

    def sweep(self, widths, prop_mh, accepted):
        self.x = self.rng.standard_normal(self.d) / np.sqrt(self.beta)

    def exchange(self, other):
        self.x, other.x = other.x, self.x

    def learn_level_shifts(self):
        pass

    def use_level_shifts(self, cold):
        pass


def _copies(start, seed=0, d=10):
    rng = np.random.default_rng(seed)
    states = [_Gauss(rng, d) for _ in start]
    for s, t in zip(states, start, strict=True):
        s.beta = 1.0 / t
    return states, rng


def test_bad_ladder_adapted_towards_equal_swap_rates():
    """(1, 1.5, 2, 64): swap rates ~0.6, 0.7, 0.0; scale-free energies: geometric is optimal."""
    start = (1.0, 1.5, 2.0, 64.0)
    states, rng = _copies(start)
    out = tempering.adapt_ladder(states, start, rng, ["theta"], np.array([0.1]), 50, 20,
                                 lambda n: None)  # fmt: skip
    assert out[0] == 1.0 and out[-1] == 64.0 and np.all(np.diff(out) > 0)
    np.testing.assert_allclose(np.log(out[1:3]), np.log([4.0, 16.0]), atol=0.25)  # 3.9, 15.8
    assert [s.beta for s in states] == [1.0 / t for t in out]
    good = (1.0, 4.0, 16.0, 64.0)  # already equal rates: it stays near
    states, rng = _copies(good, seed=1)
    again = tempering.adapt_ladder(states, good, rng, ["theta"], np.array([0.1]), 50, 20,
                                   lambda n: None)  # fmt: skip
    np.testing.assert_allclose(np.log(again), np.log(good), atol=0.25)


def test_ladder_frozen_during_tuning_and_draws():
    start = (1.0, 1.5, 2.0, 64.0)
    states, rng = _copies(start, seed=2)
    seen = []

    class Bar:
        def set_description(self, text):
            seen.append(text)

        def update(self, n):
            pass

    betas = []
    acc, w, rates, ladder = tempering.run_ladder(
        states, rng, 200, np.array([0.1]), ["theta"], lambda it: betas.append(
            [s.beta for s in states]), swap_every=1, tune=True, tune_rounds=5, tune_levels=4,
        prop_mh=False, bar=Bar(), desc="t", adapt=start,
    )  # fmt: skip
    assert "adapting the ladder" in seen[0] and "tuning step widths" in seen[1]
    assert ladder != start and ladder[0] == 1.0 and ladder[-1] == 64.0
    assert np.all(np.array(betas) == [1.0 / t for t in ladder])  # every draw's ladder
    _, _, _, fixed = tempering.run_ladder(
        *_copies(start, seed=2), 10, np.array([0.1]), ["theta"], lambda it: None, swap_every=1,
        tune=True, tune_rounds=2, tune_levels=2, prop_mh=False, bar=Bar(), desc="t",
    )  # fmt: skip
    assert fixed is None


def test_fit_records_and_prints_the_adapted_ladder(tmp_path, capsys):
    from gpmsa.cli.main import main

    sim, obs = _case()
    kw = {"n_iter": 40, "n_chains": 2, "seed": 5, "temperatures": LADDER, "tune_rounds": 3,
          "tune_levels": 5, "adapt_ladder": True}  # fmt: skip
    warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)  # (pytest restores the filters)
    a = gpmsa.fit(sim, obs, n_jobs=1, **kw)
    s = a.settings
    assert s["temperatures"] == LADDER and s["backend_options"]["adapt_ladder"] is True
    ad = np.array(s["adapted_temperatures"])
    assert ad.shape == (2, 4) and np.all(ad[:, 0] == 1.0) and np.all(ad[:, -1] == 64.0)
    assert np.all(np.diff(ad, axis=1) > 0) and not np.all(ad == LADDER)
    path = a.save(tmp_path / "a.gpmsa")
    assert gpmsa.load(path).settings["adapted_temperatures"] == s["adapted_temperatures"]
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "4 temperatures [1, 4, 16, 64] adapted to [1, " in out and "(per chain)" in out
    fixed = gpmsa.fit(sim, obs, n_jobs=1, **{**kw, "adapt_ladder": False})
    assert "adapted_temperatures" not in fixed.settings


def test_calibrate_and_studies_record_the_adapted_ladder():

    emus, obs = _models()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.calibrate(emus[0], obs[0], fast=False, n_samples=30, n_burn=0, seed=1,
                               fixed={"lamOs": 1.0}, tune_rounds=2, tune_levels=4,
                               temperatures=3, adapt_ladder=True)  # fmt: skip
    assert np.array(post.info["adapted_temperatures"]).shape == (1, 3)
    study = _study(n_samples=30, n_burn=0, n_chains=2, seed=4, tune_rounds=2, tune_levels=4,
                   temperatures=3, adapt_ladder=True)  # fmt: skip
    ad = np.array(study.settings["adapted_temperatures"])
    assert ad.shape == (2, 3) and np.all(ad[:, [0, 2]] == [1.0, 4.0]) and study.settings[
        "adapt_ladder"] is True  # fmt: skip
    t = np.linspace(0.1, 0.9, 12)[:, None]
    sim = gpmsa.SimData(t=t, y=2 * t, t_names=["E"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        obs = [gpmsa.ObsData(y=[[0.9]]), gpmsa.ObsData(y=[[1.1]])]
        fitted = gpmsa.fit_study([sim, sim], obs, shared=["E"], n_iter=30,
                                 seed=2, tune_rounds=2, tune_levels=3, temperatures=3,
                                 adapt_ladder=True)  # fmt: skip
    for member in fitted.members:
        assert member.settings["adapted_temperatures"] == fitted.settings["adapted_temperatures"]


@pytest.mark.parametrize(
    ("kw", "words"),
    [({}, "adapt_ladder=True needs temperatures="),
     ({"temperatures": 2}, "at least 3 temperatures"),
     ({"temperatures": 3, "tune": False}, "adapt_ladder=True with tune=False"),
     ({"temperatures": 3, "adapt_ladder": "yes"}, "adapt_ladder must be True or False"),
     ({"backend": "pyro"}, "adapt_ladder: the adaptive ladder runs on the numpy and torch")],
)  # fmt: skip
def test_refused_by_name(kw, words):
    sim, obs = _case()
    with pytest.raises(GPMSAError, match=words):
        gpmsa.fit(sim, obs, n_iter=10, **{"adapt_ladder": True, **kw})
    if "backend" not in kw:
        with pytest.raises(GPMSAError, match=words.replace("n_iter", "n_samples")):
            _study(n_samples=10, n_burn=0, seed=1, **{"adapt_ladder": True, **kw})
