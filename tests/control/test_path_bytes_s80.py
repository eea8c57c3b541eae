"""control's path arguments (recordings, replays, CSVs, bags): a path-like whose __fspath__ gives
bytes (or no path) is a ControlError naming the argument, not pathlib's bare TypeError."""

import pytest

from control.errors import ControlError
from control.validation import path_argument


class PathLike:
    def __init__(self, value) -> None:
        self.value = value

    def __fspath__(self):
        return self.value


@pytest.mark.parametrize("given", [PathLike(b"run.mcap"), PathLike(3), PathLike(""), b"run.mcap"])
def test_a_path_like_giving_no_str_is_refused_naming_the_argument(given):
    with pytest.raises(ControlError, match=r"^bag must be the path \(a str or os.PathLike\)"):
        path_argument(given, "bag")


def test_bytes_name_the_remedy_and_a_str_path_like_passes():
    with pytest.raises(ControlError, match="decode bytes with os.fsdecode"):
        path_argument(PathLike(b"run.mcap"), "bag")
    assert path_argument(PathLike("run.mcap"), "bag").name == "run.mcap"
