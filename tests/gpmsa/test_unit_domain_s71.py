"""A user-chosen unit domain (``SimData(x_range=, t_range=)``, SEPIA's ``transform_xt(x_range=,
t_range=)``): the range the user designed for maps onto [0, 1] instead of the design's min/max,
so theta's prior covers it and inputs inside it are inside the emulator's domain."""

import warnings
from pathlib import Path

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main
from gpmsa.io.container import ENVELOPE, read_raw, write_raw
from gpmsa.model.transforms import Standardizer

ROOT = Path(__file__).resolve().parents[2]
PARAMS = {"betaU": [[2.0], [0.2]], "lamUz": [1.0], "lamWs": [1e5], "lamWOs": [1e5]}


def truth(x, t):
    return np.sin(3 * x) + (t - 200.0) / 400.0


def design(m=30, seed=0):
    """A Latin hypercube strictly inside x in [0, 1], GD in [200, 600] (GD's runs in [226, 569]):
    the extreme runs lie well inside the range designed for."""
    rng = np.random.default_rng(seed)
    u = (rng.permutation(m) + rng.random(m)) / m
    v = (rng.permutation(m) + rng.random(m)) / m
    return 0.1 + 0.8 * u, 200.0 + 400.0 * (0.05 + 0.9 * v)


def sim(**ranges):
    x, t = design()
    return gpmsa.SimData(x=x, t=t, y=truth(x, t), x_names=["v"], t_names=["GD"], **ranges)


def emulator(**ranges):
    return gpmsa.Emulator.from_params(sim(**ranges), PARAMS)


RANGES = {"x_range": [[0.0, 1.0]], "t_range": {"GD": (200.0, 600.0)}}


def test_ranges_set_the_unit_domain_and_default_is_unchanged():
    plain, ranged = sim(), sim(**RANGES)
    assert plain.x_range is None and plain.t_range is None
    assert ranged.x_range == ((0.0, 1.0),) and ranged.t_range == ((200.0, 600.0),)
    s0, s1 = Standardizer.from_sim(plain), Standardizer.from_sim(ranged)
    assert (s0.x_ranged, s0.t_ranged) == ((), ())  # the default: the design's min/max, as before
    assert np.array_equal(s0.t_min, plain.t.min(axis=0))
    assert np.array_equal(s0.t_max, plain.t.max(axis=0))
    assert (s1.x_ranged, s1.t_ranged) == ((True,), (True,))
    assert (s1.t_min[0], s1.t_max[0]) == (200.0, 600.0)
    u = s1.t_to_unit(plain.t)
    assert 0.05 < u.min() < 0.1 and 0.9 < u.max() < 0.95  # the design inside, not spanning
    emu = gpmsa.Emulator.from_params(ranged, PARAMS)
    assert emu.domain == {"v": (0.0, 1.0), "GD": (200.0, 600.0)}
    assert emu.given_ranges == ("v", "GD")
    assert gpmsa.Emulator.from_params(plain, PARAMS).given_ranges == ()
    part = gpmsa.Emulator.from_params(sim(t_range={"GD": [150, 650]}), PARAMS)
    assert part.given_ranges == ("GD",) and part.domain["GD"] == (150.0, 650.0)
    assert part.domain["v"] == (float(plain.x.min()), float(plain.x.max()))


@pytest.mark.parametrize(
    ("ranges", "match"),
    [
        ({"t_range": {"GD": (np.nan, 600)}}, r"t_range\[GD\] = \(nan, 600.0\) must be finite"),
        ({"t_range": {"GD": (600, 200)}}, r"t_range\[GD\] .* min < max"),
        ({"t_range": {"GD": (200, 200)}}, r"t_range\[GD\] .* min < max"),
        ({"t_range": {"GD": (300, 600)}}, r"design column GD spans \[2\d\d.*outside its t_range"),
        ({"x_range": [[0.2, 1.0]]}, r"design column v spans .* outside its x_range \[0.2, 1\]"),
        ({"t_range": {"E": (0, 1)}}, r"t_range: 'E' is not a column"),
        ({"t_range": [[200], [600]]}, r"t_range must be \(1, 2\).*transpose it"),
        ({"x_range": [[0, 1, 2]]}, r"x_range must be \(1, 2\)"),
        ({"t_range": {"GD": "200..600"}}, r"t_range\[GD\] must be a numeric array"),
        ({"t_range": {"GD": (200, 600, 700)}}, r"t_range\[GD\] must be \(min, max\)"),
    ],
)
def test_bad_ranges_are_refused_naming_the_column(ranges, match):
    with pytest.raises(gpmsa.GPMSAError, match=match):
        sim(**ranges)


