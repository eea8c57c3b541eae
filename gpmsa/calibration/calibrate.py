"""``gpmsa.calibrate``: MCMC calibration with the emulator fixed (the paper's online step).

With the emulator's parameters fixed (its point estimate, or integrated over its retained draws),
the calibration samples theta and the observation precision lamOs (and, with a discrepancy basis,
the discrepancy parameters betaV and lamVz). Defaults are the paper's: GPM/SA step-size tuning of
50 rounds x 20 levels (1,000 sweeps), then 5,000 sweeps of which the first 1,000 are burned.

Engines: the calibration-only problem is a ``gpmsa.Problem`` whose emulator parameters are in
``fixed``; any backend's ``sample`` runs it. For backend="numpy" without discrepancy the default is
a specialised sampler of the same algorithm (``gpmsa.calibration.sampler``) that evaluates only the
predictive at each proposed theta; ``fast=False`` uses the generic numpy backend instead.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import replace

import numpy as np

from gpmsa import backends
from gpmsa._fp_state import underflow_as_zero
from gpmsa._threads import one_thread
from gpmsa.calibration import continuation as cont
from gpmsa.calibration.judge import Run, judge_bounds, judge_convergence
from gpmsa.calibration.observations import (
    EMULATOR_PARAMS,
    N_EMULATOR_DRAWS,
    OUTSIDE_SDS,
    Fit,
    Observations,
    check_draws_mode,
    check_emulator,
    check_log_prior,
    check_x,
    check_y,
    checked_obs_data,
    closer_fit,
    draw_positions,
    emulator_param_sets,
    emulator_record,
    far_value,
    fit_at_levels,
    fit_of,
    fixed_gp,
    given_obs_data,
    lamos_start,
    obs_inputs,
    probe_layout,
    reduce,
    theta_levels,
    theta_levels_native,
    theta_probe,
    warn_if_outside,
)
from gpmsa.calibration.posterior import Posterior
from gpmsa.calibration.sampler import CalibrationSampler, ChainResult
from gpmsa.errors import GPMSAError, ReductionWarning, numbers_text
from gpmsa.limits import check_memory
from gpmsa.mcmc import level_moves, tempering, tuning
from gpmsa.mcmc.parallel import in_this_process, run_chains
from gpmsa.mcmc.sampler import require_finite
from gpmsa.model import constraints, kronecker
from gpmsa.model import fixed_elements as per_element
from gpmsa.model.basis import describe_discrepancy, discrepancy_kind
from gpmsa.model.data import ObsData, check_count, check_flag, run_seed
from gpmsa.model.discrepancy import check_groups, to_samples
from gpmsa.model.discrepancy import record as discrepancy_record
from gpmsa.model.problem import Problem, checked_fixed, default_init, fixed_record, reduce_obs

CALIBRATION_FIXED = ("theta", "lamOs", "betaV", "lamVz")
"""The parameters ``calibrate(fixed=)`` may hold (betaV and lamVz with a discrepancy only)."""


def calibration_problem(
    emulator, x_obs, y_obs, *, discrepancy=None, extrapolate=False, constraint=None,
    theta_init=None, reduced: Observations | None = None, discrepancy_groups=None, fixed=None,
    fit: Fit | None = None,
) -> Problem:  # fmt: skip
    """The calibration-only Problem: the emulator's parameters at its point estimate in ``fixed``.

    Sampled: theta, lamOs (and betaV, lamVz with a discrepancy basis, "constant" for a scalar
    output; "constant", "linear", a matrix or a list of per-experiment ones for a vector
    output; ``discrepancy_groups`` as ``gpmsa.fit``'s). ``constraint`` and ``theta_init`` as
    ``calibrate``'s. ``reduced``: ``reduce(emulator, x_obs, y_obs, extrapolate)`` where the
    caller has it already (no discrepancy only), so that the observations are checked and
    reduced once. ``fixed``: ``calibration_fixed(emulator, fixed=, discrepancy)`` (theta on
    the unit scale): held in the Problem (``Problem.with_fixed``) beside the emulator's parameters.
    ``fit``: ``observation_fit(emulator, reduced, [emulator.params])`` where the caller has it
    (with ``reduced``), for the lamOs start.
    """
    check_emulator(emulator, categorical_theta=True)
    kronecker.check_dense(emulator, "calibration (gpmsa.calibrate)")
    if reduced is not None and discrepancy is not None:
        raise GPMSAError("calibration_problem: reduced= is the no-discrepancy reduction; with a "
                         "discrepancy basis pass reduced=None")  # fmt: skip
    if fit is not None and reduced is None:
        raise GPMSAError("calibration_problem: fit= is the fit of reduced=; pass both or neither")
    start = None
    if discrepancy is None:
        check_groups(discrepancy_groups, 0)  # groups without a basis: refused
        data = reduce(emulator, x_obs, y_obs, extrapolate) if reduced is None else reduced
        obs, corr = data.obs, data.os_corr
        fit = observation_fit(emulator, data, [emulator.params]) if fit is None else fit
        start = lamos_start(fit, data.lamos)
    else:
        given = given_obs_data(x_obs, y_obs)
        if given is None:
            x, _ = check_x(emulator, obs_inputs(emulator, x_obs, y_obs), extrapolate)
            y = check_y(emulator, y_obs)
            if emulator.K.shape[0] == 1 and y.size == x.shape[0]:
                y = y.reshape(-1, 1)
            given = ObsData(x, y)
        else:
            checked_obs_data(emulator, given, extrapolate)
        obs, corr = reduce_obs(
            given, emulator.standardizer, emulator.K, discrepancy, emulator.x_names,
            getattr(emulator, "levels", None), getattr(emulator, "y_names", None),
            discrepancy_groups, x_checked=True,  # check_x checked and warned
            index_names=getattr(emulator, "index_names", None),
        )  # fmt: skip
    pri = emulator.priors
    lo = pri.lamOs
    priors = replace(pri, lamOs=replace(lo, a=lo.a + corr[0], b=lo.b + corr[1]))
    p, q, p_u = emulator.x_unit.shape[1], emulator.t_unit.shape[1], emulator.K.shape[1]
    init = default_init(p, q, p_u, priors, obs)
    for k in EMULATOR_PARAMS:
        init[k] = np.array(emulator.params[k], dtype=float).reshape(init[k].shape)
    if start is not None:
        init["lamOs"] = np.array([start])
    con, theta0 = _theta_options(emulator, constraint, theta_init)
    if theta0 is not None:
        init["theta"] = theta0
    problem = Problem(
        emulator.x_unit, emulator.t_unit, emulator.w, emulator.lam_sim, priors, init,
        frozenset(EMULATOR_PARAMS), obs, getattr(emulator, "categorical_mask", None),
        getattr(emulator, "mean_basis", None), con,
    )  # fmt: skip
    if theta0 is None and problem.theta_levels is not None:  # a categorical theta starts at a
        problem = problem.with_init({"theta": problem.snap_theta(init["theta"])})  # level
    return problem if not fixed else problem.with_fixed(fixed)


def calibration_fixed(emulator, fixed, discrepancy=None) -> dict | None:
    """``calibrate``'s ``fixed=`` checked by name, theta's values on the unit scale (an array
    (q,) for the whole vector, or position -> value for some elements: ``fixed_elements``'s
    ``theta_unit``; a categorical one exactly at its level); the other values as given (model
    scales), for ``Problem.with_fixed`` or the fast sampler to check. None for None.

    GPMSAError for a non-dict, an emulator parameter (not sampled in a calibration), a
    discrepancy parameter without a discrepancy, or an unknown name."""
    if fixed is None:
        return None
    if not isinstance(fixed, dict):
        raise GPMSAError(f"fixed must be None or a dict name -> value, got {fixed!r}")
    names = [str(n) for n in emulator.t_names]
    allowed = ["theta", "lamOs"] + (["betaV", "lamVz"] if discrepancy is not None else [])
    for name in fixed:
        if name in EMULATOR_PARAMS:
            raise GPMSAError(
                f"fixed[{name!r}]: {name} is an emulator parameter, which calibrate does not "
                "sample: it is held at the emulator's point estimate (emulator_params='point') "
                "or its retained draws ('draws'). To hold it at a value, fit the emulator so: "
                f"gpmsa.fit(..., fixed={{{name!r}: value}}); calibrate holds {allowed}"
            )
        if name in ("betaV", "lamVz") and discrepancy is None:
            raise GPMSAError(
                f"fixed[{name!r}]: {name} is a discrepancy parameter and this calibration has "
                "no discrepancy: give discrepancy= ('constant', 'linear' or a basis), or leave "
                f"{name} out; calibrate holds {allowed}"
            )
        if name not in CALIBRATION_FIXED:
            hint = ""
            if name in names:
                hint = f" ({name!r} is a calibration parameter: fixed={{'theta': {{{name!r}: v}}}})"
            raise GPMSAError(f"fixed: unknown parameter {name!r}{hint}; calibrate holds {allowed}")
    out = dict(fixed)
    if "theta" in out:
        out["theta"] = per_element.theta_unit(out["theta"], emulator.standardizer, names,
                                              theta_levels(emulator))  # fmt: skip
    return out


def calibration_held_native(emulator, fixed) -> dict[int, float]:
    """position -> native value of each theta element that ``fixed`` (``calibrate``'s, as the
    user gave it, checked by `calibration_fixed`) holds: the draws hold exactly these
    (``fixed_elements.held_native``: the value given, a categorical one its level)."""
    if not fixed or "theta" not in fixed:
        return {}
    return per_element.held_native(fixed["theta"], emulator.t_names, theta_levels(emulator))


def _theta_options(emulator, constraint, theta_init):
    """The ``ThetaConstraint`` (or None) and the unit-scale start of theta (or None); a
    categorical element of ``theta_init`` must be one of its training levels (the end levels
    included), as ``gpmsa.fit`` asks."""
    std = emulator.standardizer
    names = tuple(emulator.t_names)
    levels = getattr(emulator, "levels", None)
    levels = None if levels is None else levels[emulator.x_unit.shape[1] :]
    closed = None if levels is None else [lv is not None for lv in levels]
    con = constraints.make(constraint, std.t_min, std.t_max, names, closed or ())
    start = constraints.theta_init_unit(theta_init, std.t_min, std.t_max, names, closed)
    if start is not None and levels is not None:
        native = constraints.theta_native(theta_init, names)
        for k, lv in enumerate(levels):
            if lv is not None and not np.any(np.isclose(lv, native[k], rtol=0, atol=1e-9)):
                raise GPMSAError(
                    f"theta_init: categorical calibration parameter {names[k]} must be one of "
                    f"its training levels {list(lv)}, got {numbers_text(native[k], *lv)[0]}"
                )
    return con, start


@underflow_as_zero
def calibrate(
    emulator,
    x_obs=None,
    y_obs=None,
    n_samples: int = 5000,
    n_burn: int | None = None,
    tune: bool | None = None,
    seed=None,
    backend: str = "numpy",
    *,
    emulator_params: str = "point",
    n_emulator_draws: int = N_EMULATOR_DRAWS,
    discrepancy=None,
    discrepancy_groups=None,
    n_chains: int = 1,
    tune_rounds: int | None = None,
    tune_levels: int | None = None,
    extrapolate: bool = False,
    fast: bool | None = None,
    log_prior=None,
    progress: bool = False,
    n_jobs: int | None = None,
    executor=None,
    constraint=None,
    theta_init=None,
    fixed: dict | None = None,
    append: bool = False,
    **options,
) -> Posterior:
    """Calibrate theta (and lamOs) by MCMC with the emulator fixed.

    Args:
        emulator: a gpmsa.Emulator.
        x_obs: (n, p) known inputs of the observations, native units; None (or (n, 0)) for an
            emulator without known inputs (p = 0): each row of y_obs is then a replicate
            observation of the one experiment.
        y_obs: (n, l_sim) observed outputs, native units (a scalar output also takes (n,)).
            A pandas DataFrame (or Series) is read by name, the emulator's x_names / y_names
            in any order, never by position (but a y_obs frame with the default labels 0, 1,
            ...: no names, by position, as ObsData reads it); a numpy masked array is refused.
            Or pass one ``gpmsa.ObsData`` as x_obs (y_obs None), as ``gpmsa.fit(data, obs)``
            takes it: each experiment then lies on its own ``index`` within the simulation
            grid (the basis is interpolated there, as SEPIA's y_ind_obs) and may carry its
            observation-error ``precision`` (native units; lamOs still scales it).
        n_samples: sweeps per chain after tuning (pyro: NUTS draws after its ``n_warmup``
            adaptation steps, 500 by default); n_burn: of these, burned (kept: the rest;
            None: 1000, 0 for a continuation).
        tune: GPM/SA step-size tuning first (tune_rounds x tune_levels sweeps); None: True,
            but a continuation (``init`` a Posterior) runs on the widths its chains ended with.
        tune_rounds, tune_levels: the tuning's rounds and candidate widths per element (None:
            the backend's default; numpy 50 x 20; torch ceil(50 / n_chains) x 20). The pyro
            backend (NUTS) has no such tuning: giving either to it is a GPMSAError.
        seed: an integer, a numpy Generator or None (fresh entropy): the same seed gives the
            same draws, with any number of chains' workers; the integer the run used is
            ``info["seed"]`` (``seed=`` that integer repeats it).
        backend: "numpy" (default), "torch", "pyro" or a plug-in's name
            (``gpmsa.backends.register``; ``gpmsa.backends.available()``).
        emulator_params: "point" (the emulator's point estimate) or "draws" (the likelihood
            averaged over ``n_emulator_draws`` of its retained draws; numpy fast path only;
            ``info["emulator_draws"]`` then records, per sample, the retained draw it was drawn
            with, which ``calibrated_predict(..., draws=True)`` pairs with its theta).
            ``n_emulator_draws`` must be an integer >= 1 in either mode (at most the retained
            draws are used); another value than its default 20 with "point" is a GPMSAError
            (it would have no effect).
        discrepancy: None (no discrepancy, the default) or a discrepancy basis (generic backends):
            "constant", "linear", an (l_obs, p_v) array, or a list of one (l_j, p_v) array per
            experiment of an ObsData on its own index grid (normalised jointly, as
            ``gpmsa.fit``'s).
        discrepancy_groups: the precision group of each discrepancy basis vector, as
            ``gpmsa.fit``'s (GPM/SA's lamVzGroup; None: one group).
        n_chains: independent chains (their kept draws are pooled in ``samples``).
        extrapolate: allow x_obs outside the emulator's x domain by more than
            ``EXTRAPOLATION_MARGIN`` (10 %) of a column's width (with an ExtrapolationWarning).
            Within the margin x_obs is taken with that warning as a joint ``gpmsa.fit``
            takes it; beyond it, False: GPMSAError naming the column.
        fast: None (auto: the specialised sampler when it applies), True, or False (the backend).
        log_prior: optional extra log prior of theta, a vectorised callable of native theta as
            ``Calibrator.update`` takes it ((k,) values for one parameter, (k, q) for more ->
            (k,) log densities; called with k = 1); fast path only.
        progress: show a tqdm bar.
        n_jobs, executor: where several chains run (numpy backend): ``n_jobs`` worker processes
            (None or -1: every CPU, never more than the chains; this process where it is a
            daemonic worker, e.g. dask's) or any
            ``concurrent.futures.Executor`` / dask ``Client``; each chain has its own seed, so
            the draws do not depend on it.
            With ``log_prior`` (a callable, not shipped to workers) the chains run here.
        constraint: optional callable of native theta (q,) -> bool, False where theta is not
            allowed: zero prior mass there (no draw inside the forbidden region); a constraint
            that rejects the start is a GPMSAError. Chains run in this process.
        theta_init: start of theta (native, (q,), or a dict / pandas Series by t_names;
            default the centre of the design's range).
        fixed: None, or name -> value of the calibration parameters held at known values (as
            ``gpmsa.fit``'s ``fixed=``, SEPIA's ``SepiaParam.fixed``): "theta" in native units,
            the whole vector ((q,), or a dict by every t_name) or some elements as a dict
            t_name or position -> value (``{"theta": {"E": 2.1}}``: E known, the others
            calibrated); "lamOs" (a known observation precision, ``{"lamOs": 1.0}``); with a
            discrepancy "lamVz" and "betaV", whole or by element (``{"lamVz": {1: 1e6}}``: group
            1's discrepancy switched off; indices as ``gpmsa.model.fixed_elements``). A held
            element is never proposed and is exactly its value in every draw (its sd 0); the
            values are checked as ``fit``'s (theta inside the design's range, a categorical
            one at a level; others inside their prior's bounds); ``info["fixed"]`` records
            them as ``fit``'s ``settings["fixed"]`` (theta on the unit scale), ``info["held"]``
            the posterior names held (``Posterior.summary``'s "held": True). The fast
            sampler holds theta and lamOs itself (the default path stays fast; its
            draws of the others are those of the generic numpy backend's model); the numpy,
            torch and pyro backends hold any of them, whole or by element. The emulator's
            parameters (betaU, lamUz, lamWs, lamWOs) are not sampled here: naming one is a
            GPMSAError (fix them in ``gpmsa.fit(..., fixed=)``).
        append: with ``init`` a Posterior, return its chains each followed by this
            continuation's draws (below).
        options: passed to the backend's ``sample`` (``fast=False`` or another backend than
            numpy), e.g. ``device="cuda"``, ``dtype="float32"`` for torch; the fast sampler
            takes none. ``init``: a backend's start rule (``gpmsa.mcmc.starts``), or a
            Posterior that ``calibrate`` returned, whose chains continue (below).

    Continuing (``init=posterior``, as ``gpmsa.fit(..., init=emulator)``): each chain starts at
    its last draw, on the engine it ran on (fast sampler or backend), with the step widths it
    ended with and its precision steps (a tuned source's uniform steps; ``info
    ["proportional_steps"]``), untuned unless ``tune=True`` (from GPM/SA's widths); the seed
    gives a fresh stream, so n sweeps continued by m are not one run of n + m, but the same
    seed repeats the continuation. A tempered source runs on at its ladder (``temperatures=``
    gives another, None: untempered), every copy tuned at its temperature from the chain's
    last state (calibrate records no hot copies; ``tune=False`` refused). Refused naming what
    differs: another emulator (``model_sha256``: another fit or other calibration priors),
    other observations, another number of chains, emulator_params or n_emulator_draws, held
    values (``fixed=``), constraint or log_prior given or not, another discrepancy, the other
    engine, and ``theta_init``. ``info["continued_from"]`` records the source's chains'
    digest. ``append=True``: the chains pooled, diagnostics, convergence, the at-bound check
    and ``emulator_draws`` over them; info "appended_to", "appended_after" (the source's draws
    per chain), "pooled_sweeps", "sweeps_run" and "accept_rate" weighted by the parts' sweeps
    (a NUTS part beside a Metropolis one: the continuation's own); refused with n_burn > 0 or
    tuning (untempered). A Posterior kept by pickle continues; one rebuilt from ``to_arviz()``
    has no widths or settings, and is refused.

    ``info["diagnostics"]`` holds each parameter's rank-normalised R-hat and bulk ESS (and
    mean, sd), ``info["convergence"]`` the verdict, and a ``gpmsa.ConvergenceWarning`` names
    each parameter with R-hat > 1.01 or ESS < 100; one chain (the default) is judged by its
    split R-hat, which compares the chain's halves (the warning then advises a longer chain or
    ``n_chains >= 2``); the warning advises a continuation too (``init=`` the Posterior, with
    ``append=True`` where it was appended). A ``gpmsa.Calibrator``'s update (its MCMC path,
    online) judges one chain by none of them: its Posterior has no diagnostics, and no
    warning. A chain that fails or produces non-finite draws raises ``gpmsa.ChainError`` naming it.
    ``info["at_bound"]`` names each calibration parameter whose posterior piles up against a
    bound of the emulator's domain ("lower" or "upper": half its draws within 1 % of the
    domain's width of it, ``gpmsa.mcmc.bounds``; categorical and held ones are not
    judged), and a ``gpmsa.AtBoundWarning`` says what it may mean (the truth outside the
    design, a missing discrepancy) and what to do; a Calibrator's update neither.

    Returns:
        Posterior with draws of each calibration parameter (named as the emulator's t_names,
        native units), "lamOs" (and with a discrepancy "betaV", or "betaV[k]" per known input
        when p > 1, and "lamVz"; with several precision groups "betaV[k,g]" and "lamVz[g]",
        the groups in ``info["discrepancy_groups"]``, the basis's kind in
        ``info["discrepancy"]``: "constant", "linear", "given" or "list"), and chains per name;
        ``info["obs_values_sha256"]`` fingerprints the observations
        (``ObsData.values_digest(emulator.x_names, emulator.y_names)``: tables are read by
        name), so that
        ``gpmsa.full_prediction`` refuses other ones with these draws, and
        ``info["obs_layout_sha256"]`` their index grids and precisions (`layout_digest`);
        ``info["emulator_sha256"]`` the emulator (``Emulator.model_sha256``), so that the
        predictions taking an emulator and ``posterior=`` refuse another one;
        ``info["versions"]`` the versions of what ran the chains (as ``fit``'s
        ``settings["versions"]``: Python, gpmsa, numpy, scipy, the BLAS, the backend's
        packages or a plug-in's module).
    """
    run = sample_calibration(
        emulator, x_obs, y_obs, n_samples, n_burn, tune, seed, backend,
        emulator_params=emulator_params, n_emulator_draws=n_emulator_draws,
        discrepancy=discrepancy, discrepancy_groups=discrepancy_groups, n_chains=n_chains,
        tune_rounds=tune_rounds, tune_levels=tune_levels, extrapolate=extrapolate, fast=fast,
        log_prior=log_prior, progress=progress, n_jobs=n_jobs, executor=executor,
        constraint=constraint, theta_init=theta_init, fixed=fixed, append=append, **options,
    )  # fmt: skip
    # the engine that ran (the fast one runs on numpy whichever backend was named); here, not
    # in sample_calibration: a Calibrator's updates skip the BLAS scan (6-16 ms)
    run.info["versions"] = backends.recorded_versions(run.info["backend"])
    where = f"gpmsa.calibrate (backend {backend!r})"
    judge_convergence(run, where, more=f", or {_more_advice(append)}")
    std = emulator.standardizer
    judge_bounds(run, emulator.t_names, std.t_min, std.t_max, where)
    return run.posterior()


def sample_calibration(
    emulator, x_obs=None, y_obs=None, n_samples: int = 5000, n_burn: int | None = None,
    tune: bool | None = None, seed=None, backend: str = "numpy", *,
    emulator_params: str = "point", n_emulator_draws: int = N_EMULATOR_DRAWS, discrepancy=None,
    discrepancy_groups=None, n_chains: int = 1, tune_rounds: int | None = None,
    tune_levels: int | None = None, extrapolate: bool = False, fast: bool | None = None,
    log_prior=None, progress: bool = False, n_jobs: int | None = None, executor=None,
    constraint=None, theta_init=None, fixed: dict | None = None, append: bool = False,
    **options,
) -> Run:  # fmt: skip
    """``calibrate``'s run, unjudged: its arguments (the same, with the same defaults) checked,
    the chains run and their draws recorded as ``calibrate`` records them, without
    ``info["diagnostics"]``, ``["convergence"]`` or ``["at_bound"]`` and their warnings
    (``judge.judge_convergence``, ``judge.judge_bounds``). ``gpmsa.calibrate`` is this run
    judged; a ``Calibrator``'s MCMC update runs it and judges several chains' convergence only
    (its one chain: fast and silent). ``run.posterior()`` is the Posterior."""
    check_emulator(emulator, categorical_theta=True)
    seed = run_seed(seed)
    n_samples = check_count(n_samples, "n_samples", 2)
    n_chains = check_count(n_chains, "n_chains")
    source = None  # init= a Posterior of calibrate: its chains continue (a rule: the backend's)
    if options.get("init") is not None and not isinstance(options["init"], str | dict):
        source = cont.checked_source(options.pop("init"), n_chains)
    append = cont.check_append(append, source, n_burn)
    if n_burn is None:
        n_burn = 1000 if source is None else 0
    ok = not isinstance(n_burn, bool) and isinstance(n_burn, int | np.integer)
    if not (ok and 0 <= n_burn < n_samples - 1):
        raise GPMSAError(burn_message(n_burn, n_samples, "n_samples", 1000))
    tune = None if tune is None else check_flag(tune, "tune")
    extrapolate = check_flag(extrapolate, "extrapolate")
    progress = check_flag(progress, "progress")
    backends.get(backend)  # unknown or not installed: a clear error before any work
    tuning_opts = _tuning_options(backend, tune_rounds, tune_levels)
    n_emulator_draws = check_count(n_emulator_draws, "n_emulator_draws")  # as Calibrator's
    sets = emulator_param_sets(emulator, emulator_params, n_emulator_draws)
    check_draws_mode(emulator_params, n_emulator_draws, "calibrate")
    if discrepancy is None:
        check_groups(discrepancy_groups, 0)  # groups without a basis: refused
    can_fast = backend == "numpy" and discrepancy is None
    fast_given = fast is not None
    if fast is None:  # a continuation: on its source's engine
        fast = can_fast and (source is None or source.info["engine"] == "fast")
    fast = check_flag(fast, "fast")
    if source is not None:
        cont.check_source(source, emulator, fast, emulator_params, n_emulator_draws, constraint,
                      log_prior, discrepancy, theta_init, backend)  # fmt: skip
    if fast and not can_fast:
        raise GPMSAError("fast=True needs backend='numpy' and no discrepancy")
    if not fast and (emulator_params != "point" or log_prior is not None):
        what = ("emulator_params='draws'" if emulator_params != "point"
                else "log_prior (a Calibrator update's prior=)")  # fmt: skip
        got = [f"backend={backend!r}"] if backend != "numpy" else []  # each in the way, as given
        if discrepancy is not None:
            got.append(f"discrepancy={describe_discrepancy(discrepancy)}")
        if fast_given:
            got.append("fast=False")
        raise GPMSAError(
            f"{what} needs the fast numpy sampler: backend='numpy', no discrepancy and fast "
            f"not False; got {', '.join(got)}"
        )
    reserved = ("n_iter", "n_chains", "tune", "seed", "progress", "n_jobs", "executor",
                "tune_rounds", "tune_levels")  # fmt: skip
    renamed = {"n_iter": "n_samples"}  # gpmsa.fit's name: no backend option (nor fast=False)
    if on_obs := sorted(set(options) & {"index", "precision"}):
        raise GPMSAError(
            f"calibrate: {on_obs} describe the observations: give them with x and y as "
            "gpmsa.ObsData(x, y, index=..., precision=...) in place of x_obs (y_obs left out)"
        )
    backends.check_options(backend, options, reserved, "calibrate", renamed)
    backends.check_tempering(backend, options)  # a plug-in's (pyro's: not its options)
    if options and fast:
        raise GPMSAError(
            f"calibrate: options {sorted(options)} go to a backend's sampler, which the fast "
            "numpy sampler replaces; pass fast=False (or another backend) to use them"
        )
    given_options = dict(options)  # recorded as given (a continuation adds its ladder)
    temps = None  # parallel tempering (numpy, torch: their samplers' option)
    if backend in ("numpy", "torch") and source is not None and not fast:
        temps = cont.continued_ladder(source, options, n_chains)  # the source's by default
    elif backend in ("numpy", "torch"):
        temps = tempering.ladder(options.get("temperatures"))
    resume = None  # a continuation's source, recorded widths and precision steps
    if source is None:
        tune = True if tune is None else tune
    else:
        tune, resume = cont.continued_run(source, tune, fast, backend, temps, append, options)
        if emulator_params == "draws":
            resume["positions"] = draw_positions(emulator, n_emulator_draws)
    pooled = 0 if not append else np.atleast_2d(next(iter(source.chains.values()))).shape[1]
    _check_calibrate_memory(emulator, n_samples + pooled, n_chains, fast,
                            1 if temps is None else len(temps))  # fmt: skip
    con, _ = _theta_options(emulator, constraint, theta_init)  # refuse bad ones before work
    theta_opts = {"constraint": constraint, "theta_init": theta_init}
    if source is not None:  # the chains start at their last draws, not at GPM/SA's initial
        theta_opts["theta_init"] = cont.theta_start(source, emulator, con)
    held = calibration_fixed(emulator, fixed, discrepancy)
    if held is not None and fast:
        theta_opts["held"] = _fast_held(emulator, held)  # checked before any work
    t0 = time.perf_counter()
    with one_thread():
        where = {"n_jobs": n_jobs, "executor": executor}
        with warnings.catch_warnings():
            if discrepancy is not None:  # the reduction with its basis warns (_run_backend)
                warnings.simplefilter("ignore", ReductionWarning)
            data = reduce(emulator, x_obs, y_obs, extrapolate)
        if source is not None:
            cont.check_same(source, observations=(
                [source.info.get(k) for k in ("obs_values_sha256", "obs_layout_sha256")],
                [data.values_sha256, data.layout_sha256]))  # fmt: skip
        fit = observation_fit(emulator, data, sets)
        # attributed to the user's call (of calibrate, or of a Calibrator's update)
        warn_if_outside(fit, discrepancy=discrepancy is not None,
                        far=far_value(emulator, data, fit))  # fmt: skip
        if fast:
            draws, info = _run_fast(
                emulator, data, fit, sets, n_samples, n_chains, tune, tuning_opts, seed,
                log_prior, progress, where, theta_opts, resume,
            )  # fmt: skip
        else:
            draws, info = _run_backend(
                emulator, data, x_obs, y_obs, backend, (discrepancy, discrepancy_groups),
                n_samples, n_chains, tune, {**tuning_opts, **options}, seed, extrapolate,
                progress, where,
                {**theta_opts, "fixed": held, "fit": None if discrepancy is not None else fit},
                resume,
            )  # fmt: skip
    held_names = info.pop("held_names", ())
    set_index = info.pop("set_index", None)
    for k, value in calibration_held_native(emulator, fixed).items():  # the value given
        draws[emulator.t_names[k]][...] = value
    require_finite(draws)
    chains = {k: v[:, n_burn:] for k, v in draws.items()}
    if append:  # the source's chains, each followed by its continuation's
        chains = cont.pool(source, chains)
    samples = {k: v.reshape(-1) for k, v in chains.items()}
    info.update(
        method="mcmc", n_samples=n_samples, n_burn=n_burn, n_chains=n_chains, tune=tune,
        seed=seed,
        emulator_params=emulator_params, seconds=time.perf_counter() - t0,
        outside_sds=fit.outside_sds, obs_values_sha256=data.values_sha256,
        obs_layout_sha256=data.layout_sha256,
        **emulator_record(emulator),
        units=dict(zip(emulator.t_names, emulator.t_units, strict=True)),
        backend_options=backends.recorded_options(given_options),
    )  # fmt: skip
    info.update(cont.settings_record(constraint, log_prior, emulator_params, n_emulator_draws))
    if source is not None:  # as gpmsa.fit's settings record a continuation
        info["continued_from"] = cont.chains_sha256(source)
        if append:
            info.update(cont.appended_info(source, n_samples, info["accept_rate"], backend))
    if emulator_params == "draws":  # the retained draw each sample was drawn with
        positions = draw_positions(emulator, n_emulator_draws)
        info["emulator_draws"] = positions[set_index[:, n_burn:].reshape(-1)]
        if append:
            info["emulator_draws"] = cont.pool_flat(source.info["emulator_draws"],
                                                    info["emulator_draws"], n_chains)  # fmt: skip
    codes = theta_levels_native(emulator)
    if codes:  # a categorical theta: its quantiles are levels (Posterior.quantile)
        info["levels"] = codes
    if held is not None:
        info["fixed"] = info.pop("fixed", {})  # after the run's own keys
        info["held"] = list(held_names)  # the posterior names held (Posterior.summary's "held")
    return Run(samples, chains, info, tuple(held_names), tuple(codes))


def _more_advice(append: bool) -> str:
    """The call a ConvergenceWarning of ``calibrate`` advises to run the chains on (as
    ``gpmsa.fit``'s): a continuation (``append``: appended)."""
    if append:
        return "append more: gpmsa.calibrate(..., init=the returned posterior, append=True)"
    return "continue these: gpmsa.calibrate(..., init=the returned posterior)"


def burn_message(n_burn, n_samples, what: str = "n_samples", default: int | None = None) -> str:
    """The refusal of an ``n_burn`` outside [0, ``what`` - 1): the run's length, and where
    ``n_burn`` is an integer too large for it, a hint (naming the ``default`` burn-in where
    ``n_burn`` is it: users meet it without passing ``n_burn`` when they shorten the run)."""
    msg = f"n_burn must be an integer in [0, {what} - 1), got {n_burn!r} with {what}={n_samples}"
    if isinstance(n_burn, int | np.integer) and not isinstance(n_burn, bool) and n_burn > 0:
        told = f"n_burn defaults to {default} burned sweeps: " if n_burn == default else ""
        msg += f" ({told}pass a smaller n_burn= or a larger {what})"
    return msg


def _tuning_options(backend: str, tune_rounds, tune_levels) -> dict[str, int]:
    """The tuning keywords for ``backend``'s sampler: those given (checked), with numpy's
    defaults for the numpy samplers; GPMSAError when given to pyro, which does not tune so."""
    given = {k: v for k, v in (("tune_rounds", tune_rounds), ("tune_levels", tune_levels))
             if v is not None}  # fmt: skip
    if backend == "pyro":
        if given:
            raise GPMSAError(f"backend 'pyro' (NUTS) has no GPM/SA step-size tuning: it takes no "
                             f"{' or '.join(given)}= (its adaptation is n_warmup)")  # fmt: skip
        return {}
    if backend == "numpy":
        given = {"tune_rounds": tuning.N_BURN, "tune_levels": tuning.N_LEVELS, **given}
    if untaken := [k for k in given if not backends.takes(backend, k)]:  # a plug-in's sample
        raise GPMSAError(f"backend {backend!r} takes no {' or '.join(untaken)}=")
    # torch's default rounds, ceil(50 / n_chains), are at most numpy's
    rounds, levels = tuning.check_tuning(given.get("tune_rounds", tuning.N_BURN),
                                         given.get("tune_levels", tuning.N_LEVELS))  # fmt: skip
    checked = {"tune_rounds": rounds, "tune_levels": levels}
    return {k: checked[k] for k in given}


def observation_fit(emulator, data, sets) -> Fit:
    """The observation's ``Fit`` over ``theta_probe`` (the best over the parameter sets). A
    categorical theta takes its levels only: its outside_sds and excess_var (the lamOs start,
    `lamos_start`) both over them, from one probe (`fit_at_levels`: the levels crossed with the
    continuous parameters' nodes); over ``theta_probe`` (without the sign-change rule) where
    the combinations of levels exceed `LEVEL_PROBE_BUDGET`. With three or more continuous
    parameters, where every set reads the data outside on the scattered nodes, `closer_fit`
    looks closer from the nearest set's nodes (one set's searches, not one per set)."""
    levels = theta_levels(emulator)
    gps = [fixed_gp(emulator, s) for s in sets]
    if levels is not None:
        at_levels = [fit_at_levels(gp.predict, data, levels) for gp in gps]
        if None not in at_levels:
            return Fit(min(f.outside_sds for f in at_levels), min(f.excess_var for f in at_levels))
    q = emulator.t_unit.shape[1]
    theta = theta_probe(q)
    layout = probe_layout(q) if levels is None else None
    fits, best = [], None  # best: (its index, gp, probe) of the set nearest the data
    for gp in gps:
        probe = gp.predict(data.x, theta)
        fits.append(fit_of(*probe, data, layout))
        if best is None or fits[-1].outside_sds < fits[best[0]].outside_sds:
            best = (len(fits) - 1, gp, probe)
    k, gp, probe = best
    if layout is None and levels is None and fits[k].outside_sds > OUTSIDE_SDS:
        # scattered nodes, and every set reads the data outside: look closer, from the nearest
        # set's nodes alone (20 draws' searches cost minutes for a large emulator)
        fits[k] = closer_fit(gp.predict, data, theta, probe)
    return Fit(min(f.outside_sds for f in fits), min(f.excess_var for f in fits))


def _check_calibrate_memory(
    emulator, n_samples: int, n_chains: int, fast: bool, copies: int = 1
) -> None:
    """Refuse before sampling a run whose stored sweeps exceed gpmsa.limits.MAX_MEMORY_BYTES;
    with parallel tempering (``copies`` > 1 temperatures, numpy or torch) its ``copies``
    likelihood states too, as ``gpmsa.fit`` counts them (``_check_fit_memory(copies=)``)."""
    p, q, p_u = emulator.x_unit.shape[1], emulator.t_unit.shape[1], emulator.K.shape[1]
    if fast:  # a tuple of q + 3 Python floats per sweep, then an array
        per_sweep = 64.0 + 56.0 * (q + 3)
    else:  # every parameter (the fixed emulator ones too) per sweep, stacked over chains
        per_sweep = 16.0 * (q + 4 + (p + q) * p_u + 2 * p_u + 1 + p)
    nbytes, what = per_sweep * n_samples * n_chains, ""
    if copies > 1:  # one likelihood state per temperature, each O((p + q + 4 p_u) m^2)
        nbytes += copies * 8.0 * emulator.x_unit.shape[0] ** 2 * (p + q + 4 * p_u + 2)
        what = f" at {copies} temperatures"
    check_memory(nbytes, f"calibrate(n_samples={n_samples}, n_chains={n_chains}){what}")


def _fast_chain(
    sampler: CalibrationSampler, n_samples: int, seed: np.random.SeedSequence, tune: bool,
    tune_rounds: int, tune_levels: int, progress: bool = False, desc: str = "calibrate",
    start: tuple | None = None, widths: np.ndarray | None = None,
    proportional: bool | None = None,
):  # fmt: skip
    """One chain of the fast sampler (a worker process runs it from plain data); ``start``,
    ``widths``, ``proportional``: a continuation's (``CalibrationSampler.run``)."""
    with one_thread(None):
        return sampler.run(
            n_samples,
            np.random.default_rng(seed),
            tune=tune,
            tune_rounds=tune_rounds,
            tune_levels=tune_levels,
            progress=progress,
            widths=widths,
            start=start,
            proportional=proportional,
        )


def _run_fast(
    emulator, data, fit, sets, n_samples, n_chains, tune, tuning_opts, seed, log_prior,
    progress, where, theta_opts, resume=None,
):  # fmt: skip
    std = emulator.standardizer
    theta_opts = dict(theta_opts)
    held_theta, held_lamos = theta_opts.pop("held", (None, None))
    con, theta0 = _theta_options(emulator, **theta_opts)
    extra = None
    if log_prior is not None:
        if not callable(log_prior):
            raise GPMSAError("log_prior must be a callable of native theta for MCMC")
        names = tuple(emulator.t_names)

        categorical = [lv is not None for lv in theta_levels(emulator) or ()]

        def extra(theta_unit: np.ndarray) -> float:
            native = constraints.round_levels(std.t_from_unit(theta_unit[None, :]), categorical)
            val = log_prior(native[:, 0] if native.shape[1] == 1 else native)
            return check_log_prior(val, names, native[0])

    sampler = CalibrationSampler(
        [fixed_gp(emulator, s) for s in sets], data, emulator.priors, extra,
        init_lamos=lamos_start(fit, data.lamos), constraint=con, init_theta=theta0,
        theta_levels=theta_levels(emulator), held_theta=held_theta, held_lamos=held_lamos,
    )  # fmt: skip
    mean = emulator.mean_basis  # a callable one goes with the emulator to every chain
    callables = [name for name, on in (("log_prior", extra is not None),
                                       ("constraint", con is not None),
                                       ("mean_basis", mean is not None and mean.kind == "callable"),
                                       ) if on]  # fmt: skip
    n_jobs, executor = in_this_process(callables, where["n_jobs"], where["executor"], n_chains)
    where = {"n_jobs": n_jobs, "executor": executor}
    fixed_info = _fast_fixed_info(emulator, held_theta, held_lamos, sampler.q)
    resumed = {} if resume is None else _fast_resume(emulator, sampler, resume, n_chains,
                                                     fixed_info.get("fixed"))  # fmt: skip
    tasks = [
        {"sampler": sampler, "n_samples": n_samples, "seed": s, "tune": tune, **tuning_opts,
         **{k: v[c] for k, v in resumed.items()}}
        for c, s in enumerate(np.random.SeedSequence(seed).spawn(n_chains))
    ]  # fmt: skip
    runs = run_chains(
        _fast_chain, tasks, progress=progress, desc="calibrate chain",
        check=lambda _, r: _wrong_fast_run(r, n_samples, sampler.q), **where,
    )  # fmt: skip
    if any(not np.isfinite(r.log_post[-1]) for r in runs):
        raise GPMSAError(
            "the posterior has no mass where the sampler looked: log_prior is -inf there "
            "(zero prior density everywhere?)"
        )
    theta = std.t_from_unit(np.stack([r.theta for r in runs]))  # (chains, n, q)
    for k, lv in enumerate(sampler.levels):  # categorical draws: exactly the level codes
        if lv is not None:
            theta[:, :, k] = np.round(theta[:, :, k])
    draws = {name: theta[:, :, k] for k, name in enumerate(emulator.t_names)}
    draws["lamOs"] = np.stack([r.lamOs for r in runs])
    set_index = np.stack([r.index for r in runs])  # (chains, n): the emulator set per draw
    rates, widths = np.stack([r.accept_rate for r in runs]), np.stack([r.widths for r in runs])
    held = [*(held_theta or ())] + ([sampler.q] if held_lamos is not None else [])
    rates[:, held] = widths[:, held] = np.nan  # held: no step, no acceptance (as the backends)
    info = {
        "engine": "fast",
        "backend": "numpy",
        "accept_rate": rates.tolist(),
        "step_widths": widths.tolist(),
        "chebyshev": all(p.cheb is not None or p.cheb2 is not None for p in sampler.preds),
        "set_index": set_index,  # calibrate's info["emulator_draws"] (popped there)
    }
    moves = level_moves.chains_record([r.level_offsets for r in runs], runs[0].level_shifted)
    if moves:  # a categorical theta's joint level move, per chain (native units)
        info["level_offsets"] = _level_record(emulator, moves)
    info.update(fixed_info)
    if resume is not None and resume["proportional"] is not None:
        info["proportional_steps"] = resume["proportional"]
    return draws, info


def _fast_fixed_info(emulator, held_theta, held_lamos, q: int) -> dict:
    """The fast sampler's info "fixed" (``per_element.record`` of the held values, as the
    backends' ``fixed_record``) and "held_names" (the posterior names held); {} with none."""
    if held_theta is None and held_lamos is None:
        return {}
    values = {} if held_theta is None else {"theta": held_theta}
    if held_lamos is not None:
        values["lamOs"] = [held_lamos]
    if len(values.get("theta", ())) == q:
        values["theta"] = [held_theta[k] for k in range(q)]
    elif "theta" in values:
        values["theta"] = {(k,): v for k, v in held_theta.items()}
    names = list(emulator.t_names)
    return {"fixed": per_element.record(values),
            "held_names": [names[k] for k in held_theta or ()]
            + (["lamOs"] if held_lamos is not None else [])}  # fmt: skip


def _fast_resume(emulator, sampler: CalibrationSampler, resume: dict, n_chains: int,
                 fixed) -> dict[str, list]:  # fmt: skip
    """A fast continuation's per-chain "start" (each chain's last draw), "widths" (recorded,
    or None: GPM/SA's) and "proportional", for `_fast_chain`; GPMSAError where the source held
    other values (``fixed``: this run's record) or a start has no posterior mass here."""
    source = resume["source"]
    cont.check_same(source, **{"fixed parameters": (source.info.get("fixed") or None,
                                                    fixed or None)})  # fmt: skip
    starts = cont.fast_starts(source, emulator, sampler.levels, resume.get("positions"))
    for c, start in enumerate(starts):
        if not np.isfinite(sampler.log_post_at(start)):
            raise GPMSAError(f"{cont.SOURCE}: chain {c}'s last draw has no posterior mass in "
                             "this calibration (another log_prior?); start "
                             "afresh")  # fmt: skip
    widths = [None] * n_chains
    if resume["widths"]:
        widths = cont.fast_widths(source, sampler.q, n_chains)
    return {"start": starts, "widths": widths, "proportional": [resume["proportional"]] * n_chains}


def _fast_held(emulator, held: dict) -> tuple[dict[int, float] | None, float | None]:
    """The fast sampler's held theta elements (position -> unit value; None: none) and held
    lamOs (None: sampled) from ``calibration_fixed``'s ``held``, checked as
    ``Problem.with_fixed`` checks them (shape, index, finite, inside the prior's bounds)."""
    levels = theta_levels(emulator)
    levels = None if levels is None else [None if lv is None else np.asarray(lv) for lv in levels]
    theta = lamos = None
    if "theta" in held:
        q = emulator.t_unit.shape[1]
        val = checked_fixed("theta", held["theta"], (q,), emulator.priors, levels)
        items = val.items() if isinstance(val, dict) else (((k,), v) for k, v in enumerate(val))
        theta = {k: float(v) for (k,), v in items}
    if "lamOs" in held:
        lamos = float(checked_fixed("lamOs", held["lamOs"], (1,), emulator.priors)[0])
    return theta, lamos


def _level_record(emulator, moves: dict) -> dict:
    """The samplers' record of the joint level moves (``level_moves.chains_record``, unit
    scale) in theta's native units, by name (``level_moves.native_record``)."""
    std = emulator.standardizer
    return level_moves.native_record(moves, emulator.t_names, std.t_min, std.t_max,
                                     tuple(emulator.levels)[len(emulator.x_names):])  # fmt: skip


def _wrong_fast_run(run, n_samples: int, q: int) -> str | None:
    """``run_chains``' check of a fast calibration chain's result: None when it is the task's
    own ChainResult, else the draws it should hold."""
    if isinstance(run, ChainResult) and np.shape(run.theta) == (n_samples, q):
        if np.shape(run.lamOs) == np.shape(run.log_post) == (n_samples,):
            return None
    return f"{n_samples} samples"


def _run_backend(
    emulator, data, x_obs, y_obs, backend, discrepancy, n_samples, n_chains, tune, tuning_opts,
    seed, extrapolate, progress, where, theta_opts, resume=None,
):  # fmt: skip
    """The generic backend's draws and info; ``discrepancy``: (basis, groups); ``theta_opts``
    with ``calibration_problem``'s ``fixed``; ``resume``: a continuation's
    (`continuation.continued_run`)."""
    discrepancy, groups = discrepancy
    problem = calibration_problem(
        emulator, x_obs, y_obs, discrepancy=discrepancy, extrapolate=extrapolate,
        reduced=data if discrepancy is None else None, discrepancy_groups=groups, **theta_opts,
    )  # fmt: skip
    if backend == "numpy":  # a constraint, a callable mean basis (torch: its sample; pyro: here)
        n_jobs, executor = in_this_process(
            problem.callables, where["n_jobs"], where["executor"], n_chains
        )
        where = {"n_jobs": n_jobs, "executor": executor}
    opts = {**tuning_opts, **backends.placement(backend, **where)}
    masks = problem.held_masks(CALIBRATION_FIXED)
    if resume is not None:
        opts.update(_backend_resume(emulator, problem, masks, resume))
    chains = backends.sample(
        backend, problem, n_iter=n_samples, n_chains=n_chains, tune=tune, seed=seed,
        progress=progress, **opts,
    )  # fmt: skip
    std = emulator.standardizer
    if masks:  # float64 whatever the backend sampled in, a held parameter exactly its value
        chains_draws = {k: np.array(v, dtype=float) for k, v in chains.draws.items()}
        for k, mask in masks.items():
            chains_draws[k][:, :, mask] = problem.init[k][mask]
        chains = replace(chains, draws=chains_draws)
    theta = std.t_from_unit(np.asarray(chains.draws["theta"]))
    # categorical draws: exactly the level codes (as the fast sampler's)
    constraints.round_levels(theta, [lv is not None for lv in theta_levels(emulator) or ()])
    draws = {name: theta[:, :, k] for k, name in enumerate(emulator.t_names)}
    draws["lamOs"] = np.asarray(chains.draws["lamOs"])[:, :, 0]
    if "lamVz" in chains.draws:
        draws.update(to_samples(np.asarray(chains.draws["betaV"]), chains.draws["lamVz"]))
    info = {
        "engine": "backend",
        "backend": backend,
        "accept_rate": {k: np.asarray(v).tolist() for k, v in chains.accept_rate.items()},
        "step_widths": {k: np.asarray(v).tolist() for k, v in chains.step_widths.items()},
    }
    if "level_offsets" in chains.info:  # a categorical theta's joint level move, per chain
        info["level_offsets"] = _level_record(emulator, chains.info["level_offsets"])
    if "temperatures" in chains.info:  # parallel tempering: as fit's settings record it
        info.update(temperatures=list(chains.info["temperatures"]),
                    swap_every=int(chains.info["swap_every"]),
                    swap_rate=np.asarray(chains.info["swap_rate"]).tolist())  # fmt: skip
    if "adapted_temperatures" in chains.info:  # adapt_ladder=True: each chain's, frozen
        info["adapted_temperatures"] = np.asarray(chains.info["adapted_temperatures"]).tolist()
    if resume is not None:  # each chain at its own adapted ladder: recorded as they adapted
        info = tempering.recorded_ladders(info, resume["source"].info)
    if resume is not None and chains.info.get("proportional_steps") is not None:
        info["proportional_steps"] = bool(chains.info["proportional_steps"])
    if discrepancy is not None:  # full_prediction(posterior=) refuses another basis
        info.update({"discrepancy": discrepancy_kind(discrepancy),
                     **discrepancy_record(problem.obs)})  # fmt: skip
    if masks:
        info["fixed"] = fixed_record(problem, masks)
        names = list(emulator.t_names)
        info["held_names"] = [names[k] for k in np.flatnonzero(masks.get("theta", []))]
        info["held_names"] += ["lamOs"] if "lamOs" in masks else []
        info["held_names"] += held_discrepancy_names(problem, masks)
    return draws, info


def _backend_resume(emulator, problem: Problem, masks: dict, resume: dict) -> dict:
    """A backend continuation's sampler options: "init" (each chain's last draw), its recorded
    "step_widths" and "proportional_steps" where it runs on them; GPMSAError where the source
    held other values or had another discrepancy basis or groups (naming them)."""
    source = resume["source"]
    disc = {} if problem.obs is None or problem.obs.D is None else discrepancy_record(problem.obs)
    cont.check_same(source, **{
        "fixed parameters": (source.info.get("fixed") or None,
                             (fixed_record(problem, masks) if masks else None) or None),
        "discrepancy basis or groups": ({k: source.info.get(k) for k in disc}, disc),
    })  # fmt: skip
    out = {"init": cont.backend_starts(source, problem, emulator)}
    if resume["widths"] is not None:
        out["step_widths"] = resume["widths"]
    if resume["proportional"] is not None:
        out["proportional_steps"] = resume["proportional"]
    return out


def held_discrepancy_names(problem: Problem, masks: dict[str, np.ndarray]) -> list[str]:
    """The posterior names (``to_samples``': "lamVz[1]", "betaV[0,1]", ...) of the discrepancy
    elements that ``masks`` (``Problem.held_masks``) hold; [] without a discrepancy."""
    if "lamVz" not in problem.init:
        return []
    shown = to_samples(*(masks.get(k, np.zeros(problem.init[k].shape, bool))
                         for k in ("betaV", "lamVz")))  # fmt: skip
    return [k for k, v in shown.items() if v]
