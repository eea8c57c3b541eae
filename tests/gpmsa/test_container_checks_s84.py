"""The emulator file reader's limits at their edges (session 84, mutation testing): what the
writer accepts the reader reads (a small, highly compressible member; the most members), a
file exactly at the size limit is read, and an empty array's other dimensions are bounded."""

from __future__ import annotations

import numpy as np
import pytest

from gpmsa import limits
from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.io import container
from gpmsa.io.container import _span_problem, _too_compressible, read_raw, write_raw

CONTENT = {"names": {}, "units": {}, "priors": {}, "settings": {}, "metadata": {},
           "diagnostics": {}}  # fmt: skip


def test_a_small_member_may_compress_beyond_the_ratio_by_its_slack():
    # the zip-bomb test allows MAX_RATIO times the compressed size plus 1024 bytes
    assert not _too_compressible(limits.MAX_RATIO + 1024, 0)
    assert _too_compressible(limits.MAX_RATIO + 1025, 0)
    assert not _too_compressible(limits.MAX_RATIO * 7 + 1024, 7)
    assert _too_compressible(limits.MAX_RATIO * 7 + 1025, 7)


def test_a_small_all_zero_array_round_trips(tmp_path):
    path = write_raw(tmp_path / "z.gpmsa", dict(CONTENT), {"z": np.zeros(120)})
    _, arrays = read_raw(path)
    np.testing.assert_array_equal(arrays["z"], np.zeros(120))


def test_an_empty_arrays_other_dimensions_are_bounded():
    assert _span_problem("a", (0, 5), 8) is None
    assert _span_problem("a", (0, limits.MAX_ARRAY_BYTES // 8), 8) is None
    assert "spans" in _span_problem("a", (0, limits.MAX_ARRAY_BYTES // 8 + 1), 8)
    assert "spans" in _span_problem("a", (0, 2**62), 8)
    with pytest.raises(GPMSAError, match="spans"):
        container.check_writable(dict(CONTENT), {"e": np.zeros((0, 2**40))})


def test_the_most_members_the_reader_takes_are_written_and_one_more_is_refused(
    tmp_path, monkeypatch
):
    monkeypatch.setattr(limits, "MAX_MEMBERS", 4)
    arrays = {f"a{k}": np.arange(3.0) + k for k in range(3)}  # + manifest.json: 4 members
    _, read = read_raw(write_raw(tmp_path / "ok.gpmsa", dict(CONTENT), arrays))
    assert sorted(read) == ["a0", "a1", "a2"]
    with pytest.raises(GPMSAError, match="MAX_MEMBERS - 1 = 3"):
        write_raw(tmp_path / "no.gpmsa", dict(CONTENT), {**arrays, "a3": np.ones(2)})


def test_a_file_exactly_at_the_size_limit_is_read(tmp_path, monkeypatch):
    path = write_raw(tmp_path / "s.gpmsa", dict(CONTENT), {"x": np.arange(5.0)})
    size = path.stat().st_size
    monkeypatch.setattr(limits, "MAX_FILE_BYTES", size)
    assert read_raw(path)[1]["x"].tolist() == [0.0, 1.0, 2.0, 3.0, 4.0]
    monkeypatch.setattr(limits, "MAX_FILE_BYTES", size - 1)
    with pytest.raises(EmulatorFileError, match="MAX_FILE_BYTES"):
        read_raw(path)


@pytest.mark.parametrize("kept", [4, 15, 21])
def test_a_file_cut_inside_its_zip_end_record_is_named_cut_short(tmp_path, kept):
    """The end record's 22 bytes cut to ``kept`` after its signature: named an incomplete copy,
    never a raw struct.error from reading the record's fields."""
    data = write_raw(tmp_path / "e.gpmsa", dict(CONTENT), {"x": np.arange(5.0)}).read_bytes()
    at = data.rfind(b"PK\x05\x06")
    assert len(data) - at == 22
    cut = tmp_path / "cut.gpmsa"
    cut.write_bytes(data[: at + kept])
    with pytest.raises(EmulatorFileError, match="cut short: its zip end record is missing"):
        read_raw(cut)