def test_a_categorical_column_takes_no_range():
    x, t = design()
    c = np.arange(30) % 3
    with pytest.raises(gpmsa.GPMSAError, match=r"x_range\[c\]: c is categorical"):
        gpmsa.SimData(x=np.column_stack([x, c]), t=t, y=truth(x, t) + c, x_names=["v", "c"],
                      x_categorical=["c"], x_range={"c": (0, 2)})  # fmt: skip


def test_file_round_trip_keeps_the_given_ranges(tmp_path, capsys):
    emu = emulator(**RANGES)
    path = emu.save(tmp_path / "ranged.gpmsa")
    back = gpmsa.load(path)
    assert back.given_ranges == ("v", "GD") and back.domain == emu.domain
    assert back.model_sha256 == emu.model_sha256
    x, t = np.array([[0.95]]), np.array([[590.0]])
    assert np.array_equal(back.predict(x, t)[0], emu.predict(x, t)[0])
    manifest, _ = read_raw(path)
    assert manifest["model"]["input_ranges"] == ["v", "GD"]
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "GD in [200, 600] (range given, design inside)" in out


def test_a_file_without_ranges_is_written_and_read_as_before(tmp_path):
    """No given range: no model.input_ranges (the manifest as before), and the shipped files
    (written before it) load with the design's min/max as the domain."""
    path = emulator().save(tmp_path / "plain.gpmsa")
    manifest, _ = read_raw(path)
    assert "input_ranges" not in manifest["model"]
    assert gpmsa.load(path).given_ranges == ()
    old = gpmsa.load(ROOT / "control" / "emulators" / "jackal_A.gpmsa")
    assert old.given_ranges == ()
    assert old.standardizer.x_ranged == () and old.standardizer.t_ranged == ()
    assert np.allclose(old.x_unit.min(axis=0), 0) and np.allclose(old.t_unit.max(axis=0), 1)


def _rewrite(src, dst, edit):
    manifest, arrays = read_raw(src)
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    edit(manifest)
    return write_raw(dst, manifest, arrays)


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda m: m["model"].pop("input_ranges"), r"arrays/x_unit: column 0 spans \[0\.1"),
        (lambda m: m["model"].update(input_ranges=["v"]), r"arrays/t_unit: column 0 spans"),
        (lambda m: m["model"].update(input_ranges=["v", "E"]), "model.input_ranges: 'E' is not"),
        (lambda m: m["model"].update(input_ranges=["v", "v"]), "model.input_ranges: must be"),
        (lambda m: m["model"].update(input_ranges=[]), "model.input_ranges: must be a non-empty"),
        (lambda m: m["model"].update(input_ranges="GD"), "model.input_ranges: must be"),
    ],
)
def test_the_reader_checks_the_recorded_ranges(tmp_path, edit, match):
    src = emulator(**RANGES).save(tmp_path / "ranged.gpmsa")
    dst = _rewrite(src, tmp_path / "edited.gpmsa", edit)
    with pytest.raises(gpmsa.EmulatorFileError, match=match):
        gpmsa.load(dst)


def test_a_design_outside_its_recorded_range_is_refused(tmp_path):
    """A design stretched past the recorded range (t_unit above 1) is refused: the range holds
    every run."""
    src = emulator(**RANGES).save(tmp_path / "ranged.gpmsa")
    manifest, arrays = read_raw(src)
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    arrays = dict(arrays, t_max=np.array([500.0]))  # design runs up to 569 now read 1.2 and more
    manifest["domain"]["GD"] = [200.0, 500.0]
    arrays["t_unit"] = (design()[1][:, None] - 200.0) / 300.0
    path = write_raw(tmp_path / "outside.gpmsa", manifest, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match=r"arrays/t_unit: must lie in \[0, 1\]"):
        gpmsa.load(path)


def _obs(gd=590.0):
    x = np.array([[0.95], [0.5], [0.05]])  # 0.95 and 0.05: outside the design's x, inside [0, 1]
    rng = np.random.default_rng(3)
    return x, truth(x[:, 0], gd)[:, None] + 0.01 * rng.standard_normal((3, 1))


