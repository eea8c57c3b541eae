"""``gpmsa.fit``: fit the GPM/SA emulator (optionally jointly with observations) by MCMC."""

from __future__ import annotations

import math
from dataclasses import replace
from datetime import datetime, timezone

import numpy as np

from gpmsa import backends
from gpmsa._version import library_versions
from gpmsa.errors import GPMSAError
from gpmsa.fitting.emulator import EMULATOR_PARAMS, Emulator, check_metadata
from gpmsa.limits import check_memory
from gpmsa.mcmc.diagnostics import convergence, summarize, warn_unconverged
from gpmsa.mcmc.parallel import in_this_process
from gpmsa.mcmc.sampler import (
    check_step_widths,
    draws_nbytes,
    parameter_elements,
    sweeps_nbytes,
)
from gpmsa.model import constraints
from gpmsa.model import fixed_elements as per_element
from gpmsa.model.basis import describe_discrepancy, discrepancy_kind
from gpmsa.model.data import ObsData, SimData, check_count, check_flag, run_seed
from gpmsa.model.discrepancy import kept_bases
from gpmsa.model.discrepancy import record as discrepancy_record
from gpmsa.model.priors import Priors
from gpmsa.model.problem import Problem, fixed_record, prepare

N_KEEP = 1000
"""Default number of retained draws (all chains together) after burn-in and thinning."""


def _factor_nbytes(m: int, p: int, q: int, p_u: int) -> float:
    """Bytes of the likelihood's covariances and factors: (p + q + 4 p_u + 2) m^2 floats."""
    return 8.0 * m * m * (p + q + 4 * p_u + 2)


