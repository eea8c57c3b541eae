"""``gpmsa.calibrate_study(discrepancy=, discrepancy_groups=)``: several fitted emulators
calibrated together online with a model discrepancy (as ``gpmsa.calibrate`` takes one).

Before: calibrate_study took no discrepancy (a TypeError), so observations with a systematic
offset pulled the shared theta away from the truth (0.51 for a truth of 0.40 below)."""

import contextlib
import io
import shutil
import warnings
from functools import cache
from pathlib import Path

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main
from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw
from gpmsa.mcmc.diagnostics import ess
from tests.gpmsa._study_cases import EXACT, emulator, simulator

# The offsets these cases observe lie far outside a near-exact emulator, on purpose: the
# discrepancy explains them. calibrate_study says so (test_study_outside_s62.py tests that).
pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.errors.OutsideEmulatorWarning")

TRUTH = 0.4
OFFSETS = (0.3, 0.2)
"""Each model's constant offset of its observations from the simulator at TRUTH."""
OLD = Path(__file__).parent.parent / "data" / "study_before_s62"
"""A study file (and its two members) written by calibrate_study before it took a discrepancy."""


def _data(n: int = 10, sd: float = 0.02, seed: int = 0):
    """Each model's x (n, 1) on [0, 1] and y = simulator(x, TRUTH) + its offset + noise."""
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 1.0, n)[:, None]
    ys = [simulator(x, TRUTH) + off + sd * rng.standard_normal((n, 1)) for off in OFFSETS]
    return x, ys


@cache
def _offset_study(discrepancy) -> gpmsa.Study:
    """Two models sharing t, each observed with its own constant offset; the emulator's nugget
    negligible, so that the discrepancy is the only model error."""
    emu = emulator(None, lam_w=EXACT)
    x, ys = _data()
    return gpmsa.calibrate_study([emu, emu], [x, x], ys, shared=["t"], labels=["a", "b-1"],
                                 discrepancy=discrepancy, n_samples=3000, n_burn=500,
                                 seed=100)  # fmt: skip


@cache
def _small_study() -> gpmsa.Study:
    """A short study with a discrepancy in model a only (for the file tests)."""
    emu = emulator(None)
    x, ys = _data(n=5, sd=0.05, seed=1)
    return gpmsa.calibrate_study([emu, emu], [x, x], ys, shared=["t"], labels=["a", "b"],
                                 discrepancy=["constant", None], n_samples=200, n_burn=50,
                                 seed=2, tune_rounds=5)  # fmt: skip


def test_a_discrepancy_recovers_the_shared_theta_that_offsets_bias():
    """Measured (data seed 0 .. 7, sampler seed data + 100): with a constant discrepancy per
    model the mean of t was 0.396 .. 0.415 and every 90% interval covered 0.4; without, 0.506
    .. 0.515 and none did."""
    with_d, without = _offset_study("constant"), _offset_study(None)
    lo, hi = with_d.posterior.interval("t", 0.9)
    assert lo < TRUTH < hi
    err = abs(with_d.posterior.mean("t") - TRUTH)
    assert err < 0.03  # measured 0.0075 here
    lo0, hi0 = without.posterior.interval("t", 0.9)
    assert not lo0 < TRUTH < hi0
    assert abs(without.posterior.mean("t") - TRUTH) > 0.08  # measured 0.106
    assert err < abs(without.posterior.mean("t") - TRUTH) / 3
    names = with_d.posterior.names
    assert names == ("t", "lamOs[a]", "betaV[a]", "lamVz[a]", "lamOs[b-1]", "betaV[b-1]",
                     "lamVz[b-1]")  # fmt: skip
    assert set(without.posterior.names) == {"t", "lamOs[a]", "lamOs[b-1]"}
    record = with_d.settings["discrepancy_by_model"]
    assert record["a"]["discrepancy"] == "constant" and "discrepancy_sha256" in record["b-1"]
    mp = with_d.member_posterior("b-1")
    assert mp.names == ("t", "lamOs", "betaV", "lamVz")
    assert np.array_equal(mp.samples["lamVz"], with_d.posterior.samples["lamVz[b-1]"])
    assert mp.info["discrepancy_sha256"] == record["b-1"]["discrepancy_sha256"]


