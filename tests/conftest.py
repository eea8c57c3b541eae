"""Shared pytest configuration."""

import sys
from pathlib import Path

import pytest

DATA_DIR = Path(__file__).parent / "data"


@pytest.fixture
def data_dir() -> Path:
    """Folder of test data files copied into the project (never ../shared)."""
    return DATA_DIR


@pytest.fixture
def dask_client():
    """A dask.distributed client of two single-thread workers in this process (threads: a
    cluster of worker processes takes seconds to start); skipped without distributed."""
    distributed = pytest.importorskip(
        "distributed",
        reason='needs distributed: pip install "terrain-gpmsa[dask]" (the dask extra)',
    )
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        yield client


@pytest.fixture(autouse=True)
def _working_folder_restored():
    """Fail a test that leaves the working folder changed (use monkeypatch.chdir): later tests
    read files by paths relative to the repository root."""
    before = Path.cwd()
    yield
    after = Path.cwd()
    if after != before:
        import os

        os.chdir(before)
        pytest.fail(f"the test changed the working folder to {after} (use monkeypatch.chdir)")


@pytest.fixture(autouse=True)
def _trace_function_restored():
    """Fail a test that leaves another trace function (restore ``sys.gettrace()``'s, never
    None): coverage and debuggers trace through it, and a run under coverage lost every later
    test's lines to two tests that set None (session 84)."""
    before = sys.gettrace()
    yield
    if sys.gettrace() is not before:
        sys.settrace(before)
        pytest.fail("the test left another trace function (restore sys.gettrace()'s after)")


@pytest.fixture
def forks(monkeypatch):
    """The names of the threads started since the test began that run at each fork of this
    process (a bar made now starts a monitor of its own, even where an earlier test left one
    running): a test of the library's forks checks that no thread of its own runs at them."""
    import os
    import threading

    import tqdm.auto
    import tqdm.std

    for cls in {tqdm.std.tqdm, tqdm.auto.tqdm}:
        if "monitor" in vars(cls):
            monkeypatch.setattr(cls, "monitor", None)
    before = set(threading.enumerate())
    seen: list[list[str]] = []
    real_fork = os.fork

    def fork():
        seen.append(sorted(t.name for t in set(threading.enumerate()) - before))
        return real_fork()

    monkeypatch.setattr(os, "fork", fork)
    return seen
