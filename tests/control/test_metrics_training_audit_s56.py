"""Audit s56: control.training and the closed-loop / training examples' inputs."""

import numpy as np
import pytest

from control.errors import ControlError
from control.training import block_scatter, feature_statistics
from tests._examples import load_example


def test_feature_statistics_refuses_features_with_no_component():
    # (runs, blocks, 0) passed, and block_scatter then failed inside numpy (zero-size max)
    with pytest.raises(ControlError, match=r"K >= 1, got shape \(4, 20, 0\)"):
        feature_statistics(np.zeros((4, 20, 0)), 4)
    stats_ = feature_statistics(np.random.default_rng(0).normal(size=(4, 20, 1)), 4)
    assert stats_.cov.shape == (4, 1, 1)
    assert block_scatter([1.0, 1.2, 1.5, 2.0], stats_).cov.shape == (16, 1, 1)


def test_track_gds_that_print_alike_are_refused_by_name(tmp_path, capsys):
    # the tables and metrics.json key each part by f"{gd:g}": a second GD that printed like the
    # first replaced its RMSE and estimate count without a word
    script = load_example("closed_loop")
    with pytest.raises(ValueError, match=r"'10:300\.0000001'.*both print as 300"):
        script.parse_segments("10:300,10:300.0000001")
    assert script.parse_segments("10:300,10:300.5,5:300") == (
        (10.0, 300.0), (10.0, 300.5), (5.0, 300.0)
    )  # fmt: skip
    with pytest.raises(SystemExit) as exit_info:
        script.main(["--out", str(tmp_path), "--track", "10:300,10:300.0000001"])
    assert exit_info.value.code == 2
    assert "--track: segment '10:300.0000001'" in capsys.readouterr().err


def test_n_pc_help_counts_the_quantiles_among_the_outputs(capsys):
    # --n-pc takes up to the feature's outputs (bands and quantiles), not the bands alone
    with pytest.raises(SystemExit):
        load_example("train_emulator").main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "1 to the feature's outputs: its 8 band powers and one per --quantiles level" in text
