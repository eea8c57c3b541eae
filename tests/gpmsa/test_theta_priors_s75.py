"""One theta prior per calibration parameter (SEPIA's ``model.params.theta.prior.params``, a
mean and an sd array): ``Priors(theta_mean=[...], theta_sd=[...])``, used by every sampler, the
grid, the starts, held and categorical elements, studies, the file and ``gpmsa info``."""

import functools
import importlib.util
import json
import warnings
import zipfile

import numpy as np
import pytest

import gpmsa
from gpmsa import Priors
from gpmsa.cli.main import main as cli_main
from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.io.container import ENVELOPE, read_raw, write_raw
from gpmsa.mcmc.starts import _truncnorm01
from gpmsa.model.problem import theta_log_prior

TIGHT = ([0.3, 0.5], [0.05, 10.0])  # a tight prior on a, a vague one on b
needs_torch = pytest.mark.skipif(
    importlib.util.find_spec("torch") is None, reason="torch not installed (the torch extra)"
)


def _data(n=24, seed=3, t_categorical=None, t=None):
    rng = np.random.default_rng(seed)
    x = rng.random((n, 1))
    x[:2, 0] = 0.05, 0.95  # the observations' x inside the design
    t = rng.random((n, 2)) if t is None else t
    y = np.sin(3 * x) + t[:, :1] + 0.5 * t[:, 1:]
    data = gpmsa.SimData(x=x, t=t, y=y, x_names=["x"], t_names=["a", "b"],
                         t_categorical=t_categorical)  # fmt: skip
    xo = np.linspace(0.1, 0.9, 4)[:, None]
    yo = np.sin(3 * xo) + 0.9 + 0.02 * rng.standard_normal(xo.shape)
    return data, xo, yo


@functools.cache
def _emulator():
    data, xo, yo = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(data, n_iter=300, seed=0), xo, yo


def _unit_log_prior(emu, means, sds):
    """``calibrate(log_prior=)`` / ``update(prior=)`` giving truncated normals per element."""
    lo, hi = emu.standardizer.t_min, emu.standardizer.t_max
    means, sds = np.asarray(means), np.asarray(sds)

    def lp(native):
        u = (np.reshape(native, (-1, lo.size)) - lo) / (hi - lo)
        return -0.5 * np.sum(((u - means) / sds) ** 2, axis=1)

    return lp


def _same(a, b):
    for k in a.samples:
        np.testing.assert_array_equal(a.samples[k], b.samples[k], err_msg=k)


# --- Priors ---------------------------------------------------------------------------------
def test_priors_take_one_value_per_element_or_one_shared():
    p = Priors(theta_mean=np.array([0.3, 0.5]), theta_sd=[0.05, 10])
    assert p.theta_mean == (0.3, 0.5) and p.theta_sd == (0.05, 10.0) and p.theta_count == 2
    assert p.theta_prior(1) == (0.5, 10.0)
    mixed = Priors(theta_mean=[0.2, 0.4, 0.6], theta_sd=0.1)
    np.testing.assert_array_equal(mixed.theta_moments(3)[1], [0.1, 0.1, 0.1])
    assert Priors().theta_moments(7) == (0.5, 10.0) and Priors().theta_count is None
    x = np.array([0.25, 0.9])
    want = -0.5 * (((0.25 - 0.3) / 0.05) ** 2 + ((0.9 - 0.5) / 10.0) ** 2)
    assert p.log_prior("theta", x) == pytest.approx(want, rel=1e-15)
    assert p.scalar_log_prior("theta", 0)(0.25) + p.scalar_log_prior("theta", 1)(0.9) == (
        pytest.approx(want, rel=1e-15)
    )
    assert p.log_prior("theta", [0.5, 1.0]) == -np.inf
    assert Priors.from_dict(json.loads(json.dumps(p.to_dict()))) == p
    assert p.to_dict()["theta_mean"] == [0.3, 0.5]


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"theta_mean": []}, r"theta_mean must be a number or a non-empty sequence"),
        ({"theta_mean": [0.5, np.nan]}, r"theta_mean\[1\] must be finite"),
        ({"theta_sd": [1.0, 0.0]}, r"theta_sd\[1\] must be finite and > 0"),
        ({"theta_sd": [1.0, "2"]}, r"theta_sd\[1\] must be a real number"),
        ({"theta_mean": [0.5, 0.5], "theta_sd": [1.0, 1.0, 1.0]}, r"gives 2 .* but .*theta_sd 3"),
        ({"theta_sd": [1.0, 1e-200]}, r"theta_sd\[1\] = 1e-200 is too small"),
        ({"theta_mean": [0.5, 1e200], "theta_sd": 1e-150}, r"theta_mean\[1\] = 1e\+200"),
    ],
)
def test_bad_per_element_values_are_refused_by_name(kw, match):
    with pytest.raises(GPMSAError, match=match):
        Priors(**kw)


