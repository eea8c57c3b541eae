"""The Metropolis-Hastings test's log u for the numpy samplers (``log u < log ratio``)."""

from __future__ import annotations

import math


def log_uniform(u: float) -> float:
    """log u of a uniform draw u in [0, 1) (``numpy.random.Generator.random``): -inf for u = 0,
    which the generator draws with chance 2**-53 and where ``math.log`` raises "math domain
    error", ending the chain. Every u > 0 gives ``math.log(u)``: seeded chains are unchanged."""
    return math.log(u) if u > 0.0 else -math.inf