def test_calibration_near_the_edge_recovers_theta_with_the_prior_on_the_given_range():
    """GD = 590 beyond the design's largest run (569): with GD's range [200, 600] given, grid
    and MCMC recover it (590.4 +- 5.3, 590.2 +- 5.7); with the design's own range the prior
    stops at 569 (MCMC 564 +- 5.7, every draw below 569.4) and the Calibrator refuses
    x_obs 1.0, outside the design's x [0.125, 0.886] by more than 10 % of its width (0.95,
    within it, is taken with a warning as a joint fit takes it: session 73)."""
    x, y = _obs(590.0)
    ranged = emulator(**RANGES)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # x inside the given range: no extrapolation warning
        grid = gpmsa.Calibrator(ranged).update(x, y)
        mcmc = gpmsa.calibrate(ranged, x, y, n_samples=1500, n_burn=300, seed=1)
    # but the one chain's convergence check (since session 76: lamOs split R-hat 1.015)
    assert {w.category for w in caught} <= {gpmsa.ConvergenceWarning}, [
        str(w.message) for w in caught
    ]
    for post in (grid, mcmc):
        assert abs(post.mean("GD") - 590.0) < 3 * post.sd("GD") + 5.0
        assert post.quantile("GD", 0.99) <= 600.0
    assert np.mean(mcmc.samples["GD"] > 569.5) > 0.9  # beyond the design's largest GD
    plain = emulator()
    hi = plain.domain["GD"][1]  # the design's largest GD, 569: the prior stops there
    with pytest.raises(gpmsa.GPMSAError, match=r"x_obs v=1 lies outside the emulator's domain"):
        gpmsa.Calibrator(plain).update(np.where(x > 0.9, 1.0, x), y)
    with warnings.catch_warnings(), pytest.warns(gpmsa.ExtrapolationWarning):
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)  # piled at the bound
        near = gpmsa.calibrate(plain, x, y, n_samples=500, n_burn=100, seed=1, extrapolate=True)
    assert near.samples["GD"].max() <= hi < 570.0


def test_outside_means_outside_the_given_range():
    """x_obs beyond the given range: calibrate and a joint fit warn within 10 % of the range
    and refuse beyond (calibrate's extrapolate=True warns); predictions likewise."""
    ranged = emulator(**RANGES)
    y = np.array([[0.5]])
    with pytest.raises(gpmsa.GPMSAError, match=r"v=1.2 lies outside the emulator's domain \[0,"):
        gpmsa.calibrate(ranged, [[1.2]], y, n_samples=100, n_burn=10, seed=1)
    with pytest.warns(gpmsa.ExtrapolationWarning):
        ranged.predict(np.array([[1.05]]), np.array([[400.0]]))
    with pytest.raises(gpmsa.GPMSAError, match="more than 10%"):
        ranged.predict(np.array([[1.2]]), np.array([[400.0]]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ranged.predict(np.array([[0.99]]), np.array([[205.0]]))  # inside the range: silent
    data = sim(**RANGES)
    obs = gpmsa.ObsData(x=[[0.02], [0.98]], y=[[0.1], [0.5]])
    with warnings.catch_warnings():
        warnings.simplefilter("error", gpmsa.ExtrapolationWarning)
        gpmsa.prepare(data, obs)  # outside the design's hull, inside the range: silent
    with pytest.warns(gpmsa.ExtrapolationWarning):
        gpmsa.prepare(data, gpmsa.ObsData(x=[[1.05]], y=[[0.5]]))
    with pytest.raises(gpmsa.GPMSAError, match="cannot extrapolate that far"):
        gpmsa.prepare(data, gpmsa.ObsData(x=[[1.2]], y=[[0.5]]))


def test_a_joint_fit_samples_theta_over_the_given_range():
    x, y = _obs(590.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim(**RANGES), gpmsa.ObsData(x=x, y=y), n_iter=300, seed=2, tune=False)
    post = gpmsa.calibration_posterior(emu)
    assert post.samples["GD"].max() > 570.0  # beyond the design's largest GD (569)
    assert post.samples["GD"].max() <= 600.0


def test_sensitivity_default_box_is_the_given_range():
    ranged = emulator(**RANGES)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        default = gpmsa.sensitivity(ranged, draws=False)
        given = gpmsa.sensitivity(ranged, draws=False, bounds={"v": (0, 1), "GD": (200, 600)})
    assert np.array_equal(default.main, given.main)
    assert np.array_equal(default.total, given.total)


def test_stored_ranges_rebuild_the_same_data():
    """``SimData`` takes back the ranges as it stores them (one (min, max) or None a column)."""
    x, t = design()
    two = gpmsa.SimData(x=np.column_stack([x, t]), t=t[::-1], y=truth(x, t), x_names=["v", "w"],
                        x_range={"w": (200, 600)})  # fmt: skip
    assert two.x_range == (None, (200.0, 600.0))
    again = gpmsa.SimData(x=two.x, t=two.t, y=two.y, x_range=two.x_range)
    assert again.x_range == two.x_range and again.t_range is None
