"""A Metropolis move along the nugget ridge of a one-component emulator (not in GPM/SA).

With one basis component (p_u = 1) and no observations, lamWs and lamWOs enter the likelihood
only through the nugget n = 1/(LamSim lamWOs) + 1/lamWs of Sigma_W, so their posterior is a
curved ridge along which GPM/SA's one-at-a-time updates crawl (integrated autocorrelation time
~100-200 sweeps on the road case, docs/performance.md). This move walks along the ridge with the
likelihood unchanged, at the cost of a few scalar operations:

In the coordinates (s, n), s = lamWs, the target density is pi(s, t(s, n)) |dt/dn| with
t = lamWOs = 1/(LamSim (n - 1/s)) and |dt/dn| = LamSim t^2. With n held, s' = s exp(h (u - 1/2))
(a symmetric walk on log s, Hastings factor s'/s) is accepted with probability

    min(1, g_s(s') g_t(t') t'^2 s' / (g_s(s) g_t(t) t^2 s)),

g the (bounded) Gamma prior densities: the likelihood cancels exactly. The move leaves the
posterior invariant; composed with GPM/SA's sweep it only adds mixing along the ridge.
"""

from __future__ import annotations

import math

from gpmsa.model.problem import Problem

WIDTH = 2.0
"""h: the width of the uniform walk on log lamWs (a factor of e^-1 to e^1)."""
N_MOVES = 5
"""Default moves per sweep where the move applies (each costs a few microseconds)."""
MAX_MOVES = 1000
"""Most moves per sweep (``ridge_moves``): beyond, the moves, not the sweep, take the time."""


def applies(problem: Problem) -> bool:
    """Whether the move leaves the likelihood unchanged: one component, no observations,
    lamWs and lamWOs both sampled."""
    sampled = problem.sampled
    return problem.obs is None and problem.p_u == 1 and "lamWs" in sampled and "lamWOs" in sampled


def proposal(s: float, t: float, lam_sim: float, u: float) -> float | None:
    """The (s', t') of a move from (s, t) with uniform u, or None off the ridge (s' <= 1/n)."""
    n = 1.0 / (lam_sim * t) + 1.0 / s
    s2 = s * math.exp(WIDTH * (u - 0.5))
    r = n - 1.0 / s2
    if r <= 0.0:
        return None
    return s2, 1.0 / (lam_sim * r)


def log_jacobian_ratio(s: float, t: float, s2: float, t2: float) -> float:
    """log(t'^2 s' / (t^2 s)): the change of coordinates and the log-scale walk's Hastings term."""
    return 2.0 * math.log(t2 / t) + math.log(s2 / s)
