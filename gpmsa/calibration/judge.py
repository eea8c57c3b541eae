"""A calibration run's draws, and the verdicts on them: convergence and the domain's bounds.

``calibrate.sample_calibration`` runs the chains and returns a `Run` (the draws and their
records, not yet a Posterior); ``gpmsa.calibrate`` then judges both: `judge_convergence` (R-hat
and ESS, ``info["diagnostics"]`` and ``info["convergence"]``, a ``ConvergenceWarning``) and
`judge_bounds` (``info["at_bound"]``, an ``AtBoundWarning``). A ``Calibrator``'s update judges
convergence with several chains only and the bounds never (one online chain: fast and silent).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gpmsa.calibration.posterior import Posterior
from gpmsa.mcmc.bounds import at_bound, warn_at_bound
from gpmsa.mcmc.diagnostics import convergence, summarize, warn_unconverged


class Run(NamedTuple):
    """A calibration's draws before their verdicts.

    ``samples``: name -> pooled kept draws (n_chains * n_kept,); ``chains``: name -> the kept
    draws per chain (n_chains, n_kept), the samplers' arrays past burn-in (the verdicts read
    these views: the Posterior's contiguous copies can sum differently in the last bit);
    ``info``: the run's record; ``held``: the posterior names held at known values;
    ``levels``: the names of categorical calibration parameters. Neither is judged."""

    samples: dict[str, np.ndarray]
    chains: dict[str, np.ndarray]
    info: dict
    held: tuple[str, ...] = ()
    levels: tuple[str, ...] = ()

    def posterior(self) -> Posterior:
        """The Posterior of these draws and their record (verdicts included, where given)."""
        return Posterior(self.samples, chains=self.chains, info=self.info)


def judge_convergence(run: Run, where: str, more: str = "") -> None:
    """Record ``run.info["diagnostics"]`` (each parameter's mean, sd, bulk ESS and rank-
    normalised R-hat: ``mcmc.diagnostics.summarize``) and ``["convergence"]`` (the verdict,
    held and categorical elements judged as ``convergence`` judges them) of the kept chains,
    and warn (``ConvergenceWarning``, naming ``where`` and ``n_samples``; ``more``: a further
    remedy) where they are flagged."""
    info, chains = run.info, run.chains
    info["diagnostics"] = summarize(chains)
    shapes = {k: v.shape[2:] for k, v in chains.items()}
    n_kept = next(iter(chains.values())).shape[1]
    info["convergence"] = convergence(info["diagnostics"], shapes, info["n_chains"], n_kept,
                                      held=set(run.held), levels=set(run.levels))  # fmt: skip
    warn_unconverged(info["convergence"], where, length="n_samples", more=more)


def judge_bounds(run: Run, t_names, t_min, t_max, where: str) -> None:
    """Record ``run.info["at_bound"]`` (``mcmc.bounds.at_bound``: each continuous, sampled
    calibration parameter whose draws pile up against a bound of the domain [``t_min``,
    ``t_max``], native units) and warn (``AtBoundWarning``, naming ``where``) for each."""
    skip = {*run.held, *run.levels}  # held and categorical elements: no such bound
    run.info["at_bound"] = at_bound(run.samples, t_names, t_min, t_max, skip)
    warn_at_bound(run.info["at_bound"], run.samples, t_names, t_min, t_max, where,
                  "Posterior.info['at_bound']")  # fmt: skip
