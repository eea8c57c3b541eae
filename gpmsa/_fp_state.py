"""numpy's floating-point error state inside gpmsa's public calls.

gpmsa computes densities and correlations whose far tails underflow to 0 (the exponential of a
very negative number, products of tiny masses), which numpy's default state ignores. A caller's
``np.seterr(under="raise")`` (or ``all="raise"``, set to catch bugs in their own code) made such
a call raise FloatingPointError from deep inside. The public entry points run with underflow
ignored (`underflow_as_zero`): their results are those of numpy's default state, and the
caller's state is as it was after the call (numpy >= 2 keeps it per thread and context, so
nested and concurrent calls each restore their own). Overflow, division by zero and invalid
operations keep the caller's handling: the library says where it expects them (``np.errstate``
at the site). A user's function that gpmsa calls (a constraint, ``log_prior``, a mean basis,
a Calibrator's ``prior``) runs in that state too: its own underflow is not raised there. The
wrapper is gpmsa's own, not numpy's ``errstate`` used as a decorator, whose
frame (numpy's) would end `gpmsa.errors.user_stacklevel`'s walk and point the library's
warnings at numpy instead of the caller's line."""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import TypeVar

import numpy as np

F = TypeVar("F", bound=Callable)


def underflow_as_zero(func: F) -> F:
    """``func`` run with numpy's underflow ignored (its default), whatever the caller set."""

    @functools.wraps(func)
    def run(*args, **kwargs):
        with np.errstate(under="ignore"):
            return func(*args, **kwargs)

    return run  # type: ignore[return-value]