def _check_fit_memory(problem, n_iter: int, n_chains: int) -> None:
    """Refuse (before sampling) a fit whose draws or factorisations exceed the memory limit:
    every sweep of every chain is stored (n_chains x n_iter x parameter elements, kept twice
    while the chains are stacked), and the likelihood keeps O((p + q + 4 p_u) m^2) floats."""
    m = problem.m
    nbytes = draws_nbytes(problem, n_iter, n_chains) + _factor_nbytes(
        m, problem.p, problem.q, problem.p_u
    )
    check_memory(nbytes, f"fit(n_iter={n_iter}, n_chains={n_chains}) of {m} runs x "
                 f"{parameter_elements(problem)} parameter elements")  # fmt: skip


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
    n_keep: int = N_KEEP,
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
    **options,
) -> Emulator:
    """Fit the emulator by GPM/SA's Metropolis-within-Gibbs; returns an ``Emulator``.

    data: the simulation runs. obs: field data for GPM/SA's classic joint calibration (theta and
    lamOs are sampled together with the emulator; the draws land in ``Emulator.calibration``).
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
    chains continue). n_keep: retained draws in all
    (evenly thinned). point: "mean" (posterior mean, default) or "map" (the draw of highest log
    posterior) for ``Emulator.params``. n_pc: basis size, or a variance fraction in (0, 1)
    (SEPIA's n_pc < 1; default 99.5%). basis: instead of the runs' PCA, a given basis
    (l_sim, p_u), columns the orthogonal basis vectors on the simulation grid in standardised
    output units (GPM/SA's ``Ksim``; ``gpmsa.BasisWarning`` when its weights' scale is not
    the one lamUz's prior expects; docs/categorical-and-constraints.md).
    discrepancy: None, "constant", "linear", an (l_obs, p_v) array on the grid every
    experiment shares, or a list of one (l_j, p_v) array per experiment on its own index grid
    (SEPIA's ``create_D_basis(D_obs=[...])``, GPM/SA's per-experiment ``Dobs``; normalised
    jointly, ``gpmsa.model.basis.discrepancy_bases``; kept in ``Emulator.discrepancy_bases`` and
    the file). discrepancy_groups: the
    precision group (0 .. G-1) of each discrepancy basis vector, GPM/SA's lamVzGroup (None: one
    group; each group has its own betaV column and lamVz). n_jobs, executor: where
    the chains run (numpy backend: ``n_jobs`` worker processes, None or -1 = every CPU but never
    more than the chains; or any ``concurrent.futures.Executor`` / dask ``Client``); the draws
    are the same wherever they run. seed: an integer, a numpy Generator or None (fresh
    entropy); the integer the fit ran with is ``settings["seed"]``, and ``fit(..., seed=that)``
    repeats it. priors: a ``gpmsa.Priors`` (None: GPM/SA's, ``Priors()``; the data
    corrections are added here). metadata: a JSON-able dict kept in ``Emulator.metadata``
    and the file. options: passed to the backend's ``sample`` (e.g. ``init``: a rule of
    ``gpmsa.mcmc.starts``, or an Emulator of this fit, whose chains then continue from their
    last kept draws: ``fit(data, n_iter=..., n_chains=emu's, init=emu)``, see
    ``continued_starts``).

    Beyond GPM/SA's model (numpy backend; docs/categorical-and-constraints.md): categorical
    inputs are declared in ``SimData`` (a categorical theta of a joint fit is sampled over its
    levels, uniform prior). mean_basis: None (zero mean, GPM/SA), "constant",
    "linear" or a callable of unit-scale [x, t] (n, p + q) -> (n, k); its coefficients are
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
    the centre; a categorical element: one of its levels).

    With more than one chain, the rank-normalised R-hat and bulk ESS of every sampled parameter
    are stored in ``Emulator.convergence`` (and the file), and a ``gpmsa.ConvergenceWarning``
    names each parameter with R-hat > 1.01 or ESS < 100. A chain that fails or produces
    non-finite draws raises ``gpmsa.ChainError`` naming it.
    """
    n_iter, n_chains = check_count(n_iter, "n_iter", 2), check_count(n_chains, "n_chains")
    continuing = isinstance(options.get("init"), Emulator)  # its chains start past burn-in
    default_burn = 0 if continuing else n_iter // 5
    n_burn = default_burn if n_burn is None else check_count(n_burn, "n_burn", 0, n_iter - 1)
    check_point(point)
    n_keep = check_keep(n_keep, n_chains)
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
    module = backends.get(backend)
    prep = prepare(data, obs, priors=priors, n_pc=n_pc, discrepancy=discrepancy,
                   mean_basis=mean_basis, discrepancy_groups=discrepancy_groups,
                   basis=basis)  # fmt: skip
    problem = _model_options(prep, data, fixed, constraint, theta_init)
    _check_fit_memory(problem, int(n_iter), int(n_chains))
    reserved = ("n_iter", "n_chains", "tune", "step_widths", "seed", "progress", "n_jobs",
                "executor")  # fmt: skip
    backends.check_options(backend, options, reserved, "fit")
    if backend == "numpy":  # (the others refuse these extensions)
        mean = problem.mean_basis
        callables = [name for name, on in (
            ("constraint", problem.constraint is not None),
            ("mean_basis", mean is not None and mean.kind == "callable"),
        ) if on]  # fmt: skip
        n_jobs, executor = in_this_process(callables, n_jobs, executor, int(n_chains))
    options.update(backends.placement(backend, n_jobs, executor))
    resumed, recorded = options.get("init"), None
    if continuing:
        options["init"] = continued_starts(resumed, problem, prep.K, obs, int(n_chains))
        if step_widths is None and tune is not True and backend != "pyro":  # NUTS adapts
            step_widths = recorded = continued_widths(resumed, problem, int(n_chains))
    if tune is None:  # only the widths the chains were tuned to run on untuned
        tune = recorded is None
    steps = None  # the precisions' steps as the chains it continues (SEPIA: once tuned, always)
    if continuing and not tune and "proportional_steps" not in options:
        steps = continued_steps(resumed)
    chains = module.sample(
        problem, n_iter=int(n_iter), n_chains=int(n_chains), tune=tune,
        step_widths=step_widths, seed=seed, progress=progress, **options,
        **({} if steps is None else {"proportional_steps": steps}),
    )  # fmt: skip
    chains.check_finite()
    kept = n_iter - n_burn
    thin = thinning(n_chains, kept, n_keep)  # each chain keeps ceil(kept / thin)
    # float64 whatever the backend sampled in (torch float32), a fixed parameter exactly at its
    # value
    post = {k: np.asarray(v[:, n_burn:], dtype=float) for k, v in chains.draws.items()}
    for k, mask in problem.held_masks(post).items():
        post[k][:, :, mask] = problem.init[k][mask]
    lp = chains.log_post[:, n_burn:]
    lp_kept = lp[:, ::thin].reshape(-1)
    n_kept = lp_kept.size  # explicit: an empty parameter (betaV when p = 0) has no -1 to infer
    retained = {k: v[:, ::thin].reshape(n_kept, *v.shape[2:]) for k, v in post.items()}
    params = point_estimate(retained, lp_kept, point)
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
        # n_jobs and executor say where the chains ran, not what they were: not recorded
        "backend_options": backends.recorded_options(
            {k: v for k, v in options.items() if k not in ("n_jobs", "executor")}
        ),
        "mean_basis": None if problem.mean_basis is None else problem.mean_basis.kind,
        "fixed": fixed_record(problem),
        "constraint": constraint is not None,
        "step_widths": {k: v.tolist() for k, v in chains.step_widths.items()},
        "fitted_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "versions": library_versions(backend),
    }  # fmt: skip
    if obs is not None and discrepancy is not None:  # full_prediction refuses another basis
        settings.update(discrepancy_record(problem.obs))
    summary = summarize(post, chains.accept_rate)
    record = None
    if n_chains > 1:
        shapes = {k: problem.init[k].shape for k in problem.sampled}
        held = {per_element.label(k, i) for k, v in problem.fixed_elements.items() for i in v}
        record = convergence(summary, shapes, n_chains, kept, held=held)
        warn_unconverged(
            record,
            f"gpmsa.fit (backend {backend!r})",
            more=", or continue these: gpmsa.fit(..., init=the returned emulator)",
        )
    return Emulator._from_prepared(
        data, prep, params,
        draws={k: retained[k] for k in EMULATOR_PARAMS}, log_post=lp_kept,
        metadata=metadata, settings=settings,
        diagnostics=summary, calibration=calibration, convergence=record,
        discrepancy_bases=kept_bases(problem.obs, discrepancy),
    )  # fmt: skip


