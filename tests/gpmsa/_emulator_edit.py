"""Tests' way round the Emulator's read-only attributes: a copy with some replaced, as an older
or hand-edited file could give, built as pickle rebuilds one (read-only again, digest fresh)."""

from __future__ import annotations

import gpmsa


def replaced(emu: gpmsa.Emulator, **attributes) -> gpmsa.Emulator:
    """A copy of ``emu`` with ``attributes`` (name -> value) in place of its own."""
    state = emu.__getstate__()
    state.update(attributes)
    state.pop("model_sha256", None)
    state.pop("_factors", None)
    out = object.__new__(gpmsa.Emulator)
    out.__setstate__({**state, "_factors": {}})
    return out
