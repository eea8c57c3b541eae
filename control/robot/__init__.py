"""Robot recordings: replay a ROS bag through the BCR, write a run for Foxglove.

Needs the optional packages of the ``robot`` extra (``pip install -e ".[robot]"``: rosbags,
mcap); they are imported only when a function needs them, so ``import control`` never does.

- `replay_bag`: IMU and odometry of a ROS 2 bag (MCAP or sqlite3), a ROS 1 bag or an MCAP file
  through the BCR and the Simplex; estimates as a table, CSV and ROS 2 bag
  (``terrain-replay`` on the command line).
- `record_run`: a closed-loop run as an MCAP file for Foxglove (examples/foxglove_layout.json).
- `write_sensor_bag`, `write_run_bag`: sampled signals or a closed-loop run as a ROS 2 bag of
  standard messages (to try the replay, and its round-trip test).
"""

from control.robot.bags import Recording, read_recording, write_run_bag, write_sensor_bag
from control.robot.condition import Resampling, StreamReport
from control.robot.record import record_run
from control.robot.replay import CSV_COLUMNS, ReplayResult, ReplaySettings, replay_bag

__all__ = [
    "CSV_COLUMNS",
    "Recording",
    "ReplayResult",
    "ReplaySettings",
    "Resampling",
    "StreamReport",
    "read_recording",
    "record_run",
    "replay_bag",
    "write_run_bag",
    "write_sensor_bag",
]
