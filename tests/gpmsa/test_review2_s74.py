"""Review of session 74's torch adaptive ladder and Calibrator walkthrough (second review).

- A Calibrator on the MCMC path of the sampler (``fast=False``, or ``backend="torch"``, which
  the walkthrough let take a constraint) whose constraint rejects every random start failed
  with the sampler's advice "pass init='gpmsa' with theta_init=", arguments a Calibrator does
  not take: only the fast sampler's "pass theta_init=" was translated. Both now name the
  Calibrator's ``mcmc_options``.
- The torch backend's adapted ladder is strictly increasing in float64 (``kept_ladder``), but
  its rows run at 1/T in the batch's dtype: in float32 two rungs 3e-8 apart share one beta
  (after 1,000 rounds with swap rates stuck at 0 and 1, the case of
  test_adapt_ladder_hostile_s73), a merged rung the fallback exists to avoid, while the record
  says otherwise. A ladder merged in the batch's dtype now gives way to the starting one.
"""

import warnings

import numpy as np
import pytest
from _calib_cases import one_t_emulator
from tqdm.auto import tqdm

import gpmsa


@pytest.fixture(scope="module")
def small():
    """A 1-parameter emulator (t in [0, 1]) at fixed parameters, one observation near t = 0.8
    (as test_walkthrough_s74)."""
    return one_t_emulator()


@pytest.mark.parametrize("backend", ["numpy", "torch"])
def test_no_random_start_names_the_calibrators_options(small, backend):
    if backend == "torch":
        pytest.importorskip("torch")
    emu, xo, yo = small
    opts = {"n_samples": 20, "n_burn": 2, "n_chains": 2, "fast": False, "tune": False}
    cal = gpmsa.Calibrator(emu, method="mcmc", backend=backend, mcmc_options=opts,
                           constraint=lambda th: th[0] > 0.99)  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError) as err:
        cal.update(xo, yo)
    assert "no 'jitter' start of theta" in str(err.value)
    assert "mcmc_options={'init': 'gpmsa', 'theta_init': [...]}" in str(err.value)
    assert type(err.value) is gpmsa.StartRejectedError and err.value.__cause__ is not None
    cal = gpmsa.Calibrator(
        emu,
        method="mcmc",
        backend=backend,
        seed=0,
        constraint=lambda th: th[0] > 0.99,
        mcmc_options={**opts, "init": "gpmsa", "theta_init": [0.995]},
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short unconverged chains
        assert cal.update(xo, yo).samples["t"].min() > 0.99


def test_other_errors_pass_unchanged(small):
    emu, xo, yo = small
    cal = gpmsa.Calibrator(emu, method="mcmc", constraint=lambda th: th[0] > 0.99,
                           mcmc_options={"n_samples": 20, "n_burn": 2, "fast": False,
                                         "init": "gpmsa", "theta_init": [0.5]})  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError) as err:  # the start given is rejected: calibrate's
        cal.update(xo, yo)
    assert "a Calibrator takes" not in str(err.value)


class _Stuck:
    """A tempered batch (rows c K + k) whose log-likelihood is set by each row's beta alone:
    0 at 1 and 1/4, -1e30 elsewhere (swap rates 0 and 1; test_adapt_ladder_hostile_s73)."""

    def __init__(self, n_rows, dtype):
        import torch

        self.n_chains, self.els, self.beta = n_rows, [("theta", (0,))], None
        self.ll_w = torch.zeros((n_rows, 1), dtype=dtype)  # (the batch's dtype and device)
        self.loglik = torch.zeros(n_rows, dtype=dtype)

    def sweep(self, widths, prop_mh, gen):
        b = self.beta.double()
        self.loglik = self.loglik.new_zeros(b.shape).where((b == 1.0) | (b == 0.25), -1e30)

    def exchange(self, a, b):
        self.loglik[a], self.loglik[b] = self.loglik[b], self.loglik[a]


def test_float32_rows_keep_distinct_temperatures():
    torch = pytest.importorskip("torch")
    tb = gpmsa.backends.get("torch")
    start = (1.0, 2.0, 4.0)
    state = _Stuck(2 * 3, torch.float32)
    gen = torch.Generator().manual_seed(0)
    ad = tb._adapt_ladders(state, np.array([0.1]), start, gen, tqdm(disable=True), 50, 20)
    betas = state.beta.view(-1, 3)
    assert torch.all(betas[:, :-1] > betas[:, 1:]), (ad, betas)  # no rung merged in float32
    assert torch.equal(betas, torch.as_tensor(1.0 / ad, dtype=torch.float32))  # as recorded
    assert np.all(np.diff(ad, axis=1) > 0) and np.all(ad[:, [0, 2]] == [1.0, 4.0])
