"""``gpmsa calibrate`` and calibrated prediction."""

import json
import re

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs

from gpmsa import Calibrator, GPMSAError, Posterior, calibrate
from gpmsa.cli.main import main
from gpmsa.predictive.calibrated import calibrated_predict


@pytest.fixture(scope="module")
def emu_file(tmp_path_factory):
    return road_emulator().save(tmp_path_factory.mktemp("emu") / "road.gpmsa")


def test_cli_prints_summary(emu_file, capsys):
    assert main(["calibrate", str(emu_file), "--x", "v=1.25", "--y", "f=12.1"]) == 0
    out = capsys.readouterr().out
    assert "posterior (grid" in out and "GD" in out and "lamOs" in out
    row = next(line for line in out.splitlines() if line.split()[0] == "GD").split()
    post = Calibrator(road_emulator()).update([[1.25]], [[12.1]])
    assert float(row[1]) == pytest.approx(post.mean("GD"), rel=1e-4)


def test_cli_json(emu_file, capsys):
    args = [
        "calibrate",
        str(emu_file),
        "--x",
        "v=1.25",
        "--y",
        "f=12.1",
        "--json",
        "--level",
        "0.8",
    ]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    gd = out["posterior"]["GD"]
    assert out["method"] == "grid" and out["x"] == {"v": 1.25} and gd["exact_grid"]
    assert gd["q10"] < gd["median"] < gd["q90"]


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (["--x", "w=1.25", "--y", "f=12.1"], r"--x needs exactly the names \['v'\]"),
        (["--x", "v=fast", "--y", "f=12.1"], "is not a number"),
        (["--x", "v=1_0", "--y", "f=12.1"], "'1_0' is not a number"),  # float() reads 10
        (["--x", "v=1.25", "--y", "f"], "expects NAME=VALUE"),
        (["--x", "v=1.25", "--x", "v=1.5", "--y", "f=12.1"], "--x v is given twice"),
        (["--x", "v=9", "--y", "f=12.1"], "outside the emulator's domain .*; pass --extrapolate"),
    ],
)
def test_cli_bad_input(emu_file, capsys, extra, match):
    assert main(["calibrate", str(emu_file), *extra]) == 2
    assert re.search(match, capsys.readouterr().err)


def test_cli_level_near_one_names_its_ends_exactly(emu_file, capsys):
    args = ["calibrate", str(emu_file), "--x", "v=1.25", "--y", "f=12.1", "--json"]
    assert main([*args, "--level", "0.99999999"]) == 0
    gd = json.loads(capsys.readouterr().out)["posterior"]["GD"]
    assert gd["q5e-07"] < gd["median"] < gd["q99.9999995"]


@pytest.mark.parametrize(
    ("level", "match"),
    [("0", r"'0' must lie in \(0, 1\)"), ("nan", "must lie in"), ("x", "is not a number"),
     ("1e-300", "are both the median")],
)  # fmt: skip
def test_cli_level_is_checked_before_any_work(emu_file, capsys, level, match):
    with pytest.raises(SystemExit) as exit_:
        main(["calibrate", str(emu_file), "--x", "v=1.25", "--y", "f=12.1", "--level", level])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and "argument --level" in err and re.search(match, err)
    assert "Warning" not in err  # refused before the calibration


def test_calibrated_prediction_grid_and_draws_agree():
    emu = road_emulator()
    x, y = road_obs()
    post = Calibrator(emu, n_draws=20_000, seed=0).update(x, y)  # seeded: the draws vary
    x_new = [[0.8], [1.25], [1.9]]
    grid = calibrated_predict(emu, post, x_new)
    draws = calibrated_predict(emu, Posterior(post.samples), x_new, n_theta=4000)
    assert grid.weights.size > 50 and draws.weights.size == 4000
    np.testing.assert_allclose(grid.mean, draws.mean, rtol=0.01)
    np.testing.assert_allclose(np.sqrt(grid.var), np.sqrt(draws.var), rtol=0.05)
    # at the observed speed the prediction reproduces the observation within its spread
    assert abs(grid.mean[1, 0] - y[0][0]) < 2 * grid.sd[1, 0]