def test_a_wrong_count_is_refused_where_the_model_is_built():
    data, xo, yo = _data(n=12)
    three = Priors(theta_mean=[0.5, 0.5, 0.5])
    with pytest.raises(GPMSAError, match=r"Priors.theta_mean gives 3 .* q = 2 calibration"):
        gpmsa.fit(data, gpmsa.ObsData(x=xo, y=yo), n_iter=10, priors=three)
    with pytest.raises(GPMSAError, match=r"Priors.theta_sd gives 1 .* q = 2 calibration"):
        gpmsa.fit(data, n_iter=10, priors=Priors(theta_sd=[1.0]))
    emu, _, _ = _emulator()
    with pytest.raises(GPMSAError, match=r"theta_mean gives 3 .* q = 2"):
        emu.with_calibration_priors(theta_mean=[0.1, 0.2, 0.3])


# --- equal values: the scalar prior, bit for bit --------------------------------------------
@pytest.mark.parametrize(
    "kw",
    [
        {},
        {"fast": False, "n_samples": 100},
        {"fixed": {"theta": {"b": 0.7}}},
        pytest.param(
            {"backend": "torch", "n_chains": 2, "n_samples": 60, "n_burn": 20, "tune": False},
            marks=needs_torch,
        ),
        "grid",
    ],  # fmt: skip
    ids=["fast", "numpy", "held", "torch", "grid"],
)
def test_equal_per_element_values_are_the_shared_prior_bit_for_bit_calibrating(kw):
    emu, xo, yo = _emulator()
    one = emu.with_calibration_priors(theta_mean=0.4, theta_sd=0.3)
    each = emu.with_calibration_priors(theta_mean=[0.4, 0.4], theta_sd=[0.3, 0.3])
    assert each.model_sha256 != one.model_sha256  # another record, the same model
    if kw == "grid":
        a = gpmsa.Calibrator(one, n_grid=33, seed=5).update(xo, yo)
        b = gpmsa.Calibrator(each, n_grid=33, seed=5).update(xo, yo)
    else:
        opts = {"n_samples": 300, "n_burn": 50, "seed": 2} | kw
        a, b = gpmsa.calibrate(one, xo, yo, **opts), gpmsa.calibrate(each, xo, yo, **opts)
    _same(a, b)


@pytest.mark.parametrize(
    "kw",
    [
        {"init": "prior", "n_chains": 2},
        pytest.param({"backend": "torch", "n_chains": 2}, marks=needs_torch),
    ],
    ids=["numpy", "torch"],
)
def test_equal_per_element_values_are_the_shared_prior_bit_for_bit_fitting(kw):
    data, xo, yo = _data(n=14)
    obs = gpmsa.ObsData(x=xo, y=yo)
    one, each = Priors(theta_mean=0.4, theta_sd=0.3), Priors(theta_mean=[0.4] * 2, theta_sd=0.3)
    a = gpmsa.fit(data, obs, n_iter=40, seed=1, priors=one, tune=False, **kw)
    b = gpmsa.fit(data, obs, n_iter=40, seed=1, priors=each, tune=False, **kw)
    np.testing.assert_array_equal(a.log_post, b.log_post)
    np.testing.assert_array_equal(a.calibration["theta"], b.calibration["theta"])


# --- per-element priors: every path the same posterior --------------------------------------
def test_a_tight_and_a_vague_prior_agree_with_log_prior_and_the_grid():
    emu, xo, yo = _emulator()
    per = emu.with_calibration_priors(theta_mean=TIGHT[0], theta_sd=TIGHT[1])
    vague = emu.with_calibration_priors(theta_sd=1e6)  # the emulator's prior ~ flat
    lp = _unit_log_prior(emu, *TIGHT)
    opts = {"n_samples": 4000, "n_burn": 500, "seed": 1}
    mcmc = gpmsa.calibrate(per, xo, yo, **opts)
    given = gpmsa.calibrate(vague, xo, yo, log_prior=lp, **opts)
    grid = gpmsa.Calibrator(per, seed=1).update(xo, yo)
    grid_given = gpmsa.Calibrator(vague, seed=1).update(xo, yo, prior=lp)
    free = gpmsa.Calibrator(vague, seed=1).update(xo, yo)
    lo, hi = emu.standardizer.t_min[0], emu.standardizer.t_max[0]
    for k in ("a", "b"):
        assert grid.mean(k) == pytest.approx(grid_given.mean(k), rel=1e-9)
        assert grid.sd(k) == pytest.approx(grid_given.sd(k), rel=1e-9)
        assert mcmc.mean(k) == pytest.approx(given.mean(k), abs=0.05 * grid.sd(k))
        assert mcmc.mean(k) == pytest.approx(grid.mean(k), abs=0.25 * grid.sd(k))  # MC error
        assert mcmc.sd(k) == pytest.approx(grid.sd(k), rel=0.25)
    # the tight prior on a pulls it towards 0.3 (unit scale) and narrows it
    centre = lo + 0.3 * (hi - lo)
    assert abs(grid.mean("a") - centre) < abs(free.mean("a") - centre)
    assert grid.sd("a") < 0.8 * free.sd("a")


