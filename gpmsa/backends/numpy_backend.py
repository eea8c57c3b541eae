"""The numpy reference backend: GPM/SA's Metropolis-within-Gibbs (see gpmsa.mcmc)."""

from __future__ import annotations

import numpy as np

from gpmsa import mcmc, tuning
from gpmsa.mcmc import Chains
from gpmsa.problem import Problem


def sample(
    problem: Problem,
    *,
    n_iter: int,
    n_chains: int = 1,
    tune: bool = True,
    step_widths: dict[str, np.ndarray] | None = None,
    seed=None,
    progress: bool = False,
    tune_rounds: int = tuning.N_BURN,
    tune_levels: int = tuning.N_LEVELS,
) -> Chains:
    """Draw ``n_iter`` sweeps per chain after GPM/SA step-size tuning (``tune=True``).

    ``tune_rounds`` x ``tune_levels`` tuning sweeps (default 50 x 20 = 1,000) precede the draws;
    ``step_widths`` (name -> widths) replace GPM/SA's initial widths. Draws hold every sweep
    (no burn-in removed). Chains run one after another, each from ``problem.init``.
    """
    return mcmc.sample(
        problem, n_iter=n_iter, n_chains=n_chains, tune=tune, step_widths=step_widths,
        seed=seed, progress=progress, tune_rounds=tune_rounds, tune_levels=tune_levels,
    )  # fmt: skip
