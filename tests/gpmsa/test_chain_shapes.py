"""Chains and a Posterior's chains must agree in shape (ArviZ pads disagreeing arrays with NaN
and summaries turn NaN), and an observation beyond float64's range is refused without a numpy
warning."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import GPMSAError


def test_a_posteriors_chains_must_share_one_shape():
    s = {"a": np.arange(10.0), "b": np.arange(10.0)}
    chains = {"a": s["a"].reshape(2, 5), "b": s["b"].reshape(5, 2)}
    with pytest.raises(GPMSAError, match=r"one shape \(n_chains, n_draws\), got a: \(2, 5\)"):
        gpmsa.Posterior(s, chains=chains)
    ok = gpmsa.Posterior(s, chains={k: v.reshape(2, 5) for k, v in s.items()})
    assert ok.chains["b"].shape == (2, 5)


@pytest.mark.parametrize(
    ("draws", "log_post", "match"),
    [
        ({"theta": np.zeros((2, 10, 1)), "lamOs": np.zeros((3, 4, 1))}, np.zeros((2, 10)),
         r"draws\['lamOs'\] has shape \(3, 4, 1\); its first two axes must be"),
        ({"theta": np.zeros((2, 10, 1))}, np.zeros((2, 7)), r"draws\['theta'\] has shape"),
        ({"theta": np.zeros((2, 10, 1))}, np.zeros(20), r"log_post must be \(n_chains, n_draws\)"),
        ({}, np.zeros((2, 10)), "draws is empty"),
    ],
)  # fmt: skip
def test_chains_refuse_arrays_of_other_shapes(draws, log_post, match):
    with pytest.raises(GPMSAError, match=match):
        gpmsa.Chains(draws=draws, log_post=log_post, accept_rate={}, step_widths={})


def test_chains_refuse_a_rate_for_other_chains():
    with pytest.raises(GPMSAError, match=r"accept_rate\['theta'\] has shape \(3, 1\)"):
        gpmsa.Chains(draws={"theta": np.zeros((2, 10, 1))}, log_post=np.zeros((2, 10)),
                     accept_rate={"theta": np.zeros((3, 1))}, step_widths={})  # fmt: skip


def test_an_observation_beyond_float64_is_refused_without_a_warning():
    rng = np.random.default_rng(0)
    x, t = rng.random((12, 1)), rng.random((12, 1))
    sim = gpmsa.SimData(x=x, t=t, y=1e-3 * (x + t))  # an output sd below 1: y / sd overflows
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [5000.0], "lamWOs": [5000.0]}
    cal = gpmsa.Calibrator(gpmsa.Emulator.from_params(sim, params))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's overflow warning leaked before the refusal
        with pytest.raises(GPMSAError, match=r"more than 1.8e308 \(overflow\) standard dev"):
            cal.update([[0.5]], [[1.7e308]])
