"""Review of the tempered continuations (session 74): a source whose chains adapted their
ladders, continued with another n_chains, names n_chains (it read "its tempering record is
damaged", advising temperatures=); a loaded record whose "temperatures" is a number (a
count, as the option takes, never what a fit records) with "adapted_temperatures" is
refused as damaged (it crashed with TypeError after the run)."""

import warnings

import pytest
from test_study_tempering_s73 import _study
from test_tempered_continuation_s74 import SMALL, _case, _fit

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.io.container import ENVELOPE, read_raw, write_raw


@pytest.fixture(scope="module")
def adapted():
    return _fit(n_iter=20, n_chains=2, seed=3, temperatures=3, adapt_ladder=True, **SMALL)


@pytest.fixture(scope="module")
def adapted_study():
    return _study(n_samples=20, n_burn=0, n_chains=2, seed=1, temperatures=3,
                  adapt_ladder=True, **SMALL)  # fmt: skip


@pytest.mark.parametrize("n_chains", [1, 3])
def test_another_n_chains_is_named(adapted, adapted_study, n_chains):
    sim, obs = _case()
    with pytest.raises(GPMSAError, match=r"init=emulator continues its 2 chain\(s\): pass n_"):
        gpmsa.fit(sim, obs, n_iter=10, n_chains=n_chains, init=adapted, seed=4)
    with pytest.raises(GPMSAError, match=r"init=study continues its 2 chain\(s\): pass n_"):
        _study(n_samples=10, n_chains=n_chains, init=adapted_study, seed=4)


def test_a_number_for_the_recorded_ladder_is_damaged(adapted, adapted_study, tmp_path):
    manifest, arrays = read_raw(adapted.save(tmp_path / "a.gpmsa"))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    manifest["settings"]["temperatures"] = 3
    emu = gpmsa.load(write_raw(tmp_path / "b.gpmsa", manifest, arrays))
    sim, obs = _case()
    damaged = r"its tempering record .*'temperatures'.* is damaged"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        with pytest.raises(GPMSAError, match=damaged):
            gpmsa.fit(sim, obs, n_iter=10, n_chains=2, init=emu, seed=4, **SMALL)
    settings = adapted_study.settings  # a plain dict
    settings["temperatures"] = 3
    try:
        with pytest.raises(GPMSAError, match=damaged):
            _study(n_samples=10, n_chains=2, init=adapted_study, seed=4, **SMALL)
    finally:
        settings["temperatures"] = [1.0, 2.0, 4.0]