def _se_sd(a: np.ndarray, n_eff: float) -> float:
    """Monte-Carlo standard error of the sample sd of ``a`` with ``n_eff`` effective draws:
    sd sqrt((kurtosis - 1) / (4 n_eff)) (delta method; sd / sqrt(2 n_eff) for a normal). The
    posterior of t with a discrepancy has heavy tails (kurtosis 6 .. 20 measured)."""
    d = a - a.mean()
    kurt = np.mean(d**4) / np.mean(d**2) ** 2
    return a.std() * np.sqrt((kurt - 1.0) / (4.0 * n_eff))


def test_a_one_model_study_equals_calibrate_with_the_same_discrepancy():
    """Measured over 12 seed pairs: the means within 3.0 and the sds within 3.3 of these
    standard errors, either sign."""
    emu = emulator(None, lam_w=EXACT)
    x, (y, _) = _data()
    study = gpmsa.calibrate_study([emu], [x], [y], discrepancy="constant", n_samples=5000,
                                  n_burn=500, seed=0)  # fmt: skip
    with pytest.warns(gpmsa.OutsideEmulatorWarning):  # the offset: the discrepancy explains it
        one = gpmsa.calibrate(emu, x, y, discrepancy="constant", n_samples=5000, n_burn=500,
                              seed=50)  # fmt: skip
    mp = study.member_posterior("model0")
    assert mp.names == one.names
    a, b = mp.chains["t"].ravel(), one.chains["t"].ravel()
    ea, eb = ess(mp.chains["t"]), ess(one.chains["t"])
    assert ea > 300 and eb > 300
    assert abs(a.mean() - b.mean()) < 4 * np.sqrt(a.var() / ea + b.var() / eb)
    assert abs(a.std() - b.std()) < 4 * np.hypot(_se_sd(a, ea), _se_sd(b, eb))
    # the discrepancy prediction from the study's draws is calibrate's (within MC error)
    obs = gpmsa.ObsData(x=x, y=y)
    preds = [gpmsa.full_prediction(emu, obs, [[0.5]], posterior=p, discrepancy="constant",
                                   n_draws=400, seed=0) for p in (mp, one)]  # fmt: skip
    means = [p.mu[:, 0, 0] * p.y_sd for p in preds]  # each draw's mean of delta(0.5)
    se = np.sqrt(sum(m.var() / min(ess(m[None, :]), m.size) for m in means))
    assert abs(preds[0].mean("delta")[0, 0] - preds[1].mean("delta")[0, 0]) < 4 * se
    delta = preds[0].mean("delta")[0, 0]
    assert abs(delta - OFFSETS[0]) < 0.05  # measured 0.293 .. 0.306 (6 seed pairs)
    with pytest.raises(gpmsa.GPMSAError, match="the draws have discrepancy parameters"):
        gpmsa.full_prediction(emu, obs, [[0.5]], posterior=mp, discrepancy=None)


def test_the_discrepancy_draws_round_trip_through_the_study_file(tmp_path):
    study = _small_study()
    assert set(study.draws) == {"theta", "mu", "lam", "lamOs", "log_post", "betaV_0", "lamVz_0"}
    assert study.draws["betaV_0"].shape == (1, 150, 1, 1)
    path = study.save(tmp_path / "run.gpmsa")
    back = gpmsa.load_study(path)
    assert set(back.draws) == set(study.draws)
    for k, v in study.draws.items():
        assert np.array_equal(back.draws[k], v), k
    assert back.posterior.names == study.posterior.names
    assert back.settings["discrepancy_by_model"] == study.settings["discrepancy_by_model"]
    assert back.discrepancy("a") == {"discrepancy": "constant", "discrepancy_groups": None}
    assert back.discrepancy("b") is None
    mp, mp0 = back.member_posterior("a"), study.member_posterior("a")
    assert mp.names == ("t", "lamOs", "betaV", "lamVz") and mp.info == mp0.info
    assert back.member_posterior("b").names == ("t", "lamOs")
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        main(["info", str(path)])
    text = out.getvalue()
    assert text.count("discrepancy constant, precision groups one") == 1
    assert "posterior lamVz[a]: mean" in text and "lamVz[b]" not in text


