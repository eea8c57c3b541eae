"""Review of the session's interruption and far-value commits: a write that fails at the file
system's limit (a full disk, a quota, a file size limit) names the file even where the failure
comes back while the temporary file is closed, and a joint fit of a scalar output names a datum
beyond 5 of its own stated noise sds (and 100 of the outputs' sds), as every other path reads a
stated precision."""

from __future__ import annotations

import os

import numpy as np
import pytest

import gpmsa
from gpmsa.io.atomic import atomic_write
from tests.gpmsa._far_cases import scalar_sim as _scalar_sim
from tests.gpmsa._far_cases import stop_sampling, texts_before_sampling

resource = pytest.importorskip("resource")
signal = pytest.importorskip("signal")

LIMIT = 4096
"""The file size limit (bytes) the writes below meet."""


@pytest.fixture
def file_size_limit():
    """A limit of ``LIMIT`` bytes on any file this process writes (RLIMIT_FSIZE; SIGXFSZ
    ignored): a write past it fails with EFBIG, as one on a full disk fails with ENOSPC. Held
    only while the test's block writes; restored after."""
    if not hasattr(signal, "SIGXFSZ"):
        pytest.skip("no SIGXFSZ")
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    if hard != resource.RLIM_INFINITY and hard < LIMIT:
        pytest.skip("a lower hard file size limit")
    handler = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)

    class Limit:
        def __enter__(self):
            resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT, hard))

        def __exit__(self, *exc):
            resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))

    try:
        yield Limit()
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, handler)


def test_text_past_the_file_size_limit_names_the_file(tmp_path, file_size_limit):
    """The text still buffered when the write failed was flushed again as the file closed, and
    that OSError ("[Errno 27] File too large") replaced the error naming the file."""
    path = tmp_path / "notes.txt"
    path.write_text("old")
    with pytest.raises(gpmsa.GPMSAError) as info:
        with file_size_limit, atomic_write(path, text=True) as fh:
            fh.write("x" * (LIMIT + 100))  # within the buffers: written at the flush
    assert str(info.value) == f"{path}: cannot write (File too large)"
    assert isinstance(info.value.__cause__, OSError)
    assert path.read_text() == "old" and os.listdir(tmp_path) == ["notes.txt"]


def test_an_emulator_save_past_the_file_size_limit_names_the_file(tmp_path, file_size_limit):
    """A save whose zip fails at the limit: a bare OSError before (the zip's last bytes were
    buffered; the flush at the close failed after the named error)."""
    from _study_cases import emulator

    path = tmp_path / "e.gpmsa"
    emulator(None).save(path)
    before = path.read_bytes()
    assert len(before) > LIMIT // 2
    with pytest.raises(gpmsa.GPMSAError, match=rf"^{path}: cannot write \(File too large\)$"):
        with file_size_limit:
            emulator(None, lam_w=500.0).save(path)
    assert path.read_bytes() == before and os.listdir(tmp_path) == ["e.gpmsa"]


def test_a_writers_own_error_is_kept_when_the_close_fails_too(tmp_path, file_size_limit):
    """A writer's own error (here a GPMSAError of its own) raised while the file still buffers
    bytes the limit refuses: that error, not the close's OSError."""
    path = tmp_path / "f.bin"
    with pytest.raises(gpmsa.GPMSAError, match="^the writer's own$"):
        with file_size_limit, atomic_write(path) as fh:
            fh.write(b"x" * (LIMIT + 100))  # within the buffer: written at the close
            raise gpmsa.GPMSAError("the writer's own")
    assert os.listdir(tmp_path) == []


def _outside(monkeypatch, sim, obs) -> list[str]:
    stop_sampling(monkeypatch)
    return texts_before_sampling(lambda: gpmsa.fit(sim, obs, seed=0))


def test_a_scalar_joint_fit_names_a_datum_far_beyond_its_stated_noise(monkeypatch):
    """A datum of stated noise sd 5 output sds lying 300 output sds beyond every run (60 of its
    noise sds) went unnamed: the joint fit asked for 100 noise sds too (SCALAR_FAR_SDS), where
    every path and docs/calibration.md ask for 5 of them."""
    sim = _scalar_sim()
    sd = float(np.std(sim.y, ddof=1))
    x = np.linspace(0.05, 0.95, 10)[:, None]
    y = np.sin(3 * x) + 0.25
    y[4] = sim.y.max() + 300 * sd
    obs = gpmsa.ObsData(x=x, y=y, precision=1 / (5 * sd) ** 2)
    texts = _outside(monkeypatch, sim, obs)
    assert len(texts) == 1
    assert texts[0].startswith("y_obs[4] = "), texts[0]
    assert " sds of the simulation outputs above every simulation run's value" in texts[0]
    y[4] = sim.y.max() + 20 * sd  # 4 of its noise sds, within the 100 output sds: unnamed
    assert _outside(monkeypatch, sim, gpmsa.ObsData(x=x, y=y, precision=1 / (5 * sd) ** 2)) == []
    y[4] = sim.y.max() + 300 * sd  # 3 of its noise sds of 100 output sds: its noise, unnamed
    assert _outside(monkeypatch, sim, gpmsa.ObsData(x=x, y=y, precision=1 / (100 * sd) ** 2)) == []
