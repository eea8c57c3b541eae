"""``gpmsa.fit``: fit the GPM/SA emulator (optionally jointly with observations) by MCMC."""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import replace
from datetime import datetime, timezone

import numpy as np

from gpmsa import backends
from gpmsa._fp_state import underflow_as_zero
from gpmsa.errors import GPMSAError, NuggetWarning, user_stacklevel
from gpmsa.fitting.continuation import (
    HOT_RECORD,
    MH_BACKENDS,
    appended_record,
    appended_thin,
    check_append,
    check_same_scales,
    component_order,
    continued_copies,
    continued_ladder,
    continued_starts,
    continued_steps,
    continued_widths,
    pool_accept,
    pool_draws,
    resumes_copies,
)
from gpmsa.fitting.emulator import EMULATOR_PARAMS, Emulator, check_metadata
from gpmsa.fitting.validation import MAX_HOT_VALUES
from gpmsa.limits import check_memory
from gpmsa.mcmc import level_moves, tempering
from gpmsa.mcmc.bounds import at_bound, warn_at_bound
from gpmsa.mcmc.diagnostics import convergence, summarize, warn_unconverged
from gpmsa.mcmc.parallel import in_this_process
from gpmsa.mcmc.sampler import (
    draws_nbytes,
    parameter_elements,
    sweeps_nbytes,
)
from gpmsa.mcmc.starts import check_init
from gpmsa.model import constraints, kronecker, nugget
from gpmsa.model import fixed_elements as per_element
from gpmsa.model.basis import describe_discrepancy, discrepancy_kind
from gpmsa.model.data import ObsData, SimData, check_count, check_flag, run_seed
from gpmsa.model.discrepancy import kept_bases, scale_record
from gpmsa.model.discrepancy import record as discrepancy_record
from gpmsa.model.far_values import far_run, joint_far_value, warn_far, warn_far_run
from gpmsa.model.priors import Priors
from gpmsa.model.problem import Problem, fixed_record, prepare

N_KEEP = 1000
"""Default number of retained draws (all chains together) after burn-in and thinning."""


def _factor_nbytes(m: int, p: int, q: int, p_u: int) -> float:
    """Bytes of the likelihood's covariances and factors: (p + q + 4 p_u + 2) m^2 floats."""
    return 8.0 * m * m * (p + q + 4 * p_u + 2)


def _check_fit_memory(
    problem, n_iter: int, n_chains: int, pooled: int = 0, copies: int = 1
) -> None:
    """Refuse (before sampling) a fit whose draws or factorisations exceed the memory limit:
    every sweep of every chain is stored (n_chains x n_iter x parameter elements, kept twice
    while the chains are stacked), and the likelihood keeps O((p + q + 4 p_u) m^2) floats,
    ``copies`` times (parallel tempering: one likelihood state per temperature); ``pooled``:
    the retained draws of an appended fit (``append=True``), source's and its own, held three
    times (the parts, the pooled arrays, the emulator's read-only copies)."""
    m = problem.m
    sep = problem.separable  # a separable design's likelihood keeps its factors alone
    nbytes = draws_nbytes(problem, n_iter, n_chains) + copies * (
        _factor_nbytes(m, problem.p, problem.q, problem.p_u)
        if sep is None
        else kronecker.fit_nbytes(sep, problem.p_u)
    )
    nbytes += 1.5 * sweeps_nbytes(parameter_elements(problem), pooled, 1)
    what = f" appending to {pooled} retained draws" if pooled else ""
    what += f" at {copies} temperatures" if copies > 1 else ""
    check_memory(nbytes, f"fit(n_iter={n_iter}, n_chains={n_chains}) of {m} runs x "
                 f"{parameter_elements(problem)} parameter elements{what}")  # fmt: skip


def simulation_fit_nbytes(
    m: int, p: int, q: int, p_u: int, n_iter: int, n_chains: int = 1
) -> float:
    """Bytes that `fit` checks against ``gpmsa.limits.MAX_MEMORY_BYTES`` for a simulation-only
    fit (no observations, default parameters) of ``m`` runs, ``p`` known inputs, ``q``
    parameters and ``p_u`` components: the same figure as for the prepared problem, for a
    caller that plans a design before its runs exist. The stored sweeps hold betaU
    ((p + q) x p_u), lamUz and lamWs (p_u each) and lamWOs."""
    elements = (p + q + 2) * p_u + 1
    return sweeps_nbytes(elements, n_iter, n_chains) + _factor_nbytes(m, p, q, p_u)