def _edit_array(name, value):
    def edit(manifest, arrays):
        arrays[name] = value(arrays[name])

    return edit


def _edit_record(key, value):
    def edit(manifest, arrays):
        manifest["settings"]["discrepancy_by_model"]["a"][key] = value

    return edit


def _drop(name):
    def edit(manifest, arrays):
        del arrays[name]

    return edit


def _fit_kind(manifest, arrays):
    manifest["study"]["kind"] = "fit"


def _unknown_label(manifest, arrays):
    record = manifest["settings"]["discrepancy_by_model"]
    record["c"] = record.pop("a")


@pytest.mark.parametrize(
    "edit, field",
    [
        (_edit_array("lamVz_0", lambda a: -a), r"arrays/lamVz_0: precisions must be > 0"),
        (_edit_array("betaV_0", lambda a: 0 * a), r"arrays/betaV_0: correlation parameters"),
        (_edit_array("betaV_0", lambda a: a + np.nan), r"arrays/betaV_0: holds NaN"),
        (_edit_array("betaV_0", lambda a: np.concatenate([a, a], axis=2)),
         r"arrays/betaV_0: has 2 rows of betaV for model a's 1 known input"),
        (_edit_array("lamVz_0", lambda a: a[:, :-1]), r"arrays/lamVz_0: must be \(chains, "),
        (_edit_array("lamVz_0", lambda a: np.concatenate([a, a], axis=2)),
         r"arrays/lamVz_0: must be \(chains, draws, G\) .* G = 1"),
        (_drop("lamVz_0"), r"arrays: this study holds exactly"),
        (_edit_record("discrepancy_sha256", "x" * 64),
         r"settings.discrepancy_by_model.a.discrepancy_sha256: must be 64"),
        (_edit_record("discrepancy", "quadratic"),
         r"settings.discrepancy_by_model.a.discrepancy: must be one of"),
        (_edit_record("discrepancy_groups", [0, 2]),
         r"settings.discrepancy_by_model.a.discrepancy_groups: must number"),
        (_unknown_label, r"settings.discrepancy_by_model: names the model 'c'"),
        (_fit_kind, r"settings.discrepancy_by_model: belongs to a calibration"),
    ],
)  # fmt: skip
def test_a_damaged_discrepancy_field_is_refused_naming_it(tmp_path, edit, field):
    path = _small_study().save(tmp_path / "run.gpmsa")
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    edit(manifest, arrays)
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)  # a consistent rewrite: hash recomputed
    with pytest.raises(gpmsa.EmulatorFileError, match=field):
        gpmsa.load_study(path)


def test_a_study_file_written_before_the_discrepancy_loads(tmp_path):
    for f in OLD.iterdir():
        shutil.copy(f, tmp_path / f.name)
    old = gpmsa.load_study(tmp_path / "old.gpmsa")
    assert old.posterior.names == ("t", "lamOs[a]", "lamOs[b]")
    assert "discrepancy_by_model" not in old.settings and old.discrepancy("a") is None
    assert old.member_posterior("b").names == ("t", "lamOs")
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        main(["info", str(tmp_path / "old.gpmsa")])
    assert "discrepancy" not in out.getvalue()


