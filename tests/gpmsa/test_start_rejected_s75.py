"""A rejected start is a `StartRejectedError` whose ``remedy`` names the arguments that give an
allowed one (session 75).

The Calibrator translated calibrate's advice ("pass theta_init=") into its own
``mcmc_options`` by matching the message's text, and a deterministic start (``init="gpmsa"``)
that the constraint rejects was found only inside the chain, so a numpy run raised a
`ChainError` that no advice reached ("chain 0 failed: ..."). Now the start is checked with the
others before any chain runs, and the Calibrator reads the error's ``remedy``.
"""

import warnings

import pytest
from _calib_cases import one_t_emulator

import gpmsa

OPTS = {"n_samples": 20, "n_burn": 2, "n_chains": 2, "fast": False, "tune": False}


@pytest.fixture(scope="module")
def small():
    return one_t_emulator()


def test_calibrate_gives_the_remedy(small):
    emu, xo, yo = small
    with pytest.raises(gpmsa.StartRejectedError) as err:
        gpmsa.calibrate(emu, xo, yo, constraint=lambda th: th[0] > 0.99, **OPTS)
    assert err.value.remedy == {"init": "gpmsa", "theta_init": ...}
    assert isinstance(err.value, gpmsa.GPMSAError)


@pytest.mark.parametrize("n_jobs", [1, 2])
def test_a_deterministic_start_is_checked_before_the_chains(small, n_jobs):
    emu, xo, yo = small
    with pytest.raises(gpmsa.StartRejectedError, match=r"init='gpmsa'.*rejects the initial "
                                                       r"value t=0\.51") as err:  # fmt: skip
        gpmsa.calibrate(emu, xo, yo, constraint=lambda th: th[0] > 0.99, init="gpmsa",
                        n_jobs=n_jobs, **OPTS)  # fmt: skip
    assert err.value.remedy == {"theta_init": ...}


def test_the_calibrator_names_its_options_for_a_deterministic_start(small):
    emu, xo, yo = small
    cal = gpmsa.Calibrator(emu, method="mcmc", constraint=lambda th: th[0] > 0.99,
                           mcmc_options={**OPTS, "init": "gpmsa"})  # fmt: skip
    with pytest.raises(gpmsa.StartRejectedError, match=r"mcmc_options=\{'theta_init': \[\.+\]\}"):
        cal.update(xo, yo)  # was a ChainError carrying calibrate's advice
    opts = {**OPTS, "init": "gpmsa", "theta_init": [0.995]}
    cal = gpmsa.Calibrator(emu, method="mcmc", constraint=lambda th: th[0] > 0.99, seed=0,
                           mcmc_options=opts)  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short unconverged chains
        assert cal.update(xo, yo).samples["t"].min() > 0.99


def test_a_message_that_merely_mentions_the_option_is_not_translated(small):
    emu, xo, yo = small

    def failing(theta):
        raise RuntimeError("pass theta_init= somewhere")  # the user's own text

    cal = gpmsa.Calibrator(emu, method="mcmc", constraint=failing, mcmc_options=OPTS)
    with pytest.raises(gpmsa.GPMSAError, match="constraint failed") as err:
        cal.update(xo, yo)
    assert "a Calibrator takes" not in str(err.value)