def test_the_numpy_sampler_follows_the_per_element_prior():
    emu, xo, yo = _emulator()
    per = emu.with_calibration_priors(theta_mean=TIGHT[0], theta_sd=TIGHT[1])
    grid = gpmsa.Calibrator(per, seed=1).update(xo, yo)
    post = gpmsa.calibrate(per, xo, yo, n_samples=4000, n_burn=500, seed=1, fast=False)
    for k in ("a", "b"):
        assert post.mean(k) == pytest.approx(grid.mean(k), abs=0.25 * grid.sd(k))
        assert post.sd(k) == pytest.approx(grid.sd(k), rel=0.25)


@needs_torch
def test_the_torch_prior_is_the_numpy_prior_per_element():
    import torch

    from gpmsa.backends.torch_backend import log_prior_elements

    p = Priors(theta_mean=[0.3, 0.5, 0.8], theta_sd=[0.05, 10.0, 0.2])
    th = np.array([[0.25, 0.9, 0.7], [0.31, 0.1, 0.99]])
    t = torch.as_tensor(th)
    whole = log_prior_elements(p, "theta", t).sum(-1).numpy()
    np.testing.assert_allclose(whole, [p.log_prior("theta", r) for r in th], rtol=1e-14)
    some = log_prior_elements(p, "theta", t[:, [0, 2]], [0, 2]).sum(-1).numpy()
    np.testing.assert_allclose(some, [p.log_theta(r[[0, 2]], [0, 2]) for r in th], rtol=1e-14)
    one = log_prior_elements(p, "theta", t[:, 2], np.int64(2)).numpy()
    np.testing.assert_allclose(one, [p.scalar_log_prior("theta", 2)(r[2]) for r in th])


@needs_torch
def test_torch_calibration_follows_the_per_element_prior():
    emu, xo, yo = _emulator()
    per = emu.with_calibration_priors(theta_mean=TIGHT[0], theta_sd=TIGHT[1])
    grid = gpmsa.Calibrator(per, seed=1).update(xo, yo)
    post = gpmsa.calibrate(per, xo, yo, n_samples=500, n_burn=100, seed=3, backend="torch",
                           n_chains=4, tune=False)  # fmt: skip
    assert post.mean("a") == pytest.approx(grid.mean("a"), abs=0.5 * grid.sd("a"))
    assert post.sd("a") == pytest.approx(grid.sd("a"), rel=0.5)


def test_prior_starts_draw_each_element_from_its_own_prior():
    rng = np.random.default_rng(0)
    mean, sd = np.tile([0.2, 0.8], 20_000), np.tile([0.02, 0.05], 20_000)
    draws = _truncnorm01(mean, sd, mean.size, rng).reshape(-1, 2)
    np.testing.assert_allclose(draws.mean(0), [0.2, 0.8], atol=2e-3)
    np.testing.assert_allclose(draws.std(0), [0.02, 0.05], rtol=0.03)
    wide = np.full(2000, 2.0)  # most draws fall outside (0, 1): redrawn, element by element
    a = _truncnorm01(0.9, 2.0, 2000, np.random.default_rng(1))
    b = _truncnorm01(np.full(2000, 0.9), wide, 2000, np.random.default_rng(1))
    np.testing.assert_array_equal(a, b)
    assert 0.0 < a.min() and a.max() < 1.0


# --- held and categorical elements ----------------------------------------------------------
def test_a_held_elements_prior_is_a_constant():
    emu, xo, yo = _emulator()
    opts = {"n_samples": 1500, "n_burn": 300, "seed": 4, "fixed": {"theta": {"b": 0.9}}}
    near = emu.with_calibration_priors(theta_mean=[0.3, 0.9], theta_sd=[0.05, 0.05])
    far = emu.with_calibration_priors(theta_mean=[0.3, 0.1], theta_sd=[0.05, 0.05])
    a, b = gpmsa.calibrate(near, xo, yo, **opts), gpmsa.calibrate(far, xo, yo, **opts)
    assert np.all(a.samples["b"] == b.samples["b"])
    assert a.mean("a") == pytest.approx(b.mean("a"), abs=0.02 * a.sd("a"))


