"""Session 74's walkthrough of the new features by a new user (SEPIA / GPM/SA background): two
defects of a ``Calibrator`` with a theta constraint on its MCMC path.

- ``Calibrator(emu, backend="torch", constraint=...)`` was refused ("constraint needs
  backend='numpy'") although ``gpmsa.calibrate(..., backend="torch", constraint=...)``, which
  the MCMC path runs, takes it (its sampler rejects such proposals chain by chain). Only pyro,
  whose ``calibrate`` refuses a constraint, is refused now.
- A constraint that rejects the MCMC path's start (the design's centre) failed at the first
  ``update`` with ``calibrate``'s advice "pass theta_init=", an argument the Calibrator does not
  take: the error now names ``mcmc_options={"theta_init": ...}``.
"""

import pytest
from _calib_cases import one_t_emulator

import gpmsa


@pytest.fixture(scope="module")
def small():
    """A 1-parameter emulator (t in [0, 1], centre 0.5) at fixed parameters, and one
    observation near t = 0.8."""
    return one_t_emulator()


def test_a_torch_calibrator_takes_a_constraint(small):
    pytest.importorskip("torch")
    emu, xo, yo = small
    cal = gpmsa.Calibrator(emu, backend="torch", constraint=lambda th: th[0] > 0.6, seed=0,
                           mcmc_options={"n_samples": 60, "n_burn": 10, "tune": False,
                                         "theta_init": [0.8]})  # fmt: skip
    post = cal.update(xo, yo)
    assert post.info["backend"] == "torch"
    assert post.samples["t"].min() > 0.6


def test_a_pyro_calibrator_takes_a_constraint(small):
    """(Refused until session 75.)"""
    pytest.importorskip("pyro")
    emu, xo, yo = small
    cal = gpmsa.Calibrator(emu, backend="pyro", constraint=lambda th: th[0] > 0.6, seed=0,
                           mcmc_options={"n_samples": 30, "n_burn": 0, "n_warmup": 15,
                                         "max_tree_depth": 3, "theta_init": [0.8]})  # fmt: skip
    post = cal.update(xo, yo)
    assert post.info["backend"] == "pyro"
    assert post.samples["t"].min() > 0.6


def test_a_rejected_start_names_the_calibrators_option(small):
    emu, xo, yo = small
    cal = gpmsa.Calibrator(emu, method="mcmc", constraint=lambda th: th[0] > 0.6,
                           mcmc_options={"n_samples": 60, "n_burn": 10})  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError, match=r"rejects the initial value t=0\.51.*"
                                               r"mcmc_options=\{'theta_init'"):  # fmt: skip
        cal.update(xo, yo)
    opts = {"n_samples": 60, "n_burn": 10, "theta_init": [0.8]}
    cal = gpmsa.Calibrator(emu, method="mcmc", constraint=lambda th: th[0] > 0.6, seed=0,
                           mcmc_options=opts)  # fmt: skip
    assert cal.update(xo, yo).samples["t"].min() > 0.6
