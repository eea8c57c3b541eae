"""Studies against posteriors computed independently (session 66): simulators linear in theta,
emulators at fixed parameters with a negligible nugget (in effect the simulator), observation
errors of known precision (lamOs held at 1), so that each model's likelihood of theta is a
normal one written down here, not read from gpmsa."""

import warnings

import numpy as np
import pytest
from scipy.special import ndtr

import gpmsa
from gpmsa.mcmc.diagnostics import ess

LO, HI = 2.0, 4.0
"""The native range of the calibration parameter E in every model."""
GRID = np.linspace(0.0, 1.0, 6)
"""The output grid of the functional model."""
PARAMS = {"lamUz": [1.0], "lamWs": [1e6], "lamWOs": [1e6]}


def _emulator(sim: gpmsa.SimData, n_inputs: int, n_pc=None) -> gpmsa.Emulator:
    """The emulator at fixed parameters (a nugget of 1e-6: its error ~1e-3 of the outputs)."""
    return gpmsa.Emulator.from_params(sim, {"betaU": [[0.5]] * n_inputs, **PARAMS}, n_pc=n_pc)


def _scalar(a: float, b: float) -> gpmsa.Emulator:
    """y = a + b E, no known input."""
    t = np.linspace(LO, HI, 25)[:, None]
    return _emulator(gpmsa.SimData(t=t, y=a + b * t, t_names=["E"]), 1)


def _within(draws: np.ndarray, mean: float, sd: float, k: float = 4.0) -> None:
    """The draws' mean and sd within k Monte-Carlo standard errors (from their ESS)."""
    n = ess(draws)
    assert n > 300, n
    assert abs(draws.mean() - mean) < k * sd / np.sqrt(n), (draws.mean(), mean, sd, n)
    assert abs(draws.std() - sd) < k * sd / np.sqrt(2 * n), (draws.std(), sd, n)


def test_shared_theta_is_the_product_of_the_models_normal_likelihoods():
    """Three models (no input and a scalar output; one input; a 6-point functional output)
    share E: its posterior is the product of their normal likelihoods in E (mean 2.98, sd
    0.030), the prior Normal(0.5, 10) on the unit scale, truncated to (2, 4)."""
    xg, tg = np.meshgrid(np.linspace(0, 1, 5), np.linspace(LO, HI, 9), indexing="ij")
    x, t = xg.reshape(-1, 1), tg.reshape(-1, 1)
    with_x = _emulator(gpmsa.SimData(x=x, t=t, y=0.5 - t + 0.7 * x, t_names=["E"]), 2)
    t = np.linspace(LO, HI, 25)[:, None]
    func = _emulator(gpmsa.SimData(t=t, y=0.2 + 0.8 * t * (1 + GRID), index=GRID,
                                   t_names=["E"]), 1, n_pc=1)  # fmt: skip
    rng, sig, truth = np.random.default_rng(100), (0.3, 0.2, 0.15), 3.0
    y_a = 1.0 + 2.0 * truth + sig[0] * rng.standard_normal((4, 1))
    x_b = np.linspace(0.1, 0.9, 5)[:, None]
    y_b = 0.5 - truth + 0.7 * x_b + sig[1] * rng.standard_normal((5, 1))
    y_c = 0.2 + 0.8 * truth * (1 + GRID)[None] + sig[2] * rng.standard_normal((2, 6))
    obs = [gpmsa.ObsData(y=y_a, precision=sig[0] ** -2),
           gpmsa.ObsData(x=x_b, y=y_b, precision=sig[1] ** -2),
           gpmsa.ObsData(y=y_c, precision=sig[2] ** -2)]  # fmt: skip
    with warnings.catch_warnings():  # the near-exact emulator's tiny sds read as "outside"
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        study = gpmsa.calibrate_study([_scalar(1.0, 2.0), with_x, func], obs, shared=["E"],
                                      fixed={"lamOs": 1.0}, n_samples=3000, n_burn=300,
                                      seed=0, tune_rounds=20)  # fmt: skip
    e = np.linspace(LO, HI, 20001)
    lp = -0.5 * ((y_a - (1 + 2 * e)) ** 2).sum(0) / sig[0] ** 2
    lp -= 0.5 * ((y_b - (0.5 - e + 0.7 * x_b)) ** 2).sum(0) / sig[1] ** 2
    lp -= (
        0.5
        * ((y_c[None] - 0.2 - 0.8 * e[:, None, None] * (1 + GRID)) ** 2).sum((1, 2))
        / sig[2] ** 2
    )
    lp -= 0.5 * (((e - LO) / (HI - LO) - 0.5) / 10) ** 2
    w = np.exp(lp - lp.max())
    w /= w.sum()
    mean = (w * e).sum()
    _within(study.posterior.chains["E"], mean, np.sqrt((w * (e - mean) ** 2).sum()))


