"""Files written by older versions continue as HEAD's own do (session 84's sweep of the
project's history): a study saved before it recorded its observations' digests (before
6947c74) and an emulator whose data-corrected prior an older version summed in another order
(commits up to 730acb1: lamWOs's b 0.06017731895204935, now ...927)."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw
from gpmsa.studies.study import OBS_DIGESTS, OBS_LAYOUTS
from tests.gpmsa._study_cases import emulator, observations

pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")


def _rewritten(path, edit, fmt: str = gpmsa.io.container.FORMAT) -> None:
    """Rewrite the gpmsa file ``path`` with ``edit`` applied to its manifest (as an older
    version wrote it: resealed, so that its content digest holds)."""
    manifest, arrays = read_raw(path, formats=(fmt,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    edit(manifest)
    write_raw(path, manifest, arrays, fmt=fmt)


def _study_data():
    rng = np.random.default_rng(4)
    pairs = [observations(0.4, 3, 0.05, rng) for _ in range(2)]
    return [x for x, _ in pairs], [y for _, y in pairs]


def _calibrate(init="auto", n_samples: int = 20, seed: int = 1) -> gpmsa.Study:
    xs, ys = _study_data()
    return gpmsa.calibrate_study([emulator()] * 2, xs, ys, labels=["a", "b"], shared=["t"],
                                 n_samples=n_samples, n_burn=5, seed=seed, tune_rounds=2,
                                 tune_levels=2, init=init)  # fmt: skip


def test_a_study_file_without_the_observations_record_continues(tmp_path):
    """Before 6947c74 a study recorded no digests of its observations: calibrate_study(...,
    init=study) refused such a file as 'another study: its observations differ ([None, None]
    there, ...)'. Unrecorded, they are not compared (as fit(init=emulator) takes a file
    without obs_sha256): the continuation runs as from the same study with the record."""
    path = tmp_path / "s.gpmsa"
    _calibrate().save(path)
    twin = _calibrate(init=gpmsa.load_study(path), seed=2)

    def drop(manifest):
        for key in (OBS_DIGESTS, OBS_LAYOUTS):
            del manifest["settings"][key]

    _rewritten(path, drop, STUDY_FORMAT)
    old = gpmsa.load_study(path)
    assert OBS_DIGESTS not in old.settings
    again = _calibrate(init=old, seed=2)
    for name in ("theta", "lamOs", "log_post"):
        np.testing.assert_array_equal(again.draws[name], twin.draws[name])


def test_a_study_with_other_observations_is_still_refused(tmp_path):
    """Where the source records its observations, other ones are refused as before."""
    src = _calibrate()
    xs, ys = _study_data()
    with pytest.raises(gpmsa.GPMSAError, match="observations differ"):
        gpmsa.calibrate_study([emulator()] * 2, xs, [ys[0] + 0.1, ys[1]], labels=["a", "b"],
                              shared=["t"], n_samples=20, n_burn=0, seed=2, init=src)  # fmt: skip


def _functional_data() -> gpmsa.SimData:
    rng = np.random.default_rng(0)
    x, t = rng.random((16, 1)), rng.random((16, 1))
    grid = np.linspace(0.0, 1.0, 8)
    return gpmsa.SimData(x=x, t=t, y=np.sin(3 * x + 2 * grid) * (1 + t) + grid * t)


def test_an_emulator_whose_corrected_prior_differs_in_the_last_bits_continues(tmp_path):
    """Versions up to 730acb1 summed the data correction of lamWOs's prior in another order
    (b 0.06017731895204935, now ...927 for the same runs): fit(init=emulator) of such a file
    refused it as 'another model: its priors differ' naming no field. A prior that agrees to
    1e-12 is the same model, as it already was where K's columns are reordered."""
    data = _functional_data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.GPMSAWarning)
        src = gpmsa.fit(data, n_pc=2, n_iter=40, seed=1, tune=False)
    b = src.priors.to_dict()["lamWOs"]["b"]
    path = tmp_path / "e.gpmsa"
    src.save(path)

    def nudge(manifest):
        manifest["priors"]["lamWOs"]["b"] = float(np.nextafter(b, np.inf))

    _rewritten(path, nudge)
    old = gpmsa.load(path)
    assert old.priors.to_dict()["lamWOs"]["b"] != b
    twin = gpmsa.fit(data, n_pc=2, n_iter=20, seed=2, init=src)
    again = gpmsa.fit(data, n_pc=2, n_iter=20, seed=2, init=old)
    np.testing.assert_allclose(again.draws["lamWOs"], twin.draws["lamWOs"], rtol=1e-9)


def test_an_emulator_with_other_user_priors_is_still_refused():
    """A prior the user set differently (theta_sd) is another model, as before."""
    data = _functional_data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.GPMSAWarning)
        src = gpmsa.fit(data, n_pc=2, n_iter=40, seed=1, tune=False)
    with pytest.raises(gpmsa.GPMSAError, match="priors differ"):
        gpmsa.fit(data, n_pc=2, n_iter=20, seed=2, init=src, priors=gpmsa.Priors(theta_sd=5.0))