def check_keep(n_keep, n_chains: int) -> int:
    """``n_keep`` checked: an integer >= 1 and at least ``n_chains`` (every chain keeps a draw);
    GPMSAError otherwise."""
    n_keep = check_count(n_keep, "n_keep")
    if n_keep < n_chains:
        raise GPMSAError(
            f"n_keep={n_keep} is fewer than n_chains={n_chains}: every chain keeps a draw"
        )
    return n_keep


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


def _check_levels(problem: Problem, theta_unit: np.ndarray, names, what: str,
                  only=None) -> None:  # fmt: skip
    """GPMSAError when a categorical element of ``theta_unit`` (those at positions ``only``;
    None: all) is not one of its levels."""
    for k, lv in enumerate(problem.theta_levels or ()):
        if only is not None and k not in only:
            continue
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
        problem = replace(problem, constraint=constraints.make(
            constraint, std.t_min, std.t_max, data.t_names))  # fmt: skip
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


def continued_starts(
    emulator: Emulator, problem: Problem, K: np.ndarray, obs: ObsData | None, n_chains: int
) -> dict[str, np.ndarray]:
    """Each chain's start at its last kept draw in ``emulator`` (a fit of the same data, and
    observations for a joint fit, with ``n_chains`` chains): name -> (n_chains, *shape), for a
    backend's ``init``. Its chains continue where they stopped being recorded (a draw of each
    chain, not a fresh dispersed start): a fit that warned of R-hat or ESS runs on without
    starting over. GPMSAError naming what differs."""
    if not emulator.draws or not emulator.log_post.size:
        raise GPMSAError("init=emulator continues a fit's chains; this emulator has no draws "
                         "(Emulator.from_params?)")  # fmt: skip
    settings = emulator.settings or {}
    n_prev = int(settings.get("n_chains", 1) or 1)
    if n_prev != n_chains:
        raise GPMSAError(f"init=emulator continues its {n_prev} chain(s): pass n_chains={n_prev}")
    same = (emulator.x_unit.shape == problem.x_sim.shape and emulator.K.shape == K.shape
            and np.array_equal(emulator.x_unit, problem.x_sim)
            and np.array_equal(emulator.t_unit, problem.t_sim)
            and np.allclose(emulator.w, problem.w, rtol=0.0, atol=1e-12))  # fmt: skip
    if not same:
        raise GPMSAError(
            "init=emulator was fitted to other simulation runs (or another n_pc or basis)"
        )
    cal = emulator.calibration or {}
    if (obs is None) != (not cal):
        raise GPMSAError(
            "init=emulator is a joint fit: pass its observations (obs=)" if cal else
            "init=emulator is a simulator-only fit; a joint fit (obs=) starts its own chains"
        )  # fmt: skip
    if obs is not None and settings.get("obs_sha256") not in (None, obs.digest()):
        raise GPMSAError("init=emulator was fitted jointly with other observations")
    differs = _model_differences(emulator, problem)
    if differs:
        raise GPMSAError(
            f"init=emulator was another model: its {', '.join(differs)} differ from this fit's; "
            "continue it with the same settings, or start afresh"
        )
    per = emulator.log_post.size // n_chains
    last = np.arange(1, n_chains + 1) * per - 1  # kept draws are stored chain after chain
    out = {}
    for name, init in problem.init.items():
        source = emulator.draws if name in EMULATOR_PARAMS else cal
        if name not in source or np.shape(source[name])[1:] != init.shape:
            raise GPMSAError(
                f"init=emulator has no {name} of shape {init.shape} (another discrepancy basis, "
                "groups or model?)"
            )
        out[name] = np.array(source[name][last], dtype=np.float64)
    return out