def test_a_categorical_elements_entry_is_unused():
    rng = np.random.default_rng(5)
    t = np.column_stack([rng.random(24), rng.integers(0, 3, 24)])
    data, xo, yo = _data(t=t, t_categorical=["b"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(data, n_iter=150, seed=0)
    x = emu.with_calibration_priors(theta_mean=[0.3, 0.1], theta_sd=[0.1, 0.01])
    y = emu.with_calibration_priors(theta_mean=[0.3, 0.9], theta_sd=[0.1, 5.0])
    opts = {"n_samples": 300, "n_burn": 50, "seed": 6}
    _same(gpmsa.calibrate(x, xo, yo, **opts), gpmsa.calibrate(y, xo, yo, **opts))
    grid_x = gpmsa.Calibrator(x, n_grid=33, seed=1).update(xo, yo)
    grid_y = gpmsa.Calibrator(y, n_grid=33, seed=1).update(xo, yo)
    assert grid_x.mean("a") == grid_y.mean("a") and grid_x.mean("b") == grid_y.mean("b")
    levels = [None, np.array([0.0, 0.5, 1.0])]
    assert theta_log_prior(x.priors, levels, [0.35, 0.5]) == pytest.approx(-0.5 * 0.25, rel=1e-12)


# --- studies --------------------------------------------------------------------------------
def test_a_shared_parameter_needs_the_same_prior_of_it_in_every_model():
    emu, xo, yo = _emulator()
    one = emu.with_calibration_priors(theta_mean=[0.3, 0.5], theta_sd=[0.05, 10.0])
    other = emu.with_calibration_priors(theta_mean=[0.3, 0.2], theta_sd=[0.05, 0.5])
    study = gpmsa.calibrate_study([one, other], [xo, xo], [yo, yo], shared=["a"],
                                  n_samples=150, n_burn=50, seed=1)  # fmt: skip
    assert [e.prior for e in study.layout.elements] == [(0.3, 0.05), (0.5, 10.0), (0.2, 0.5)]
    with pytest.raises(GPMSAError, match=r"shared parameter 'b': the models' theta priors"):
        gpmsa.calibrate_study([one, other], [xo, xo], [yo, yo], shared=["b"], n_samples=10,
                            n_burn=5)  # fmt: skip


# --- the file and gpmsa info ----------------------------------------------------------------
def test_the_file_keeps_per_element_priors_and_a_shared_one_as_before(tmp_path, capsys):
    emu, _, _ = _emulator()
    per = emu.with_calibration_priors(theta_mean=TIGHT[0], theta_sd=TIGHT[1])
    back = gpmsa.load(per.save(tmp_path / "per.gpmsa"))
    assert back.priors == per.priors and back.model_sha256 == per.model_sha256
    with zipfile.ZipFile(tmp_path / "per.gpmsa") as z:
        pri = json.loads(z.read("manifest.json"))["priors"]
    assert pri["theta_mean"] == [0.3, 0.5] and pri["theta_sd"] == [0.05, 10.0]
    assert cli_main(["info", str(tmp_path / "per.gpmsa")]) == 0
    out = capsys.readouterr().out
    assert "theta [a Normal(0.3, 0.05), b Normal(0.5, 10)] on (0, 1) (unit scale, one per" in out
    shared = emu.priors.to_dict()  # a shared prior: the numbers it always was
    assert shared["theta_mean"] == 0.5 and shared["theta_sd"] == 10.0


def test_a_file_with_the_wrong_count_is_refused(tmp_path):
    emu, _, _ = _emulator()
    path = emu.with_calibration_priors(theta_sd=[0.2, 0.3]).save(tmp_path / "e.gpmsa")
    manifest, arrays = read_raw(path)
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    manifest["priors"]["theta_sd"] = [0.2, 0.3, 0.4]
    bad = write_raw(tmp_path / "bad.gpmsa", manifest, arrays)
    with pytest.raises(EmulatorFileError, match=r"priors.theta_sd: 3 per-element .* q = 2"):
        gpmsa.load(bad)
    manifest["priors"]["theta_sd"] = [0.2, -0.3]
    with pytest.raises(EmulatorFileError, match=r"priors.theta_sd\[1\]: -0.3 is out of range"):
        gpmsa.load(write_raw(tmp_path / "bad.gpmsa", manifest, arrays))
