"""A topic refused for lacking its leading '/' names the absolute name to give only where
prefixing '/' makes one (a ROS name begins with a letter or "_"): before, `--imu-topic " /imu"`
was told "give '/ /imu'" and `~imu` (a private name, which a bag never records) "give
'/~imu'"."""

import pytest

from control.errors import ControlError
from control.robot.replay import ReplaySettings


@pytest.mark.parametrize("topic", [" /imu", "~imu", "1imu"])
def test_no_hint_names_a_topic_that_is_no_name(topic):
    with pytest.raises(ControlError, match="imu_topic / --imu-topic must start with '/'") as err:
        ReplaySettings(imu_topic=topic)
    assert str(err.value).endswith(f"got {topic!r}")
    assert "give" not in str(err.value)


def test_a_relative_name_is_still_told_its_absolute_name():
    with pytest.raises(ControlError) as err:
        ReplaySettings(odom_topic="odometry/filtered")
    assert str(err.value).endswith("got 'odometry/filtered': give '/odometry/filtered'")


def test_a_hidden_relative_name_is_told_its_absolute_name():
    with pytest.raises(ControlError, match=r"got '_imu': give '/_imu'$"):
        ReplaySettings(imu_topic="_imu")
