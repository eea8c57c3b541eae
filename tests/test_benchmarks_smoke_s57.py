"""Benchmarks at their smallest settings (session 57): what broke or mislabelled there, tested on
the pure functions (a benchmark's own run takes 5-350 s) and one run that takes about a second."""

import inspect
import warnings
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import control
from control.sensor_checks import SensorLimits, flight_reading
from tests._examples import load_benchmark
from tests._script_runs import run_scripts

ROOT = Path(__file__).resolve().parents[1]


def test_sensor_checks_power_table_takes_every_block_when_there_are_fewer_than_1000() -> None:
    # --keep-s 1.05 (valid: one block a drive) gives 198 blocks: the power table drew 1,000
    # without replacement and stopped with numpy's "Cannot take a larger sample" traceback
    bench = load_benchmark("sensor_checks")
    blocks = np.random.default_rng(0).standard_normal((30, bench.BLOCK))
    limits = SensorLimits(noise_sd_mps2=1.0)
    hits, tried = bench.lattice_hits(
        blocks, 2.0, 10, np.random.default_rng(1), flight_reading(limits), limits.lattice_p
    )
    assert tried == 30
    assert 0 <= hits <= tried
    assert blocks.std() > 0.9  # the caller's blocks are left as they were (copies are rounded)
    assert not np.allclose(blocks, np.round(blocks / 2.0) * 2.0)


def test_fault_soak_worst_runs_over_the_whole_run_are_random_scenarios_only() -> None:
    # the list sliced the outcomes that did not crash by the number of random scenarios: one
    # crashed scenario let the first example into "random scenarios with the largest excess"
    bench = load_benchmark("fault_soak")

    def outcome(name: str, crash: str = "", diff: float = 0.0, during: float = 0.0):
        sc = bench.Scenario(name, "A", ((50.0, 300.0),), 1, 1, "spike", 1.0, 1.0)
        return bench.Outcome(sc, crash=crash, fast_clean=1.0, fast_fault=1.0 + diff,
                             during_clean=0.0, during_fault=during, statuses=Counter())  # fmt: skip

    random_out = [outcome("#0", crash="clean run: boom"), outcome("#1", diff=0.5, during=0.2)]
    example_out = [outcome("example", diff=2.0, during=0.3)]
    during, worse = bench.worst_outcomes(random_out, example_out)
    assert [o.scenario.name for o in worse] == ["#1"]
    assert [o.scenario.name for o in during] == ["example", "#1"]  # worst first, both kinds


def _random_run(steps, delays) -> dict:
    return {"kind": "random", "case": "A", "mean": np.array([300.0, 500.0]),
            "true": np.array([300.0, 500.0]), "lo": np.array([250.0, 450.0]),
            "hi": np.array([350.0, 550.0]), "steps": steps, "delays": delays}  # fmt: skip


def test_accuracy_random_set_without_a_rise_does_not_judge_the_delay_target() -> None:
    # --random-tracks 1 (track 401: no rise of 150) printed "median delay nan m [nan, nan] ...
    # target NOT met" after numpy's empty-slice warnings
    bench = load_benchmark("closed_loop_accuracy")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        line = bench.report_random([_random_run([(400.0, 300.0)], [np.nan])], "A")
    assert line.endswith("rises >= 150: none  target not judged (no rise to time)")
    assert "cover 1.000" in line
    judged = bench.report_random([_random_run([(300.0, 500.0)], [3.0])], "A")
    assert "rises >= 150: n 1, median delay 3.0 m [3.0, 3.0], never detected 0" in judged
    assert judged.endswith("target NOT met")  # coverage 1.0 lies outside 0.85-0.95


def test_feature_information_lack_of_fit_is_unknown_with_as_many_runs_as_coefficients() -> None:
    # --n-runs 10 (the smallest allowed): the cubic's 10 coefficients go through every run mean;
    # the lack of fit divided by zero degrees of freedom (a RuntimeWarning, then inf in the table)
    bench = load_benchmark("feature_information")
    rng = np.random.default_rng(0)
    v, gd = rng.uniform(0.5, 2.0, 10), rng.uniform(200.0, 600.0, 10)
    feats = np.log(gd)[:, None, None] + 0.1 * rng.standard_normal((10, 16, 2))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.isnan(bench.fit(v, gd, feats, batch=4).lack_of_fit)
    v, gd = rng.uniform(0.5, 2.0, 12), rng.uniform(200.0, 600.0, 12)
    feats = np.log(gd)[:, None, None] + 0.1 * rng.standard_normal((12, 16, 2))
    assert np.isfinite(bench.fit(v, gd, feats, batch=4).lack_of_fit)