def test_noisy_prediction_on_the_grid_is_exact_and_matches_draws():
    """noise=True on a grid posterior stays on the grid (deterministic, never below the noise-free
    variance) and agrees with the draw-based mixture of per-draw lamOs."""
    emu = road_emulator()
    x, y = road_obs()
    post = Calibrator(emu, n_draws=40_000).update(x, y, seed=3)
    clean = calibrated_predict(emu, post, [[1.5]])
    noisy = calibrated_predict(emu, post, [[1.5]], noise=True)
    again = calibrated_predict(emu, post, [[1.5]], noise=True)
    assert noisy.weights.size == clean.weights.size > 50
    np.testing.assert_array_equal(noisy.var, again.var)
    np.testing.assert_allclose(noisy.mean, clean.mean)
    assert noisy.var[0, 0] > clean.var[0, 0]
    via_draws = calibrated_predict(
        emu, Posterior(post.samples), [[1.5]], noise=True, n_theta=40_000
    )
    extra = noisy.var[0, 0] - clean.var[0, 0]
    extra_draws = (
        via_draws.var[0, 0]
        - calibrated_predict(emu, Posterior(post.samples), [[1.5]], n_theta=40_000).var[0, 0]
    )
    assert extra == pytest.approx(extra_draws, rel=0.05)


def test_calibrated_prediction_quantiles_and_noise():
    emu = road_emulator()
    x, y = road_obs()
    post = Calibrator(emu).update(x, y)
    pred = calibrated_predict(emu, post, [[1.5]])
    for q in (0.05, 0.5, 0.95):
        assert pred.cdf(pred.quantile(q))[0, 0] == pytest.approx(q, abs=1e-9)
    with pytest.raises(GPMSAError, match=r"y must be finite, got nan at index \(\)"):
        pred.cdf(np.nan)  # was a silent NaN probability
    with pytest.raises(GPMSAError, match="y must hold real numbers"):
        pred.cdf(1.0 + 0j)
    with pytest.raises(GPMSAError, match=r"y must have shape \(1, 1\) .* got \(3, 4\)"):
        pred.cdf(np.ones((3, 4)))  # was broadcast into a (3, 4) answer for one point
    lo, hi = pred.interval(0.9)
    assert lo[0, 0] < pred.mean[0, 0] < hi[0, 0]
    noisy = calibrated_predict(emu, post, [[1.5]], noise=True)
    assert noisy.var[0, 0] > pred.var[0, 0]
    mc = calibrate(emu, x, y, seed=1)
    via_mcmc = calibrated_predict(emu, mc, [[1.5]])
    assert via_mcmc.mean[0, 0] == pytest.approx(pred.mean[0, 0], abs=0.5 * pred.sd[0, 0])
    with pytest.raises(GPMSAError, match="q must lie in"):
        pred.quantile(1.0)
    with pytest.raises(GPMSAError, match="outside the emulator's domain"):
        calibrated_predict(emu, post, [[5.0]])
    with pytest.raises(GPMSAError, match="n_theta must be an integer >= 1"):
        calibrated_predict(emu, post, [[1.5]], n_theta=0)


def test_cli_output_piped_into_a_closed_reader_exits_cleanly(tmp_path):
    """`gpmsa info FILE | head -1`: the reader leaves early; no traceback, exit status 0."""
    import subprocess
    import sys

    path = tmp_path / "road.gpmsa"
    road_emulator().save(path)
    code = "import sys; from gpmsa.cli.main import main; sys.exit(main(sys.argv[1:]))"
    proc = subprocess.Popen(
        [sys.executable, "-c", code, "info", str(path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    proc.stdout.close()  # nobody reads: the first write raises BrokenPipeError
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 0, err
    assert "Traceback" not in err