MH_BACKENDS = ("numpy", "torch")
"""Backends whose recorded ``step_widths`` are GPM/SA's Metropolis widths (a continuation runs
on with them)."""


def continued_widths(emulator: Emulator, problem: Problem, n_chains: int) -> dict | None:
    """The step widths ``emulator``'s chains ran with (``settings["step_widths"]``, per chain),
    for its continuation; None where it recorded none or its backend's are not Metropolis widths
    (``MH_BACKENDS``; pyro records its NUTS step size there). GPMSAError where the record does
    not fit ``problem``'s chains and parameters (a damaged file)."""
    settings = emulator.settings or {}
    record = settings.get("step_widths")
    if not record or settings.get("backend") not in MH_BACKENDS:
        return None
    try:
        check_step_widths(record, problem, n_chains)
    except GPMSAError as exc:
        raise GPMSAError(
            f"init=emulator: its recorded step widths (settings['step_widths']) do not fit "
            f"this fit ({exc}); pass step_widths= or tune=True"
        ) from None
    return record


def continued_steps(emulator: Emulator) -> bool | None:
    """Whether ``emulator``'s chains stepped the precisions by GPM/SA's proportional step (its
    ``settings["proportional_steps"]``; a file written before that was recorded: ``not
    settings["tune"]``, the rule its sampler followed), for its untuned continuation; None where
    its backend is not a Metropolis one (``MH_BACKENDS``). GPMSAError naming a damaged record."""
    settings = emulator.settings or {}
    if settings.get("backend") not in MH_BACKENDS:
        return None
    steps = settings.get("proportional_steps")
    if steps is None and isinstance(settings.get("tune"), bool):
        steps = not settings["tune"]
    if steps is not None and not isinstance(steps, bool):
        raise GPMSAError(
            f"init=emulator: its settings['proportional_steps'] must be true, false or null, got "
            f"{steps!r}; pass proportional_steps= or tune=True"
        )
    return steps


def _model_differences(emulator: Emulator, problem: Problem) -> list[str]:
    """What of the model ``emulator`` was fitted with differs from ``problem``'s: its priors,
    mean basis, fixed parameters, theta constraint and discrepancy basis and groups."""
    settings = emulator.settings or {}
    mb = problem.mean_basis
    disc = {} if problem.obs is None or problem.obs.D is None else discrepancy_record(problem.obs)
    n_grp = problem.obs.n_groups if problem.obs is not None and problem.obs.p_v else 0
    checks = {
        "priors": (_prior_record(emulator.priors, n_grp), _prior_record(problem.priors, n_grp)),
        "mean_basis": (settings.get("mean_basis"), None if mb is None else mb.kind),
        "fixed parameters": (settings.get("fixed", {}), fixed_record(problem)),
        "theta constraint": (bool(settings.get("constraint", False)),
                             problem.constraint is not None),
        "discrepancy": ({k: settings.get(k) for k in ("discrepancy_sha256", "discrepancy_groups")},
                        {k: disc.get(k) for k in ("discrepancy_sha256", "discrepancy_groups")}),
    }  # fmt: skip
    return [name for name, (old, new) in checks.items() if old != new]


def _prior_record(priors: Priors, n_grp: int) -> dict:
    """``priors.to_dict()`` with lamVz as the list of the ``n_grp`` groups' priors and rhoV_a,
    rhoV_b as the lists of the groups' betaV Beta parameters (a shared prior, equal per-group
    ones and, for betaV, none (betaU's) are one model); as written without a discrepancy, or
    where the per-group priors do not fit the groups."""
    out = priors.to_dict()
    if n_grp and (not priors.per_group or len(priors.lamVz) == n_grp):
        one = replace(priors, lamVz=priors.lamvz_priors(n_grp)).to_dict()
        out["lamVz"] = one["lamVz"]
    if n_grp and (not priors.rhov_per_group or len(priors.rhoV_a) == n_grp):
        pairs = priors.rhov_priors(n_grp)
        out["rhoV_a"], out["rhoV_b"] = [a for a, _ in pairs], [b for _, b in pairs]
    return out
