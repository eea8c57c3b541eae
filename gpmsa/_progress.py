"""The progress bar of the library's long loops: tqdm (``tqdm.auto``) on stderr, shown only with
``progress=True``, as ``gpmsa.fit``'s; it never changes a result."""

from __future__ import annotations


def progress_bar(progress: bool, total: int, desc: str, unit: str = "draw"):
    """A tqdm bar of ``total`` steps described by ``desc`` (the call's name), off unless
    ``progress``; use it as a context manager and ``update(1)`` per step."""
    from tqdm.auto import tqdm  # imported when used, as the samplers import it

    return tqdm(total=total, desc=desc, unit=unit, disable=not progress, mininterval=0.5)