def test_feature_information_singular_covariance_is_named_with_its_remedy() -> None:
    # a variant with more outputs than the short campaigns' batch means (--n-runs 10 --keep-s
    # 16.67, 10 outputs) stopped section 4 with numpy's "Singular matrix" traceback
    # (the table row says so and section 4 goes on; fit raises what the rows catch)
    bench = load_benchmark("feature_information")
    rng = np.random.default_rng(0)
    v, gd = rng.uniform(0.5, 2.0, 12), rng.uniform(200.0, 600.0, 12)
    feats = rng.standard_normal((12, 16, 3))
    feats[..., 2] = feats[..., 1]  # two outputs alike: Sigma(v) is singular
    with pytest.raises(np.linalg.LinAlgError):
        bench.fit(v, gd, feats, batch=8)
    message = bench.singular("", 10, 16.67)
    assert message.startswith("Sigma(v) singular: 10 runs x 16.67 s hold too few batches")
    assert message.endswith("(raise --n-runs or --keep-s)")
    assert bench.singular("bands, B = 125", 10, 16.67).startswith("bands, B = 125: Sigma(v)")


def test_second_channel_loop_reads_the_feature_its_emulators_were_fitted_to() -> None:
    # the loops ran the default BCRSettings, whose feature has had two quantiles added (10
    # outputs) since: every run stopped on "y must be 8 finite numbers" (the 8 band powers)
    bench = load_benchmark("second_channel_loop")
    settings = bench.loop_settings()
    assert settings.feature == bench.SPEC
    assert settings.feature.dim == 8
    assert replace(settings, feature=control.BCRSettings().feature) == control.BCRSettings()


@pytest.mark.parametrize("hook", ["reset", "_take", "_block_feature", "_signal_reason"])
def test_second_channel_loop_bcr_overrides_the_bcr_hooks_it_extends(hook: str) -> None:
    # BCR._take lost its (drop, restart, reason) arguments and _signal_reason gained (timing,
    # steady): the two-channel runs stopped with "_take() missing 3 required positional args"
    bench = load_benchmark("second_channel_loop")
    mine = inspect.signature(getattr(bench.TwoChannelBCR, hook))
    assert mine == inspect.signature(getattr(control.BCR, hook))


def test_backends_rhat_of_too_few_draws_is_nan_without_a_warning() -> None:
    bench = load_benchmark("backends")
    draws = {"a": np.random.default_rng(0).standard_normal((2, 4))}  # split R-hat: NaN
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        n_eff, r_hat = bench.ess_rhat(draws, ["a"])
    assert np.isnan(r_hat) and n_eff > 0
    draws = {"a": np.random.default_rng(0).standard_normal((2, 400))}
    assert 0.98 < bench.ess_rhat(draws, ["a"])[1] < 1.02


def test_roadgen_speed_prints_the_load_average_with_its_timings() -> None:
    (done,) = run_scripts([("benchmarks/roadgen_speed.py", ["--repeats", "1"])])
    assert done["returncode"] == 0, done["stderr"][-2000:]
    lines = done["stdout"].splitlines()
    assert lines[0].startswith("median of 1 runs; load average ")
    assert lines[-1].startswith("load average ") and lines[-1].endswith(" cores")
    assert sum(line.endswith(" ms") for line in lines) == 7


def test_tempered_continuation_prints_each_variant_with_its_ratios_and_the_load(capsys) -> None:
    # in this interpreter (its main takes argv): a fresh one's start and imports cost ~1.5 s
    load_benchmark("tempered_continuation").main(["--quick"])
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("# two-mode case") and "load average " in lines[0]
    assert lines[-1].startswith("load average ") and lines[-1].endswith(" cores")
    rows = [line for line in lines if line.startswith(("(a)", "(b)", "(c)"))]
    assert len(rows) == 3
    assert all("(exact 0.5)" in row and " of 2 chains" in row for row in rows)
    assert lines[-2].startswith("a/b ") and "; a/c " in lines[-2]


def test_tempered_continuation_refuses_too_few_sweeps() -> None:
    bench = load_benchmark("tempered_continuation")
    with pytest.raises(SystemExit):
        bench.main(["--sweeps", "5"])