def _hierarchical_exact(m: np.ndarray, s: np.ndarray) -> dict:
    """Posterior means and sds (unit scale) of a group's mu and sd and of each theta_k, for
    theta_k's normal likelihoods N(m_k, s_k^2), theta_k ~ Normal(mu, sd^2) truncated to (0, 1),
    mu ~ Normal(0.5, 10) on (0, 1), sd ~ Uniform(0, 1): theta_k integrated in closed form on a
    grid of (mu, log sd)."""
    mu = np.linspace(0.0005, 0.9995, 600)[:, None]
    sd = np.exp(np.linspace(np.log(1e-3), 0.0, 800))[None, :]
    lp = -0.5 * ((mu - 0.5) / 10) ** 2 + np.log(sd)  # d sd = sd d(log sd)
    log_z = np.log(ndtr((1 - mu) / sd) - ndtr(-mu / sd))
    parts = []
    for mk, sk in zip(m, s, strict=True):
        v = 1 / (1 / sk**2 + 1 / sd**2)
        c = v * (mk / sk**2 + mu / sd**2)
        a, b = -c / np.sqrt(v), (1 - c) / np.sqrt(v)
        mass = ndtr(b) - ndtr(a)
        tot = sk**2 + sd**2
        lp = lp - 0.5 * (mk - mu) ** 2 / tot - 0.5 * np.log(tot) + np.log(mass) - log_z
        pa, pb = np.exp(-0.5 * a**2), np.exp(-0.5 * b**2)
        shift = (pa - pb) / np.sqrt(2 * np.pi) / mass  # the truncated normal's moments
        first = c + np.sqrt(v) * shift
        var = v * (1 + (a * pa - b * pb) / np.sqrt(2 * np.pi) / mass - shift**2)
        parts.append((first, var + first**2))
    w = np.exp(lp - lp.max())
    w /= w.sum()

    def moments(first, second):
        m1 = (w * first).sum()
        return m1, np.sqrt((w * second).sum() - m1**2)

    out = {"mu": moments(mu, mu**2), "sd": moments(sd, sd**2)}
    out.update({k: moments(*p) for k, p in enumerate(parts)})
    return out


def test_hierarchical_theta_matches_the_closed_form_grid():
    """Four models, each its own E_k ~ Normal(mu, sd^2) truncated to the range (the default
    uniform sd prior): E_k, mu and the group sd against a grid over (mu, sd) with E_k
    integrated in closed form."""
    a, b, sig, n = (1.0, -0.5, 2.0, 0.3), (2.0, 1.5, -1.0, 3.0), (0.3, 0.2, 0.15, 0.4), (3, 4, 2, 3)
    truth = (2.6, 3.0, 3.3, 2.9)
    rng = np.random.default_rng(200)
    emus, obs, m, s = [], [], [], []
    for k in range(4):
        emus.append(_scalar(a[k], b[k]))
        y = a[k] + b[k] * truth[k] + sig[k] * rng.standard_normal((n[k], 1))
        obs.append(gpmsa.ObsData(y=y, precision=sig[k] ** -2))
        m.append(((y.mean() - a[k]) / b[k] - LO) / (HI - LO))
        s.append(sig[k] / abs(b[k]) / np.sqrt(n[k]) / (HI - LO))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        study = gpmsa.calibrate_study(emus, obs, hierarchical=["E"], fixed={"lamOs": 1.0},
                                      labels=list("abcd"), n_samples=4000, n_burn=400, seed=0,
                                      tune_rounds=20)  # fmt: skip
    exact = _hierarchical_exact(np.array(m), np.array(s))
    chains, r = study.posterior.chains, HI - LO
    _within(chains["E.mu"], LO + r * exact["mu"][0], r * exact["mu"][1])
    _within(chains["E.sd"], r * exact["sd"][0], r * exact["sd"][1])
    for k, lab in enumerate("abcd"):
        _within(chains[f"E[{lab}]"], LO + r * exact[k][0], r * exact[k][1])


@pytest.mark.parametrize("y", [np.empty((0, 1)), np.empty((0, 3))])
def test_obs_data_without_experiments_is_refused(y):
    """A model without observations: ObsData(y=(0, l)) raised numpy's "need at least one array
    to stack"."""
    with pytest.raises(gpmsa.GPMSAError, match="y_obs has no experiments"):
        gpmsa.ObsData(y=y)


def test_an_emulator_a_study_cannot_calibrate_is_named_by_its_model():
    """An emulator a study cannot calibrate is refused naming the model; the message said
    "calibration: ..." only. (The case here was a categorical calibration parameter, which
    the studies calibrate since session 72: tests/gpmsa/test_study_categorical_s72.py.)"""
    obs = [gpmsa.ObsData(y=[[7.0]]), gpmsa.ObsData(y=[[3.0]])]
    for kw in ({"hierarchical": ["E"]}, {}):
        with pytest.raises(gpmsa.GPMSAError, match=r"model 'b': emulator lacks \["):
            gpmsa.calibrate_study([_scalar(1.0, 2.0), object()], obs, labels=["a", "b"], **kw)
