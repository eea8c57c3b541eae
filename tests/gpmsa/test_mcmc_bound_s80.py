"""The fast calibration sampler at the domain's bound (a posterior piled near theta = 0): its log
posterior there is the dense one (the Chebyshev series of one observation and the dense solves of
two), with the truncated Normal(0.5, 10) prior and no mass at or beyond the bound; a step beyond
the bound is rejected and the chain stays; the step widths stay those tuning chose (no adaptation
while sampling). All deterministic."""

import math

import numpy as np
import pytest
from _calib_cases import two_param_emulator

from gpmsa.calibration import sampler as smp
from gpmsa.calibration.observations import fixed_gp, reduce
from gpmsa.calibration.sampler import CalibrationSampler
from tests._examples import load_benchmark

LAM = 400.0
XO, YO = np.array([[0.3], [0.8]]), np.array([[0.75], [1.0]])
B_NEAR = (1e-12, 1e-9, 1e-6, 1e-4, 1e-3, 0.01, 0.05, 0.1, 0.3)


def _sampler(emu, n_obs: int) -> CalibrationSampler:
    data = reduce(emu, XO[:n_obs], YO[:n_obs], False)
    return CalibrationSampler([fixed_gp(emu, emu.params)], data, emu.priors, held_lamos=LAM)


@pytest.mark.parametrize("n_obs", [1, 2])
def test_log_posterior_near_the_bound_is_the_dense_one(n_obs: int) -> None:
    # reference: the SBC generator's own dense solves of the predictive (Higdon et al. 2008),
    # the Gaussian likelihood of the reduced data with Sigma_obs / lamOs, and the prior
    # Normal(0.5, 10) on the unit scale; equal up to one constant
    sbc = load_benchmark("sbc_calibration")
    emu = two_param_emulator()
    s = _sampler(emu, n_obs)
    pred = s.preds[0]
    assert (pred.cheb2 is not None) == (n_obs == 1)  # one observation: the 2-D series
    obs = pred.L @ pred.L.T / LAM
    diffs = []
    for a in (0.2, 0.65):
        for b in B_NEAR:
            theta = np.array([a, b])
            mean, cov = sbc.predictive(emu, pred.x, theta)
            c = cov[0] + obs
            r = pred.z - mean[0]
            ll = -0.5 * (np.linalg.slogdet(c)[1] + r @ np.linalg.solve(c, r))
            lp = -0.5 * float(np.sum(((theta - 0.5) / 10.0) ** 2))
            diffs.append(s.log_post_at(([a, b], LAM, 0)) - (ll + lp))
    np.testing.assert_allclose(diffs, diffs[0], rtol=0, atol=1e-8)
    for b in (0.0, -1e-12, -0.05, 1.0, 1.0 + 1e-12):  # the open unit domain
        assert s.log_post_at(([0.3, b], LAM, 0)) == -math.inf


def test_a_step_beyond_the_bound_is_rejected_and_the_chain_stays() -> None:
    s = _sampler(two_param_emulator(), 2)
    state = smp._State(s, [0.5, 0.01], LAM, 0)
    widths = [0.2, 0.2, 1.0]
    acc = np.zeros(3)
    # u: (step, acceptance) per element; b's step 0.2 * (0 - 0.5) = -0.1 lands at -0.09, and an
    # acceptance draw of 1e-300 would take any finite posterior ratio: refused by the bound
    state.sweep(widths, False, acc, [0.5, 0.999, 0.0, 1e-300, 0.5, 0.5, 0.5, 0.5])
    assert state.theta[1] == 0.01 and acc[1] == 0
    lp_before = state.log_post()
    # the same draw with a step that stays inside (-0.005): taken
    state.sweep(widths, False, acc, [0.5, 0.999, 0.475, 1e-300, 0.5, 0.5, 0.5, 0.5])
    assert state.theta[1] == pytest.approx(0.005, abs=1e-15) and acc[1] == 1
    assert state.log_post() != lp_before


def test_step_widths_are_those_tuning_chose_while_sampling(monkeypatch) -> None:
    s = _sampler(two_param_emulator(), 2)
    seen = []
    sweep = smp._State.sweep

    def record(self, widths, prop_mh, accepted, u):
        seen.append(list(widths))
        return sweep(self, widths, prop_mh, accepted, u)

    monkeypatch.setattr(smp._State, "sweep", record)
    n_iter, rounds, levels = 100, 2, 3
    res = s.run(n_iter, np.random.default_rng(1), tune=True, tune_rounds=rounds, tune_levels=levels)
    assert len(seen) == rounds * levels + n_iter
    assert all(w == res.widths.tolist() for w in seen[-n_iter:])
    # every theta move is within half its width, and the chain stays in the open unit square
    steps = np.abs(np.diff(res.theta, axis=0))
    assert np.all(steps <= 0.5 * res.widths[:2] + 1e-15)
    assert np.all((res.theta > 0.0) & (res.theta < 1.0))
