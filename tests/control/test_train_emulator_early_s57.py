"""train_emulator.py refuses, before the campaign, settings whose band-emulator block scatter
must be singular (it drove the whole campaign, then failed in control.training.block_scatter)."""

import numpy as np
import pytest
from _train_cases import CampaignReached, run_until_the_campaign

from control.errors import ControlError
from control.observation_model import BlockScatter
from control.training import (
    SINGULAR_WEIGHT,
    BlockStatistics,
    block_scatter,
    covariance_rank,
    feature_statistics,
    weight_beyond_rank,
)


@pytest.mark.parametrize(
    "argv, messages",
    [
        (  # 8 + 2 anchor runs of rank 1: full rank only with every run, and 2 m/s sees
            # the run at 0.5 m/s with a weight of 6e-23 (drove, then failed at 0.5 m/s)
            ["--n-runs", "8", "--keep-s", "16.67"],
            [
                "--n-runs 8 and 2 anchor runs with --keep-s 16.67: the band emulators' 10 x 10 "
                "block covariance (K = 8 band powers + 2 quantiles) would be singular whatever "
                "the roads: each run's 2 batches of 8 blocks give it rank 1, so it needs 10 runs "
                "near each speed, and at 2 m/s all but 6e-23 of the kernel weight lies on the 9 "
                "nearest runs: raise --n-runs, --anchor-runs or --keep-s",
            ],
        ),
        (
            ["--n-runs", "8", "--keep-s", "16.67", "--anchor-speeds"],
            [
                "--n-runs 8 with --keep-s 16.67:",
                "and 8 runs x 1 < 10 at every speed: raise --n-runs or --keep-s",
            ],
        ),  # fmt: skip
        (  # the band powers alone: K = 8
            ["--n-runs", "8", "--keep-s", "16.67", "--anchor-speeds", "--quantiles"],
            ["8 x 8 block covariance (K = 8 band powers + 0 quantiles)", "lies on the 7 nearest"],
        ),
        (  # 25 s: 3 batches, rank 2; 5 runs across 1.5 m/s
            ["--n-runs", "5", "--n-pc", "5", "--keep-s", "25", "--anchor-speeds"],
            ["rank 2, so it needs 5 runs near each speed", "lies on the 4 nearest runs"],
        ),
    ],
)
def test_a_scatter_that_must_be_singular_is_refused_before_the_campaign(
    monkeypatch, tmp_path, capsys, argv, messages
):
    with pytest.raises(SystemExit) as exc:
        run_until_the_campaign(monkeypatch, tmp_path, [*argv, "--cases", "A", "--features", "band"])
    assert exc.value.code == 2
    error = capsys.readouterr().err.strip().splitlines()[-1]
    for message in messages:
        assert message in error
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "argv",
    [
        [],  # the defaults: 198 + 2 x 33 runs of 120 s
        ["--n-runs", "24", "--keep-s", "18"],  # the tests' settings
        ["--n-runs", "16", "--keep-s", "12", "--block-samples", "80", "--n-pc", "7", "--quantiles"],
        ["--n-runs", "16", "--keep-s", "18", "--speed-range", "0.5", "1.5"],
        ["--n-runs", "4", "--n-pc", "4", "--keep-s", "50"],
        # the smallest that gave the scatter, measured (16 and 12 runs of rank 1)
        ["--n-runs", "12", "--keep-s", "16.67"],
        ["--n-runs", "16", "--keep-s", "16.67", "--anchor-speeds"],
        # the preflight test's late failure: near-singular, not certainly singular
        ["--n-runs", "11", "--keep-s", "16.7", "--anchor-runs", "1"],
    ],
)
def test_settings_that_can_give_the_scatter_reach_the_campaign(monkeypatch, tmp_path, argv):
    with pytest.raises(CampaignReached):
        run_until_the_campaign(monkeypatch, tmp_path, argv)


@pytest.mark.parametrize("n_blocks, rank", [(16, 1), (17, 2), (23, 2), (24, 2), (25, 3)])
def test_covariance_rank_is_the_rank_feature_statistics_gives(n_blocks, rank):
    feats = np.random.default_rng(n_blocks).normal(size=(3, n_blocks, 10))
    cov = feature_statistics(feats, batch=8).cov
    assert covariance_rank(n_blocks, batch=8) == rank
    assert [np.linalg.matrix_rank(c) for c in cov] == [rank] * 3


def test_a_node_below_the_singular_weight_is_refused_by_block_scatter():
    """The bound behind the check: whatever the runs' covariances of that rank (traces up to
    1,000 times apart), block_scatter refuses a node whose share <= SINGULAR_WEIGHT. Random
    designs, half with barely enough runs over a wide speed range, half with plenty."""
    rng = np.random.default_rng(57)
    seen = {"refused": 0, "accepted": 0}
    for trial in range(200):
        dim, rank = int(rng.integers(3, 11)), int(rng.integers(1, 4))
        need = -(-dim // rank)
        if trial % 2:
            m, span = max(2, need + int(rng.integers(0, 3))), rng.uniform(1.0, 4.0)
        else:
            m, span = int(rng.integers(2 * need, 4 * dim + 1)), rng.uniform(0.3, 2.0)
        speed = rng.uniform(0.5, 0.5 + span, m)
        nodes = np.linspace(speed.min(), speed.max(), 16)
        roots = (
            rng.normal(size=(m, dim, rank)) * np.sqrt(10.0 ** rng.uniform(0, 3, m))[:, None, None]
        )
        stats_ = BlockStatistics(
            mean=np.zeros((m, dim)),
            cov=roots @ roots.transpose(0, 2, 1),
            features=rng.normal(size=(m, 2, dim)),
        )
        share = weight_beyond_rank(speed, rank, dim, nodes)
        if np.any(share <= SINGULAR_WEIGHT):
            with pytest.raises(ControlError, match="is singular"):
                block_scatter(speed, stats_, nodes=nodes)
            seen["refused"] += 1
        elif np.all(share > 1e-6):  # far from the bound these covariances have full rank
            assert isinstance(block_scatter(speed, stats_, nodes=nodes), BlockScatter)
            seen["accepted"] += 1
    assert seen["refused"] >= 30 and seen["accepted"] >= 80, seen  # 42 and 125


def test_weight_beyond_rank_at_its_ends():
    speed = np.linspace(0.5, 2.0, 8)
    nodes = np.linspace(0.5, 2.0, 16)
    assert np.all(weight_beyond_rank(speed, 1, 10, nodes) == 0.0)  # 8 x 1 < 10
    assert np.allclose(weight_beyond_rank(speed, 10, 10, nodes), 1.0)  # one run is enough
    share = weight_beyond_rank(speed, 1, 8, nodes)  # every run needed: the farthest's weight
    assert share[0] == pytest.approx(
        np.exp(-50.0) / np.exp(-0.5 * ((speed - 0.5) / 0.15) ** 2).sum(), rel=1e-12
    )
    with pytest.raises(ControlError, match="run_rank and dim must be integers >= 1"):
        weight_beyond_rank(speed, 0, 10, nodes)
