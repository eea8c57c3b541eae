"""The numpy reference backend: GPM/SA's Metropolis-within-Gibbs, implemented in gpmsa.mcmc.sampler.

Its ``sample(problem, *, n_iter, n_chains=1, tune=True, step_widths=None, seed=None,
progress=False, tune_rounds=50, tune_levels=20) -> Chains`` is ``gpmsa.mcmc.sampler.sample``.
"""

from gpmsa.mcmc.sampler import sample

__all__ = ["sample"]
