"""gpmsa's grid calibration and bases under a caller's ``np.seterr(all="raise")`` (session 86):
a Calibrator update whose posterior is narrow (the lamOs quadrature's and the refinement's far
tails underflow to 0), two-parameter draws, a theta prior whose lower tail underflows, a linear
discrepancy on a huge index and a pulse's range far below its neighbours' give what numpy's default
state gives, and leave the caller's state as it was."""

import numpy as np
from _calib_cases import road_emulator, two_param_emulator

import gpmsa
from gpmsa import Calibrator
from gpmsa.calibration.calibrator import log_theta_norm
from gpmsa.model.basis import discrepancy_basis
from gpmsa.model.far_values import far_run

RAISE = {"divide": "raise", "over": "raise", "under": "raise", "invalid": "raise"}


def _same_under_raise(run) -> None:
    default = run()
    with np.errstate(all="raise"):
        raised = run()
        assert np.geterr() == RAISE
    assert len(raised) == len(default)
    for a, b in zip(raised, default, strict=True):
        np.testing.assert_array_equal(a, b)


def _summary(post) -> list:
    out = []
    for g in post.grids.values():
        out += [g.nodes, g.density, g.mean(), g.sd()]
    return out


def test_a_narrow_posterior_is_refined_alike_under_raise():
    v = np.linspace(0.6, 1.9, 40)[:, None]
    rng = np.random.default_rng(0)
    f = 0.02 * 410 * v**1.6 * (1 + 0.005 * rng.standard_normal(v.shape))

    def run():
        post = Calibrator(road_emulator()).update(v, f)
        return [*_summary(post), post.info["expected_inv_lamOs"], post.info["log_evidence"]]

    _same_under_raise(run)


def test_two_parameter_draws_are_alike_under_raise():
    x, y = [[0.3]], [[np.sin(0.6 + 0.6) + 0.8 * 0.6 * 0.3]]

    def run():
        post = Calibrator(two_param_emulator(), n_draws=2000, seed=3).update(x, y)
        return [*_summary(post), *(post.samples[k] for k in ("a", "b", "lamOs"))]

    _same_under_raise(run)


def test_a_theta_prior_with_an_underflowing_lower_tail_has_its_norm_under_raise():
    _same_under_raise(lambda: [log_theta_norm(0.5, 0.01), log_theta_norm(3.0, 0.1)])


def test_a_linear_discrepancy_on_a_huge_or_tiny_index_is_alike_under_raise():
    for index in (np.linspace(1e200, 1.5e200, 5), np.array([0.0, 1e-300, 1.0, 1e300])):
        _same_under_raise(lambda index=index: [discrepancy_basis("linear", index)])


def test_a_narrow_pulse_is_judged_alike_under_raise():
    s = np.linspace(0.0, 1.0, 50)
    rng = np.random.default_rng(4)
    x, t = rng.uniform(size=(40, 1)), rng.uniform(size=(40, 1))
    with np.errstate(under="ignore"):  # (the test's own pulse underflows)
        pulse = np.exp(-(((s - (0.2 + 0.6 * x)) / 0.02) ** 2)) * (1.0 + t)
    data = gpmsa.SimData(x=x, t=t, y=pulse, index=s)
    _same_under_raise(lambda: [far_run(data, s) is None])
