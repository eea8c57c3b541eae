"""A run's one-line repr counts as a person writes it: "1 estimate", "1 sensor sample" (it
read "1 estimates over 0.3 s ...; 1 sensor samples"), as the Emulator's repr says "1 output"."""

from __future__ import annotations

import numpy as np

from control.estimate import run_text


def test_one_estimate_and_one_sample_read_singular():
    text = run_text(np.array(["ok"], dtype=object), [0.5], [2.0], "sensor")
    assert text == "1 estimate over 0.0 s, 0.0 m: ok 1; 1 sensor sample", text
    assert run_text([], [0.5], [2.0], "IMU") == "no estimate; 1 IMU sample"


def test_many_read_plural_as_before():
    text = run_text(np.array(["ok", "filling"]), [0.0, 0.25, 1.5], [0.0, 0.5, 3.0], "IMU")
    assert text == "2 estimates over 1.5 s, 3.0 m: filling 1, ok 1; 3 IMU samples", text
    assert run_text([], [], [], "sensor") == "no estimate; 0 sensor samples"


def test_a_replay_of_one_estimate_counts_it_in_the_singular():
    from control.robot.replay import ReplayResult

    fake = type("R", (), {"status": np.array(["ok"]), "duration_s": 1.0,
                          "status_counts": lambda self: {"ok": 1}})()  # fmt: skip
    assert ReplayResult._count_line(fake).startswith("1 estimate over 1.0 s: ok 1")


def test_a_posterior_of_no_parameters_says_so():
    import gpmsa

    assert repr(gpmsa.Posterior({})) == "Posterior(no parameters, method=?)"


def _replay_with_edges(edges):
    """A ReplayResult's describe() over stand-ins of its parts, one estimate per edge given."""
    from types import SimpleNamespace

    from control.robot.replay import ReplayResult

    topic = SimpleNamespace(describe=lambda: "a topic")
    n = len(edges)
    fake = SimpleNamespace(
        imu=topic, odometry=topic, resampling=SimpleNamespace(filter="none"), notes=(),
        status=np.array(["ok"] * n), gd_mean=np.full(n, 300.0), mode=np.array(["normal"] * n),
        domain_edge=np.array(edges), real_time_factor=50.0, read_s=0.1, condition_s=0.1,
        bcr_s=0.1, _count_line=lambda: f"{n} estimates",
    )  # fmt: skip
    return ReplayResult.describe(fake)


def test_one_estimate_at_an_edge_is_counted_in_the_singular():
    text = _replay_with_edges(["upper", "", "lower", "lower"])
    assert "\n1 estimate favours the upper edge of the emulator's GD domain" in text, text
    assert "\n2 estimates favour the lower edge of the emulator's GD domain" in text, text
