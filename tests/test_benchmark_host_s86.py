"""Every benchmark prints the host's load beside its timings through ``benchmarks/_host.py``,
which gives NaNs where the OS keeps no load average: ``os.getloadavg`` does not exist on
Windows, where 23 benchmarks ended in an AttributeError."""

import os
from pathlib import Path

from tests._examples import BENCHMARKS, load_benchmark


def test_no_benchmark_calls_getloadavg_itself():
    scripts = sorted(Path(BENCHMARKS).glob("*.py"))
    callers = [p.name for p in scripts if "getloadavg" in p.read_text(encoding="utf-8")]
    assert callers == ["_host.py"]


def test_the_load_reads_nan_without_getloadavg(monkeypatch):
    host = load_benchmark("_host")
    monkeypatch.setattr(os, "getloadavg", lambda: (0.5, 0.25, 0.125))
    assert host.load_average() == (0.5, 0.25, 0.125)
    monkeypatch.delattr(os, "getloadavg")
    assert all(x != x for x in host.load_average())
    speed = load_benchmark("roadgen_speed")  # one of the 23, whose load line then reads nan
    assert "nan" in speed.load()