def test_per_model_discrepancies_and_their_groups_are_checked():
    emu = emulator(None)
    x, ys = _data(n=4, seed=3)
    kw = dict(shared=["t"], n_samples=20, n_burn=5, seed=0, tune=False)
    with pytest.raises(gpmsa.GPMSAError, match=r"discrepancy has 3 entries for 2 models"):
        gpmsa.calibrate_study([emu, emu], [x, x], ys, discrepancy=["constant"] * 3, **kw)
    with pytest.raises(gpmsa.GPMSAError, match=r"discrepancy_groups has 3 entries for 2 models"):
        gpmsa.calibrate_study([emu, emu], [x, x], ys, discrepancy="constant",
                              discrepancy_groups=[None, None, [0]], **kw)  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError, match=r"discrepancy must be None, 'constant'"):
        gpmsa.calibrate_study([emu, emu], [x, x], ys, discrepancy=3, **kw)
    with pytest.raises(gpmsa.GPMSAError, match=r"model 'model1': discrepancy_groups needs a "):
        gpmsa.calibrate_study([emu, emu], [x, x], ys, discrepancy=["constant", None],
                              discrepancy_groups=[0], **kw)  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError, match=r"model 'model0': a scalar output supports"):
        gpmsa.calibrate_study([emu, emu], [x, x], ys, discrepancy=["cubic", None], **kw)
    # one group list for every model, or one per model
    a = gpmsa.calibrate_study([emu, emu], [x, x], ys, discrepancy="constant",
                              discrepancy_groups=[0], **kw)  # fmt: skip
    b = gpmsa.calibrate_study([emu, emu], [x, x], ys, discrepancy=("constant", "constant"),
                              discrepancy_groups=[None, [0]], **kw)  # fmt: skip
    assert a.posterior.names == b.posterior.names


@cache
def _vector_case():
    from _predict_cases import known_truth_case  # the module (and cache) the others import

    return known_truth_case()


def test_a_member_posterior_refuses_another_basis():
    emu, obs, *_ = _vector_case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a few observations near the design's edge
        study = gpmsa.calibrate_study([emu, emu], [obs, obs], shared=["t"], discrepancy="linear",
                                      n_samples=40, n_burn=10, seed=0, tune=False)  # fmt: skip
    post = study.member_posterior(1)
    with pytest.raises(gpmsa.GPMSAError, match="discrepancy basis differs from the one the draws"):
        gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, discrepancy="constant",
                              n_draws=2)  # fmt: skip
    pred = gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, discrepancy="linear",
                                 n_draws=2, seed=0)  # fmt: skip
    assert pred.p_v == 2 and np.all(np.isfinite(pred.delta))
    assert post.names == ("t", "lamOs", "betaV", "lamVz")
    assert {"betaV[model0]", "lamVz[model1]"} <= set(study.posterior.names)


def test_precision_groups_per_model_are_named_recorded_and_saved(tmp_path):
    emu, obs, *_ = _vector_case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a few observations near the design's edge
        study = gpmsa.calibrate_study([emu, emu], [obs, obs], shared=["t"], discrepancy="linear",
                                      discrepancy_groups=[[0, 1], None], n_samples=30,
                                      n_burn=10, seed=1, tune=False)  # fmt: skip
    names = set(study.posterior.names)
    assert {"betaV[0,0][model0]", "betaV[0,1][model0]", "lamVz[0][model0]", "lamVz[1][model0]",
            "betaV[model1]", "lamVz[model1]"} <= names  # fmt: skip
    assert study.draws["betaV_0"].shape == (1, 20, 1, 2) and study.draws["lamVz_1"].shape[2] == 1
    back = gpmsa.load_study(study.save(tmp_path / "g.gpmsa"))
    post = back.member_posterior("model0")
    assert post.info["discrepancy_groups"] == [0, 1] and "lamVz[1]" in post.names
    assert "discrepancy_groups" not in back.member_posterior("model1").info
    pred = gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, discrepancy="linear",
                                 n_draws=2, seed=0)  # fmt: skip
    assert np.all(np.isfinite(pred.delta))
    with pytest.raises(gpmsa.GPMSAError, match="discrepancy precision group"):
        gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, discrepancy="linear",
                              discrepancy_groups=None, n_draws=2)  # fmt: skip
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        main(["info", str(tmp_path / "g.gpmsa")])
    text = out.getvalue()
    assert "discrepancy linear, precision groups [0, 1]" in text
    assert "discrepancy linear, precision groups one" in text