@underflow_as_zero
def fit(
    data: SimData,
    obs: ObsData | None = None,
    n_iter: int = 30_000,
    tune: bool | None = None,
    n_chains: int = 1,
    backend: str = "numpy",
    seed=None,
    progress: bool = False,
    priors: Priors | None = None,
    *,
    n_burn: int | None = None,
    n_keep: int | None = None,
    point: str = "mean",
    n_pc: int | float | None = None,
    basis=None,
    discrepancy=None,
    discrepancy_groups=None,
    step_widths: dict | None = None,
    metadata: dict | None = None,
    n_jobs: int | None = None,
    executor=None,
    mean_basis=None,
    fixed: dict | None = None,
    constraint=None,
    theta_init=None,
    append: bool = False,
    **options,
) -> Emulator:
    """Fit the emulator by GPM/SA's Metropolis-within-Gibbs; returns an ``Emulator``.

    data: the simulation runs (a run whose value lies far beyond every other run's at an output
    point, such as a -999 missing-value code, draws a ``gpmsa.OutlierRunWarning`` before the
    sampling: docs/internals.md). obs: field data for GPM/SA's classic joint calibration (theta and
    lamOs are sampled together with the emulator; the draws land in ``Emulator.calibration``;
    a ``gpmsa.AtBoundWarning`` where theta's piles up against a bound of the domain, as
    ``gpmsa.calibrate`` warns).
    n_iter: sweeps per chain after step-size tuning (``tune``: 50 rounds x 20 levels, 1,000
    sweeps whatever ``n_iter``: a sweep's cost grows as m^3, ~0.06 s at m = 1,000 runs and
    ~0.35 s at 2,000 on a 2-core machine, so tuning alone takes 1 and 6 minutes there;
    ``progress=True`` shows it; None: tune, but for a continuation (``init`` a numpy or torch
    fit's emulator, no ``step_widths``), which runs on with the widths its chains were tuned
    to, as SEPIA's second ``do_mcmc``; True tunes again from GPM/SA's widths). An untuned
    continuation steps the precisions as the chains it continues did (``continued_steps``:
    uniformly with the tuned widths after tuning, as SEPIA, else GPM/SA's proportional step),
    unless ``proportional_steps`` (a numpy and torch option) is given; settings record it.
    n_burn: sweeps discarded per chain (default n_iter // 5; 0 when ``init`` is an emulator whose
    chains continue). n_keep: retained draws in all (evenly thinned; None: 1,000, ``N_KEEP``).
    append: with ``init`` an emulator, return its retained draws followed, chain by chain, by
    this continuation's, thinned by its step (``settings["thin"]``: the continuation keeps its
    sweeps thin, 2 thin, ... after each chain's last kept draw, so each pooled chain is evenly
    spaced in sweeps), as SEPIA's second ``do_mcmc`` and GPM/SA's ``gpmmcmc(pout, n)``; point
    estimate, diagnostics and convergence over the pooled retained draws; settings
    "appended_to" (the source's ``model_sha256``), "appended_after" (its draws per chain),
    "pooled_sweeps" and "sweeps_run" (per chain, after burn-in and in all). It refuses (naming
    the argument) n_burn > 0, tuning (numpy, torch), an n_keep other than the draws the step
    keeps, and ``init`` not an emulator (a tempered continuation may tune its copies: see
    parallel tempering below). point: "mean" (posterior mean, default) or "map" (the
    draw of highest log posterior) for ``Emulator.params``. n_pc: basis size, or a variance
    fraction in (0, 1) (SEPIA's n_pc < 1; default 99.5%). basis: instead of the runs' PCA, a
    given basis (l_sim, p_u), columns the orthogonal basis vectors on the simulation grid in
    standardised output units (GPM/SA's ``Ksim``; ``gpmsa.BasisWarning`` when its weights'
    scale is not the one lamUz's prior expects; docs/categorical-and-constraints.md).
    discrepancy: None, "constant", "linear", an (l_obs, p_v) array on the grid every
    experiment shares, or a list of one (l_j, p_v) array per experiment on its own index grid
    (SEPIA's ``create_D_basis(D_obs=[...])``, GPM/SA's per-experiment ``Dobs``; normalised
    jointly, ``gpmsa.model.basis.discrepancy_bases``; kept in ``Emulator.discrepancy_bases`` and
    the file; an array's or list's normalising divisor in settings["discrepancy_scale"]).
    discrepancy_groups: the
    precision group (0 .. G-1) of each discrepancy basis vector, GPM/SA's lamVzGroup (None: one
    group; each group has its own betaV column and lamVz). n_jobs, executor: where
    the chains run (numpy backend: ``n_jobs`` worker processes, None or -1 = every CPU but never
    more than the chains; or any ``concurrent.futures.Executor`` / dask ``Client``); the draws
    are the same wherever they run. seed: an integer, a numpy Generator or None (fresh
    entropy); the integer the fit ran with is ``settings["seed"]``, and ``fit(..., seed=that)``
    repeats it. priors: a ``gpmsa.Priors`` (None: GPM/SA's, ``Priors()``; the data
    corrections are added here). metadata: a JSON-able dict kept in ``Emulator.metadata``
    and the file. backend: "numpy" (default), "torch", "pyro" or a plug-in's name
    (``gpmsa.backends.register``). options: passed to the backend's ``sample`` (e.g.
    ``init``: a rule of ``gpmsa.mcmc.starts``, or an Emulator of this fit, whose chains then
    continue from their last kept draws: ``fit(data, n_iter=..., n_chains=emu's, init=emu)``,
    see ``continued_starts``).

    Beyond GPM/SA's model (numpy backend; docs/categorical-and-constraints.md): categorical
    inputs are declared in ``SimData`` (a categorical theta of a joint fit is sampled over its
    levels, uniform prior). mean_basis: None (zero mean, GPM/SA), "constant",
    "linear" or a callable of unit-scale [x, t] (n, p + q) -> (n, k), called on a copy and
    again at every prediction, so a deterministic function of each row (one using random
    numbers or state gives predictions that change from call to call); its coefficients are
    integrated out (flat prior). fixed: name -> value held fixed (model scales as
    ``Emulator.params``; theta in native units), e.g. ``{"lamWOs": 1e5 - 1}``: a scalar or an
    array of the parameter's shape holds the whole array; a dict element index -> value holds
    those elements and samples the others (SEPIA's per-element fixing; every backend: pyro
    samples a site of the free elements), e.g. ``{"lamVz": {1: 1e6}}`` (group 1's discrepancy
    switched off), ``{"betaU": {(2, 0): 0.5}}``. Indices count from 0: an int for a 1-D
    parameter (theta also by t_name); a tuple (i, j) for betaU (p + q, p_u) and betaV (p, G),
    where an int i means (i, 0) only if there is one column (``gpmsa.model.fixed_elements``);
    naming every element equals fixing the whole array. constraint (joint fit only): a
    callable of native theta (q,) -> bool, False where theta is not allowed (zero prior mass
    there). theta_init: the chains' start of theta (native, (q,) or a dict by t_names; default
    the centre; a categorical element: one of its levels): the start of ``init="gpmsa"``, one
    chain's default; the dispersed starts of several chains (``init`` "auto", "jitter") and
    ``init="prior"`` draw theta instead (``init="gpmsa"`` starts every chain at theta_init);
    refused with ``init`` an emulator, whose chains continue from their last kept draws.
    Tuning options (``tune_rounds``, ``tune_levels``; torch ``tune_stages``; pyro
    ``n_warmup``, ``target_accept``) act only where the chains tune: a run with ``tune`` False
    (or None resolved to False, an untuned continuation) takes them without effect, so that
    a continuation loop may pass the same options on every call.

    Parallel tempering (numpy and torch options ``temperatures`` and ``swap_every``; off by default,
    and then the draws are the plain sampler's, bit for bit): for a posterior with several modes
    that the one-element steps do not cross (a ConvergenceWarning whose chains lie apart, log
    posteriors tens apart). ``temperatures``: an integer n (the ladder T = 2**k, k = 0 .. n - 1; 1:
    no tempering) or a ladder (1, T_1, ...), strictly increasing from 1; each chain then runs a copy
    per temperature, its likelihood raised to 1/T (priors untempered), each copy tuned at its
    temperature; neighbouring copies propose to swap states every ``swap_every`` (1) sweeps, and
    only the T = 1 copy's draws are kept. It costs about one sweep per copy (n times the time,
    memory for n likelihood states). ``settings`` record "temperatures", "swap_every" and
    "swap_rate" (per chain, per neighbour pair): rates near 0 say the ladder is too sparse, the
    hottest copy should cross between the modes (a barrier of 50 in log posterior needs T_max of
    tens). torch: the batch holds every chain's copies (n_chains x n rows); with ``chain_groups`` >
    1 each group holds whole chains with all their copies (tuning in one batch). Refused on the pyro
    backend (docs/internals.md, "Parallel tempering"). A continuation (``init`` an emulator) of a
    tempered fit runs on tempered, at its ladder (each chain's where they adapted theirs) and
    ``swap_every`` unless ``temperatures=`` is given (``temperatures=None`` given, or 1:
    untempered); a plain fit's with ``temperatures=`` at that ladder. A numpy or torch tempered fit
    records each hot copy's last state and widths (settings "hot_states", "hot_step_widths"), and
    its continuation at that ladder (either backend's) resumes every copy where it stopped,
    untuned (``tune`` None or False; torch: each copy at the median of its chains' widths), the
    T = 1 copy at the chain's last kept draw: no warm-up. Otherwise (no such record, another
    ladder, ``tune=True``, ``step_widths=`` or ``adapt_ladder=True``)
    every copy of a chain starts at the chain's last kept state, from its recorded widths, and
    is tuned at its temperature (the copies warming up, swapping: ``tune_rounds`` x
    ``tune_levels`` sweeps per copy) before any draw is kept; ``tune=False`` is refused there,
    and ``append=True`` pools as a plain append (the warm-up between the parts). numpy and
    torch option ``adapt_ladder=True`` (off by default; with ``temperatures``, at least 3, and
    ``tune``): each chain adapts its ladder's temperatures between 1 and the hottest during
    tuning towards equal swap rates, then freezes it before the widths' tuning and the draws (an
    exact MCMC; about ``tune_rounds`` x ``tune_levels`` more sweeps per copy; torch: after the
    first stage's warm-up, each chain from its own swaps); ``settings["adapted_temperatures"]``
    (per chain) records it, "temperatures" the ladder it started from.

    A categorical theta of a joint fit moves levels jointly with the continuous theta
    (``gpmsa.mcmc.level_moves``): ``settings["level_offsets"]`` records, per categorical name,
    its "levels", the "shifted" elements and per chain their conditional "modes" at each level
    (native units; the move from level a to b shifts them by modes[b] - modes[a]).

    The rank-normalised R-hat and bulk ESS of every sampled parameter are stored in
    ``Emulator.convergence`` (and the file), and a ``gpmsa.ConvergenceWarning`` names each
    parameter with R-hat > 1.01 or ESS < 100; one chain (the default) is judged by its split
    R-hat, which compares the chain's halves (the warning then advises a longer chain or
    ``n_chains >= 2``, which can show whether independent chains agree). A chain that fails or
    produces non-finite draws raises ``gpmsa.ChainError`` naming it. In a daemonic worker (e.g.
    a dask task's), which may not start processes, n_jobs None or -1 runs the chains in it.
    """
    n_iter, n_chains = check_count(n_iter, "n_iter", 2), check_count(n_chains, "n_chains")
    continuing = isinstance(options.get("init"), Emulator)  # its chains start past burn-in
    if isinstance(options.get("init"), str | os.PathLike):  # a rule (a file name: say how)
        check_init(options["init"], n_chains, "gpmsa.load")
    append = check_append(append, options.get("init"), n_burn)
    if continuing and theta_init is not None:  # the chains start at their last kept draws
        raise GPMSAError(
            "theta_init= sets a fresh chain's start; init=emulator's chains continue from their "
            "last kept draws, so it would have no effect: leave theta_init out (or start "
            "afresh without init=emulator)"
        )
    default_burn = 0 if continuing else n_iter // 5
    n_burn = default_burn if n_burn is None else check_count(n_burn, "n_burn", 0, n_iter - 1)
    check_point(point)
    thin = None  # append: the source's step
    if append:
        thin = appended_thin(options["init"], int(n_iter), int(n_chains), n_keep)
    n_keep = check_keep(N_KEEP if n_keep is None else n_keep, n_chains)
    tune = None if tune is None else check_flag(tune, "tune")
    progress = check_flag(progress, "progress")
    metadata = check_metadata(metadata)
    if obs is None and discrepancy is not None:
        given = describe_discrepancy(discrepancy)
        raise GPMSAError(
            f"discrepancy={given} needs observations (obs=): a discrepancy is fitted with the "
            "field data, and a simulator-only fit has none"
        )
    seed = run_seed(seed)
    temps = _check_tempering(options, backend)
    if continuing and backend in MH_BACKENDS:  # the source's ladder unless temperatures= given
        temps = continued_ladder(options["init"], options, int(n_chains), temps)
    resume = (continuing and backend in MH_BACKENDS and temps is not None and tune is not True
              and step_widths is None
              and resumes_copies(options["init"].settings or {}, options,
                                 int(n_chains)))  # fmt: skip
    if continuing and temps is not None and tune is False and not resume:
        raise GPMSAError(
            "tune=False with a tempered continuation (temperatures=, or init=emulator a tempered "
            "fit) that does not resume its hot copies (a numpy or torch fit at the source's "
            "ladder, whose record holds them, settings 'hot_states'): every copy is tuned at its "
            "temperature (from the T = 1 copy's widths) while the copies warm up from the "
            "chain's last state, before any draw is kept; leave tune out (or tune=True: from "
            "GPM/SA's widths), or pass temperatures=None to continue without tempering"
        )
    if isinstance(data, SimData) and data.separable is not None and backend != "numpy":
        kronecker.refuse(f"backend={backend!r}")
    backends.get(backend)  # unknown or not installed: a clear error before any work
    prep = prepare(data, obs, priors=priors, n_pc=n_pc, discrepancy=discrepancy,
                   mean_basis=mean_basis, discrepancy_groups=discrepancy_groups,
                   basis=basis)  # fmt: skip
    problem = _model_options(prep, data, fixed, constraint, theta_init)
    pooled = options["init"].n_draws + int(n_chains) * (n_iter // thin) if append else 0
    _check_fit_memory(problem, int(n_iter), int(n_chains), pooled,
                      1 if temps is None else len(temps))  # fmt: skip
    reserved = ("n_iter", "n_chains", "tune", "step_widths", "seed", "progress", "n_jobs",
                "executor")  # fmt: skip
    backends.check_options(backend, options, reserved, "fit")
    if backend == "numpy":  # (torch's sample keeps its callables here; pyro runs here)
        n_jobs, executor = in_this_process(problem.callables, n_jobs, executor, int(n_chains))
    options.update(backends.placement(backend, n_jobs, executor))
    resumed, recorded, order = options.get("init"), None, None
    if continuing:  # order: K's columns among the source's (per-component parameters follow)
        check_same_scales(resumed, data, prep.standardizer)
        options["init"] = continued_starts(resumed, problem, prep.K, obs, int(n_chains))
        order = component_order(resumed, problem)
        if step_widths is None and tune is not True and backend != "pyro":  # NUTS adapts
            step_widths = recorded = continued_widths(resumed, problem, int(n_chains), order)
        if resume:  # every hot copy where it stopped, with its widths
            options["hot_copies"] = continued_copies(resumed, problem, int(n_chains),
                                                     options["temperatures"], order)  # fmt: skip
    if tune is None:  # only the widths the chains were tuned to run on untuned
        # tempered: every copy tuned, warmed up, unless each resumes where it stopped
        tune = recorded is None or (temps is not None and not resume)
    if append and tune and backend in MH_BACKENDS and temps is None:
        raise GPMSAError(
            "append=True pools the chains' draws evenly spaced in sweeps; tuning (tune=True, "
            "or tune=None where init=emulator records no Metropolis step widths) would run "
            "1,000 sweeps between the source's and the continuation's: pass tune=False (and "
            "step_widths= to choose the widths)"
        )
    steps = None  # the precisions' steps as the chains it continues (SEPIA: once tuned, always;
    # pyro's NUTS has none)
    if continuing and not tune and backend in MH_BACKENDS and "proportional_steps" not in options:
        steps = continued_steps(resumed)
    outlier = far_run(data, prep.standardizer.grid)
    if outlier is not None:  # before the long sampling, which the user may then stop
        warn_far_run(outlier, user_stacklevel())
    far = None if obs is None else joint_far_value(data, obs, prep.standardizer)
    if far is not None:  # before the long sampling, which the user may then stop
        warn_far(far, user_stacklevel(), discrepancy=discrepancy is not None)
    chains = backends.sample(
        backend, problem, n_iter=int(n_iter), n_chains=int(n_chains), tune=tune,
        step_widths=step_widths, seed=seed, progress=progress, **options,
        **({} if steps is None else {"proportional_steps": steps}),
    )  # fmt: skip
    chains.check_finite()
    kept = n_iter - n_burn
    first = 0  # append: sweep thin - 1 lies thin sweeps after the source's last kept draw
    if append:
        first = thin - 1
    else:
        thin = thinning(n_chains, kept, n_keep)  # each chain keeps ceil(kept / thin)
    # float64 whatever the backend sampled in (torch float32), a fixed parameter exactly at its
    # value
    post = {k: np.asarray(v[:, n_burn:], dtype=float) for k, v in chains.draws.items()}
    for k, mask in problem.held_masks(post).items():
        post[k][:, :, mask] = problem.init[k][mask]
    lp = chains.log_post[:, n_burn:]
    lp_kept = lp[:, first::thin].reshape(-1)
    n_kept = lp_kept.size  # explicit: an empty parameter (betaV when p = 0) has no -1 to infer
    retained = {k: v[:, first::thin].reshape(n_kept, *v.shape[2:]) for k, v in post.items()}
    calibration = None
    if obs is not None:
        calibration = {k: v for k, v in retained.items() if k not in EMULATOR_PARAMS}
        native = prep.standardizer.t_from_unit(calibration["theta"])
        for k, lv in enumerate(problem.theta_levels or ()):
            if lv is not None:  # categorical draws: exactly the level codes
                native[..., k] = np.round(native[..., k])
        for k, v in fit_held_native(problem, fixed, data.t_names).items():
            native[:, k] = v  # exactly the value given (as gpmsa.calibrate)
        calibration["theta_native"] = native
    if append:
        retained, lp_kept, calibration = pool_draws(
            resumed, retained, lp_kept, calibration, int(n_chains), order
        )
    params = point_estimate(retained, lp_kept, point)
    settings = {
        "n_iter": int(n_iter), "n_burn": n_burn, "thin": thin, "n_chains": int(n_chains),
        "tune": bool(tune), "backend": backend, "seed": seed, "point": point,
        "proportional_steps": chains.info.get("proportional_steps"),  # None: NUTS (pyro)
        "n_pc": int(prep.K.shape[1]), "basis": "pca" if basis is None else "given",
        "joint_obs": obs is not None,
        "obs_lengths": None if obs is None else [int(e.size) for e in obs.experiments],
        "obs_sha256": None if obs is None else obs.digest(),
        "discrepancy": discrepancy_kind(discrepancy),
        "init": chains.info.get("init", "gpmsa"),
        **({"continued_from": resumed.model_sha256} if continuing else {}),
        **(appended_record(resumed, int(n_iter), int(n_chains)) if append else {}),
        # n_jobs and executor say where the chains ran, not what they were: not recorded
        "backend_options": backends.recorded_options(
            {k: v for k, v in options.items() if k not in ("n_jobs", "executor")}
        ),
        "mean_basis": None if problem.mean_basis is None else problem.mean_basis.kind,
        "fixed": fixed_record(problem),
        "constraint": constraint is not None,
        "step_widths": {k: v.tolist() for k, v in chains.step_widths.items()},
        **({} if temps is None else tempering_record(chains.info, resumed)),
        **({} if "level_offsets" not in chains.info else {  # a categorical theta's level move
            "level_offsets": level_moves.native_record(
                chains.info["level_offsets"], data.t_names, prep.standardizer.t_min,
                prep.standardizer.t_max, tuple(data.levels)[len(data.x_names):])}),
        "fitted_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "versions": backends.recorded_versions(backend),
    }  # fmt: skip
    if obs is not None and discrepancy is not None:  # full_prediction refuses another basis
        source = (resumed.settings or {}) if continuing else None  # keeps its scale
        settings.update(discrepancy_record(problem.obs), **scale_record(discrepancy, source))
    if append:  # the source's sweeps are gone: its retained draws and these, as pooled
        per = lp_kept.size // n_chains
        summary = summarize({k: v.reshape(n_chains, per, *v.shape[1:])
                             for k, v in retained.items()})  # fmt: skip
        pool_accept(summary, resumed, chains.accept_rate, int(n_iter), backend, order)
    else:
        per = kept
        summary = summarize(post, chains.accept_rate)
    record = sampled_convergence(problem, summary, n_chains, per)  # one chain: split R-hat
    how = more_advice(append, settings)
    warn_unconverged(record, f"gpmsa.fit (backend {backend!r})", more=f", or {how}",
                     names=element_names(data.x_names, data.t_names,
                                         problem.init["betaU"].shape[1]))  # fmt: skip
    if calibration is not None:  # theta's posterior piled against its domain's bound
        draws = dict(zip(data.t_names, np.moveaxis(calibration["theta_native"], -1, 0),
                         strict=True))  # fmt: skip
        levels = problem.theta_levels or [None] * len(data.t_names)  # None: none categorical
        skip = {name for name, lv in zip(data.t_names, levels, strict=True) if lv is not None}
        skip |= {data.t_names[k] for k in fit_held_native(problem, fixed, data.t_names)}
        std = prep.standardizer
        found = at_bound(draws, data.t_names, std.t_min, std.t_max, skip)
        warn_at_bound(found, draws, data.t_names, std.t_min, std.t_max,
                      f"gpmsa.fit (backend {backend!r}, joint calibration)",
                      "gpmsa.calibration_posterior(emulator).info['at_bound']")  # fmt: skip
    if problem.separable is None:  # a point estimate that cannot factor: said here, not later
        bad = nugget.failing_component(problem.zt, params, problem.lam_sim, problem.categorical)
        if bad is not None:
            where = f"at the fit's point estimate (point={point!r})"
            warnings.warn(
                nugget.not_positive_definite(bad, params, problem.lam_sim, problem.m, where)
                + ". predict, loo, calibrate, Calibrator, cross_validate and sensitivity refuse "
                "this emulator",
                NuggetWarning, stacklevel=user_stacklevel(),
            )  # fmt: skip
    return Emulator._from_prepared(
        data, prep, params,
        draws={k: retained[k] for k in EMULATOR_PARAMS}, log_post=lp_kept,
        metadata=metadata, settings=settings,
        diagnostics=summary, calibration=calibration, convergence=record,
        discrepancy_bases=kept_bases(problem.obs, discrepancy),
    )  # fmt: skip


def tempering_record(info: dict, source: Emulator | None) -> dict:
    """The settings of a tempered fit from its sampler's ``info``: "temperatures" (the ladder it
    started from), "swap_every", "swap_rate" (per chain, per neighbour pair) and, where the
    chains adapted their ladders (``adapt_ladder``) or continued ``source``'s adapted ones
    (each chain at its own: "temperatures" then the source's), "adapted_temperatures" (per
    chain, frozen for the draws); the hot copies' last states and widths (``HOT_RECORD``;
    numpy, torch) where they hold at most ``MAX_HOT_VALUES`` numbers."""
    out = {"temperatures": np.asarray(info["temperatures"]).tolist(),
           "swap_every": int(info["swap_every"]),
           "swap_rate": np.asarray(info["swap_rate"]).tolist()}  # fmt: skip
    if "adapted_temperatures" in info:  # per chain, frozen
        out["adapted_temperatures"] = np.asarray(info["adapted_temperatures"]).tolist()
    hot = [{k: np.asarray(v) for k, v in info[key].items()} for key in HOT_RECORD if key in info]
    if hot and sum(v.size for h in hot for v in h.values()) <= MAX_HOT_VALUES:  # numpy, torch
        for key, record in zip(HOT_RECORD, hot, strict=True):  # each hot copy's last state and
            out[key] = {k: v.tolist() for k, v in record.items()}  # widths, to resume from
    return tempering.recorded_ladders(out, source.settings if source is not None else {})


def element_names(x_names, t_names, n_pc: int) -> dict[str, str]:
    """The inputs a fit's elements stand for, as a ConvergenceWarning shows them: "theta[i]"
    the i-th calibration parameter, "betaU[i,j]" the i-th input of x then theta (of each of the
    ``n_pc`` components j)."""
    inputs = [str(n) for n in (*x_names, *t_names)]
    out = {f"theta[{i}]": str(n) for i, n in enumerate(t_names)}
    out.update({f"betaU[{i},{j}]": n for i, n in enumerate(inputs) for j in range(n_pc)})
    return out


def more_advice(append: bool, settings: dict) -> str:
    """The call a ConvergenceWarning of ``fit`` advises to run the chains on: a continuation
    (``append``: appended), for a tempered fit (its ``settings``) at its ladder, which such a
    continuation takes by default (each chain's adapted one where they adapted them)."""
    how = "append more: gpmsa.fit(..., init=the returned emulator, append=True"
    if not append:
        how = "continue these: gpmsa.fit(..., init=the returned emulator"
    temps = settings.get("temperatures")
    if temps is None:
        return how + ")"
    every = settings.get("swap_every", 1)
    every = f", swap_every={every}" if every != 1 else ""
    if "adapted_temperatures" in settings:
        return (
            f"{how}{every}), tempered as these chains ran: by default at each chain's "
            "adapted ladder (settings['adapted_temperatures']; temperatures= gives another)"
        )
    ladder = ", ".join(f"{t:g}" if float(f"{t:g}") == t else repr(t) for t in temps)
    return f"{how}, temperatures=[{ladder}]{every}), tempered as these chains ran"


def _check_tempering(options: dict, backend: str):
    """The ladder of ``fit``'s ``temperatures`` option (``tempering.ladder``; None: off).
    GPMSAError naming ``temperatures``/``swap_every``/``adapt_ladder`` given to another backend
    than numpy or torch (``backends.check_tempering``)."""
    backends.check_tempering(backend, options)
    return tempering.ladder(options.get("temperatures"))


def check_keep(n_keep, n_chains: int) -> int:
    """``n_keep`` checked: an integer >= 1 and at least ``n_chains`` (every chain keeps a draw);
    GPMSAError otherwise."""
    n_keep = check_count(n_keep, "n_keep")
    if n_keep < n_chains:
        raise GPMSAError(
            f"n_keep={n_keep} is fewer than n_chains={n_chains}: every chain keeps a draw"
        )
    return n_keep


def sampled_convergence(
    problem: Problem, summary: dict, n_chains: int, per: int, skip: tuple[str, ...] = ()
) -> dict:
    """`convergence` record of every parameter ``problem`` sampled but ``skip``, its held
    elements (``fixed=``) excepted, over ``n_chains`` chains of ``per`` draws each."""
    shapes = {k: problem.init[k].shape for k in problem.sampled if k not in skip}
    held = {per_element.label(k, i) for k, v in problem.fixed_elements.items() for i in v}
    levels = {f"theta[{k}]" for k, lv in enumerate(problem.theta_levels or ()) if lv is not None}
    return convergence(summary, shapes, n_chains, per, held=held, levels=levels)


def thinning(n_chains: int, kept: int, n_keep: int) -> int:
    """The smallest thinning step at which ``n_chains`` chains of ``kept`` sweeps each keep at
    most ``n_keep`` draws in all (a chain keeps ceil(kept / thin) of its sweeps)."""
    thin = max(1, math.ceil(n_chains * kept / n_keep))
    while n_chains * math.ceil(kept / thin) > n_keep:
        thin += 1
    return thin


def point_estimate(draws: dict[str, np.ndarray], log_post: np.ndarray, point: str) -> dict:
    """The emulator parameters' point estimate from their retained draws (n, *shape) and log
    posteriors (n,): "mean" each element's mean within its draws' range (a parameter that never
    moved keeps its value exactly: the mean of equal floats can round past it), "map" the draw
    of the highest log posterior."""
    if point == "mean":
        return {k: np.clip(draws[k].mean(axis=0), draws[k].min(axis=0), draws[k].max(axis=0))
                for k in EMULATOR_PARAMS}  # fmt: skip
    best = int(np.argmax(log_post))
    return {k: np.array(draws[k][best], dtype=float) for k in EMULATOR_PARAMS}


def check_point(point) -> None:
    """GPMSAError unless ``point`` is "mean" or "map" (the point estimate of ``fit``)."""
    if not (isinstance(point, str) and point in ("mean", "map")):
        raise GPMSAError(f"point must be 'mean' or 'map', got {point!r}")


def _check_levels(problem: Problem, theta_unit: np.ndarray, names, what: str) -> None:
    """GPMSAError when a categorical element of ``theta_unit`` is not one of its levels."""
    for k, lv in enumerate(problem.theta_levels or ()):
        if lv is not None and not np.any(np.isclose(lv, theta_unit[k], rtol=0, atol=1e-12)):
            raise GPMSAError(f"{what}: categorical calibration parameter {names[k]} must be one "
                             "of its training levels")  # fmt: skip


def _model_options(prep, data: SimData, fixed, constraint, theta_init) -> Problem:
    """``prep.problem`` with the theta constraint, theta's start and the fixed parameters."""
    problem = prep.problem
    std = prep.standardizer
    if (constraint is not None or theta_init is not None) and problem.obs is None:
        raise GPMSAError("constraint= and theta_init= apply to theta: they need obs= (a joint fit)")
    if constraint is not None:
        categorical = [lv is not None for lv in problem.theta_levels or ()]
        problem = replace(problem, constraint=constraints.make(
            constraint, std.t_min, std.t_max, data.t_names, categorical))  # fmt: skip
    levels = problem.theta_levels
    closed = None if levels is None else [lv is not None for lv in levels]
    start = constraints.theta_init_unit(theta_init, std.t_min, std.t_max, data.t_names, closed)
    if start is not None:
        _check_levels(problem, start, data.t_names, "theta_init")
        problem = problem.with_init({"theta": start})
    return problem if fixed is None else hold_fixed(problem, fixed, std, data.t_names)


def hold_fixed(problem: Problem, fixed, standardizer, t_names) -> Problem:
    """``problem`` holding ``fit``'s ``fixed=`` (name -> value; theta in native units, put on
    the unit scale where the problem has theta, a joint fit); GPMSAError for a non-dict."""
    if not isinstance(fixed, dict):
        raise GPMSAError(f"fixed must be None or a dict name -> value, got {fixed!r}")
    fixed = dict(fixed)
    if "theta" in fixed and problem.obs is not None:
        fixed["theta"] = per_element.theta_unit(fixed["theta"], standardizer, t_names,
                                                problem.theta_levels)  # fmt: skip
    return problem.with_fixed(fixed)


def fit_held_native(problem: Problem, fixed, t_names) -> dict[int, float]:
    """position -> native value of each theta element that ``fit``'s ``fixed=`` (checked by
    `hold_fixed`) holds in ``problem``, a joint fit: exactly the value given, a categorical
    one its level (``fixed_elements.held_native``); {} where it holds none."""
    if not isinstance(fixed, dict) or "theta" not in fixed or problem.obs is None:
        return {}
    return per_element.held_native(fixed["theta"], t_names, problem.theta_levels)
