"""Outputs written by older versions are replaced as HEAD's own are (session 84's sweep of the
project's history): a CSV of estimates from before the domain_edge column (07aa72a)."""

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from control.errors import ControlError  # noqa: E402
from control.robot import replay_bag, write_sensor_bag  # noqa: E402
from control.robot.replay import CSV_HEADER, check_csv_target  # noqa: E402

OLD_HEADER = (
    b"stamp_ns,time_s,position_m,speed_mps,status,reason,gd_mean,gd_sd,gd_lo,gd_hi,"
    b"prob_gd_above_max,prob_change,command_mps,mode"
)
"""The first line of ReplayResult.to_csv before 07aa72a (commits a66bc35 to 07aa72a^)."""


def test_a_csv_of_estimates_before_the_domain_edge_column_is_replaced(tmp_path):
    """Before, replay_bag(csv=) and ReplayResult.to_csv refused it as 'exists and is not a CSV
    of estimates' (it is one, of an older version), over an older run's output folder."""
    old = tmp_path / "estimates.csv"
    old.write_bytes(OLD_HEADER + b"\r\n1700000000000000000,0.0,0.0,1.0,filling,no samples yet,"
                    b"nan,nan,nan,nan,nan,nan,1.0,performance\r\n")  # fmt: skip
    check_csv_target(old, "csv")
    n = 400
    t = 1.0 + np.arange(n) / 120.0
    accel = np.random.default_rng(1).normal(size=n)
    bag = write_sensor_bag(tmp_path / "bag", t, accel, t, t - 1.0, np.ones(n))
    result = replay_bag(bag, "A", csv=old)
    lines = old.read_bytes().splitlines()
    assert lines[0] == CSV_HEADER and len(lines) == result.gd_mean.size + 1


def test_a_header_cut_or_reordered_is_still_not_a_csv_of_estimates(tmp_path):
    """Only the headers the library wrote are taken as its tables."""
    for head in (OLD_HEADER[:-5], OLD_HEADER.replace(b"gd_mean,gd_sd", b"gd_sd,gd_mean"),
                 b"time_s," + OLD_HEADER):  # fmt: skip
        path = tmp_path / "x.csv"
        path.write_bytes(head + b"\n1,2\n")
        with pytest.raises(ControlError, match="is not a CSV of estimates"):
            check_csv_target(path, "csv")
