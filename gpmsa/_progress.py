"""The progress bar of the library's long loops: tqdm (``tqdm.auto``) on stderr, shown only with
``progress=True``, as ``gpmsa.fit``'s; it never changes a result.

No bar starts a thread. tqdm starts a monitor thread ("tqdm_monitor") with its first bar, a
disabled one too, and keeps it running; a process that forks its chains' workers later
(``gpmsa.fit(..., n_chains=2)``) would fork beside it: on Python >= 3.12 a DeprecationWarning
("This process is multi-threaded, use of fork() may lead to deadlocks in the child") and a real,
if rare, deadlock where the thread holds tqdm's lock at the fork. Without ``progress`` no tqdm
object is made (`NoBar`); with it, a tqdm subclass whose ``monitor_interval`` is 0 (the monitor
only refreshes a bar that has waited over ``maxinterval``; these bars update at each step).
tqdm's own class, and the bars of the caller, are left as they are."""

from __future__ import annotations

import functools


class NoBar:
    """What `progress_bar` gives without ``progress``: the parts of a tqdm bar that the library
    uses (``update``, ``n``, ``total``, ``set_description``, ``close``, a context manager), doing
    nothing but count."""

    disable = True

    def __init__(self, total: int | None = None, initial: int = 0) -> None:
        self.total = total
        self.n = initial

    def update(self, n: int = 1) -> None:
        self.n += n

    def set_description(self, desc: str | None = None, refresh: bool = True) -> None:
        pass

    def close(self) -> None:
        pass

    def __enter__(self) -> NoBar:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


@functools.cache
def _bar_class():
    from tqdm.auto import tqdm  # imported when used, as before

    class Bar(tqdm):
        """tqdm.auto's bar without the monitor thread (see the module docstring)."""

        monitor_interval = 0

    return Bar


def progress_bar(
    progress: bool,
    total: int,
    desc: str | None,
    unit: str = "draw",
    *,
    mininterval: float = 0.5,
    initial: int = 0,
    leave: bool = True,
):
    """A tqdm bar of ``total`` steps described by ``desc`` (the call's name; None: none) when
    ``progress``, else a `NoBar`; use it as a context manager and ``update(1)`` per step.
    Neither starts a thread (see the module docstring). ``leave``: tqdm's (False: the bar is
    cleared when closed). Used by control's loops too (control may import gpmsa)."""
    if not progress:
        return NoBar(total, initial)
    return _bar_class()(total=total, desc=desc, unit=unit, mininterval=mininterval,
                        initial=initial, leave=leave)  # fmt: skip
