"""Online calibration with a fixed emulator: prepared once, then ``update`` per observation window.

For one or two calibration parameters the posterior is computed exactly on a grid (no sampling):
with the emulator parameters fixed, the observation's reduced data u given the simulation weights w
is Gaussian at every theta (``gpmsa.calibration.model``), lamOs is integrated out per theta node by
quadrature, and the posterior is the prior times that likelihood on the grid, refined around each
mode (separated region of mass) that the grid does not resolve (where heavy tails hold the grid
beyond its node budget, the core of each marginal, its tails on fewer nodes; for one parameter
down to float64's resolution; a warning where a marginal stays under ``grid.UNRESOLVED_SD``
node spacings per sd).
Between nodes the posterior density is linear (bilinear for two parameters): its quantiles, CDF
and draws use that density, its moments the trapezoid sums over the nodes (``GridMarginal``; the
two differ by about h^2 / 6 in variance, h the node spacing, so the draws' sd can exceed ``sd()``
by a fraction of a percent on a grid that resolves the posterior) (``gpmsa.calibration.grid``:
interpolation, constraint boundaries, draws, refinement).
More parameters use the MCMC of ``gpmsa.calibrate``.

A categorical calibration parameter (``theta_levels``): its grid axis is its levels, exactly
(a continuous parameter beside it on ``n_grid`` nodes per level, default 129); its marginal a
``LevelMarginal`` (a probability per level: the posterior integrated over the continuous
nodes at that level), whose quantiles and draws are levels; the continuous axis of each level
is refined as one parameter's is (a warning where a level's continuous density stays
unresolved), and such a grid takes no constraint with a continuous parameter ("auto" chooses
MCMC there: ``gpmsa.calibrate``'s joint level move).

The fixed grid (``Calibrator.theta_grid``): ``n_grid`` equally spaced nodes per calibration
parameter spanning the emulator's domain [t_min, t_max] of that parameter (the design's range,
or the range given as ``SimData(t_range=)``), end points included (default 129 for one
parameter, 65 x 65 for two, in 'ij' order, first parameter slowest).
"""

from __future__ import annotations

import inspect
import math
import threading
import warnings
from collections.abc import Callable

import numpy as np
from scipy.special import log_ndtr

from gpmsa import backends
from gpmsa._fp_state import underflow_as_zero
from gpmsa._progress import progress_bar
from gpmsa._threads import one_thread
from gpmsa.calibration.grid import (
    MODE_MASS,
    RIDGE_SD,
    UNRESOLVED_SD,
    ConstraintCut,
    check_log_density,
    check_mass,
    conditional_sds,
    constrained,
    draw_allowed,
    draw_bilinear,
    interp_log,
    mesh,
    nearest,
    refined_axes,
    refined_axis,
    resolution,
    tail_refined_axes,
    trimmed_marginal,
    whole_refined_axis,
    with_edges,
    zero_edges,
)
from gpmsa.calibration.judge import judge_convergence
from gpmsa.calibration.local_cubic import NARROW_PRIOR_SD, narrowest_sd
from gpmsa.calibration.model import (
    GridPredictor,
    LamOsMarginal,
    chebyshev_plan,
    lamos_marginal,
    predictor_bytes,
)
from gpmsa.calibration.observations import (
    EMULATOR_PARAM_MODES,
    N_EMULATOR_DRAWS,
    Fit,
    Observations,
    check_draws_mode,
    check_emulator,
    draw_positions,
    emulator_param_sets,
    emulator_record,
    far_value,
    fit_at_levels,
    fixed_gp,
    outside_sds,
    probe_layout,
    reduce,
    theta_levels,
    theta_levels_native,
    theta_probe,
    warn_if_outside,
)
from gpmsa.calibration.posterior import LevelMarginal, Posterior, trapezoid_weights
from gpmsa.errors import (
    GPMSAError,
    GridResolutionWarning,
    StartRejectedError,
    numbers_text,
    user_stacklevel,
)
from gpmsa.limits import check_memory
from gpmsa.model import constraints
from gpmsa.model.data import as_float, check_count, check_flag, repr_names, run_seed
from gpmsa.model.problem import extensions_used

METHODS = ("auto", "grid", "mcmc")
N_DRAWS = 4000
"""Default ``n_draws`` of a Calibrator: the draws a grid posterior makes for its samples."""
MAX_REFINE = 4
"""Refinement passes of one update, at most (each refines the peaks still unresolved)."""
MAX_REFINE_ONE = 9
"""The same for one parameter, whose passes are cheap (N_REFINE nodes): a peak on one node
narrows the spacing about 64-fold per pass, from 1/128 of the range to float64's resolution
(``Calibrator._min_step``) in 8 (4 passes resolved an sd down to about 1e-9 of the range)."""
MIN_STEP_ULPS = 8
"""One parameter: refined nodes are at least this many float64 spacings (ulps) apart, in the
unit scale and in the parameter's native units (``Calibrator._min_step``)."""
LEVEL_MASS = 0.01
"""A categorical theta's grid: the levels whose conditional resolution is checked hold at least
this share of the mass."""
BISECT_STEPS = 64
"""Bisection steps locating a constraint's boundary between two nodes (to adjacent floats)."""
PRIOR_BISECT_LEVELS = 4
"""Bisection steps per call of a callable prior locating its zero region's edges (one parameter,
no constraint): it is called at the 2**4 - 1 midpoints those steps may visit, of all edges at
once (16 calls of 15 points an edge instead of 64 of one; 4-8 levels measured alike for a
cheap prior, and a prior's cost per point grows with the level)."""


_MCMC_ONLY = {
    "fixed": "holds parameters on the MCMC path",
    "discrepancy": "is a discrepancy model's option, taken on the MCMC path",
    "discrepancy_groups": "is a discrepancy model's option, taken on the MCMC path",
}
"""The Calibrator's ``mcmc_options`` that the exact grid has no use for (refused with it), and
what each does on the MCMC path."""


def _check_mcmc_options(options, backend: str) -> dict:
    """``options`` (None or a dict of ``gpmsa.calibrate`` keywords, backend ``backend``'s
    sampler options among them, as ``calibrate`` passes them on) as a dict; GPMSAError naming
    what is not a keyword the Calibrator may pass on (it gives the data, ``extrapolate`` and the
    prior itself)."""
    from gpmsa.calibration.calibrate import sample_calibration  # calibrate imports this module

    if options is None:
        return {}
    if not isinstance(options, dict):
        raise GPMSAError(f"mcmc_options must be None or a dict, got {type(options).__name__}")
    own = {"emulator", "x_obs", "y_obs", "extrapolate", "log_prior"}
    named = {k for k, v in inspect.signature(sample_calibration).parameters.items()
             if v.kind is not inspect.Parameter.VAR_KEYWORD}  # fmt: skip
    params = inspect.signature(backends.get(backend).sample).parameters.values()
    sampler = {p.name for p in params if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)}
    sampler -= {"problem"}
    allowed = sorted((named | sampler) - own - {"n_iter"})  # n_iter: calibrate's n_samples
    taken = own | {"n_iter"}  # the Calibrator's own, or calibrate's n_samples: never passed on
    unknown = sorted((set(options) & taken) if backends.open_ended(backend)  # a plug-in's
                     else set(options) - set(allowed), key=str)  # fmt: skip
    if unknown:
        raise GPMSAError(
            f"mcmc_options: unknown keyword(s) {unknown}; gpmsa.calibrate takes {allowed} "
            f"(with the {backend!r} backend)"
        )
    _refuse_continuation(options)
    return dict(options)


def _refuse_continuation(options: dict) -> None:
    """GPMSAError where ``options`` continue an offline calibration (``init`` other than a
    start rule, ``append`` other than False): each update runs fresh chains on its own
    observations, so there is no calibration to continue."""
    fresh = ("a Calibrator's update runs fresh chains on each update's observations, so there "
             "are no chains to continue")  # fmt: skip
    init = options.get("init")
    if init is not None and not isinstance(init, str | dict):
        raise GPMSAError(
            f"mcmc_options['init'] takes a start rule (a name such as 'gpmsa', or a dict), got "
            f"{type(init).__name__}: {fresh} (a Posterior's chains continue in "
            "gpmsa.calibrate(..., init=posterior))"
        )
    if options.get("append", False) is not False:
        raise GPMSAError(
            f"mcmc_options['append']={options['append']!r}: {fresh} (append=True pools a "
            "continuation's draws with its source's in gpmsa.calibrate(..., init=posterior, "
            "append=True)): leave it out"
        )


_NUTS_UNUSED = ("tune_rounds", "tune_levels", "step_widths")
"""``gpmsa.calibrate`` options of GPM/SA's step-size tuning, which pyro's NUTS does not take (it
adapts its step size in its warm-up)."""


def _refuse_unused_sampler_options(options: dict, backend: str, draws: bool = False) -> None:
    """GPMSAError now, not at the first update, for ``mcmc_options`` (``options``, checked by
    `_check_mcmc_options`) that ``gpmsa.calibrate`` on ``backend`` refuses as without effect
    there: GPM/SA's tuning or step widths with pyro (NUTS), ``fast=True`` where the fast numpy
    sampler cannot run (another backend, a discrepancy), and a backend sampler's own options
    (``step_widths``, ``init``, ``temperatures``, ...) where it runs. Each names the options,
    the backend and the remedy (``draws``: emulator_params="draws", which only the fast
    sampler takes). Tuning counts are checked as ``calibrate`` checks them."""
    from gpmsa.calibration.calibrate import _tuning_options, sample_calibration

    if backend == "pyro":
        given = [k for k in _NUTS_UNUSED if _given(options, k)]
        if given:
            them = "it" if len(given) == 1 else "them"
            raise GPMSAError(
                f"mcmc_options {given}: backend 'pyro' (NUTS) has no GPM/SA step-size tuning "
                "or step widths (it adapts its step size in its warm-up, "
                f"mcmc_options={{'n_warmup': ...}}): leave {them} out, or use backend='numpy' "
                "or 'torch'"
            )
    _tuning_options(backend, options.get("tune_rounds"), options.get("tune_levels"))
    fast = options.get("fast")
    if fast is not None:
        fast = check_flag(fast, "mcmc_options['fast']")
    can_fast = backend == "numpy" and options.get("discrepancy") is None
    if fast and not can_fast:
        got = f"backend={backend!r}" if backend != "numpy" else "mcmc_options['discrepancy']"
        raise GPMSAError(
            f"mcmc_options['fast']=True needs backend='numpy' and no discrepancy (the fast numpy "
            f"sampler), got {got}: leave mcmc_options['fast'] out"
        )
    named = {k for k, v in inspect.signature(sample_calibration).parameters.items()
             if v.kind is not inspect.Parameter.VAR_KEYWORD}  # fmt: skip
    sampler_only = sorted(k for k in options if k not in named)  # the backend sampler's
    if sampler_only and can_fast and fast is not False and draws:
        raise GPMSAError(
            f"mcmc_options {sampler_only} go to the numpy backend's sampler, and "
            "emulator_params='draws' needs the fast numpy sampler, which takes none of them: "
            "leave them out"
        )
    if sampler_only and can_fast and fast is not False:
        raise GPMSAError(
            f"mcmc_options {sampler_only} go to the numpy backend's sampler, which the fast "
            "numpy sampler replaces (gpmsa.calibrate's default without a discrepancy): add "
            "mcmc_options['fast'] = False (or choose backend='torch') to use them, or leave "
            "them out"
        )


def _refuse_placement(options: dict, backend: str) -> None:
    """GPMSAError now, not at the first update, for an ``n_jobs`` or ``executor`` that backend
    ``backend``'s sampler refuses whatever the data, with its message: pyro's (its chains run
    one after another here: no executor, n_jobs None, 1 or -1), and torch's n_jobs with one
    chain group (a given ``chain_groups`` other than the integer 1 is left to the update, whose
    refusal depends on the chains and the CPUs)."""
    if backend == "numpy":  # its chains may run elsewhere: checked where they run
        return
    backends.placement(backend, executor=options.get("executor"))
    if "n_jobs" not in options:
        return
    groups = options.get("chain_groups", 1)
    one_group = isinstance(groups, int | np.integer) and groups is not True and groups == 1
    if backend == "pyro":
        backends.get(backend).check_n_jobs(options["n_jobs"])
    elif backend == "torch" and one_group:  # (1.0 or True: refused by name at the update)
        backends.get(backend).check_n_jobs(options["n_jobs"], 1, options.get("n_chains", 1))


def _given(options: dict, key: str) -> bool:
    """Whether ``options[key]`` is given as calibrate and pyro's ``sample`` read it: a tuning
    count not None, step widths not empty."""
    return bool(options.get(key)) if key == "step_widths" else options.get(key) is not None


def _mcmc_backend(backend, options) -> str:
    """The Calibrator's backend: ``backend``, or where it is None (the default)
    ``options["backend"]`` (``mcmc_options``), else numpy; GPMSAError where both are given and
    name different ones (an explicit "numpy" too)."""
    if not isinstance(options, dict) or "backend" not in options:
        return "numpy" if backend is None else backend
    given = options["backend"]
    if backend is None or (isinstance(given, str) and given == backend):
        return given
    raise GPMSAError(
        f"backend={backend!r} and mcmc_options['backend']={given!r} disagree: give the "
        "backend once, as Calibrator(..., backend=)"
    )


class Calibrator:
    """Calibration of ``emulator`` for a stream of observations, prepared once.

    Args:
        emulator: a gpmsa.Emulator (the grid uses no discrepancy model; the MCMC path takes
            one as ``mcmc_options={"discrepancy": ...}``).
        method: "grid" (exact, q <= 2), "mcmc" (``gpmsa.calibrate``), or "auto" (grid for q <= 2;
            MCMC for a categorical and a continuous parameter with a ``constraint``).
        n_grid: nodes per calibration parameter of the fixed grid (default 129 for q = 1, 65 for
            2; a categorical parameter's nodes are its levels, and the continuous one beside it
            has n_grid per level, default 129). Refused on the MCMC path (it has no grid).
        emulator_params: "point" (the emulator's point estimate) or "draws" (average the
            likelihood over up to ``n_emulator_draws`` of its retained draws, evenly spaced:
            the posterior of theta, lamOs and the draw, whose draws record the draw drawn
            with each in ``info["emulator_draws"]``, as ``gpmsa.calibrate``'s, for
            ``calibrated_predict(..., draws=True)``; another ``n_emulator_draws`` than 20 with
            "point" is a GPMSAError: it would have no effect).
        extrapolate: allow x_obs outside the emulator's x domain by more than
            ``EXTRAPOLATION_MARGIN`` (10 %) of a column's width (with an ExtrapolationWarning).
            Within the margin x_obs is taken with that warning as a joint ``gpmsa.fit``
            takes it; beyond it, False: GPMSAError naming the column. The default of every
            update; ``update(..., extrapolate=)`` sets it for one.
        n_draws: draws a grid posterior makes (lazily) for ``Posterior.samples``; another
            value than its default is refused on the MCMC path (whose draws are its chains').
        seed: seed of those draws (and of the MCMC), for reproducibility: an integer, a numpy
            Generator (an integer is drawn from it) or None (fresh entropy).
        mcmc_options: keyword arguments for ``gpmsa.calibrate`` when the method is MCMC
            (``"fixed"``, which holds parameters at known values, and ``"discrepancy"`` /
            ``"discrepancy_groups"``, only there: with the grid method they are a GPMSAError),
            the backend's sampler options among them, as
            ``calibrate`` takes them (``{"dtype": "float32"}`` for torch, ``{"n_warmup": 200}``
            for pyro). A continuation's ``"init"`` (a Posterior) and ``"append": True`` are a
            GPMSAError: each update runs fresh chains. So are options that ``calibrate`` on
            this backend refuses as without effect (`_refuse_unused_sampler_options`: pyro's
            GPM/SA tuning and step widths, ``"fast": True`` where the fast sampler cannot run,
            a backend sampler's options where it runs), and an ``"n_jobs"`` or ``"executor"``
            its sampler refuses whatever the data (`_refuse_placement`: pyro's ``n_jobs`` > 1
            or executor, torch's ``n_jobs`` > 1 with one chain group). With ``method="grid"``
            given, any but ``"backend"`` is a GPMSAError (the grid would ignore them; "auto"
            keeps them for an emulator that needs MCMC).
        backend: engine of the MCMC path ("numpy", "torch", "pyro" or a plug-in's name,
            ``gpmsa.backends.register``; see ``gpmsa.backends.available()``). The grid path
            is numpy's; another backend makes "auto" choose MCMC. None (the default):
            ``mcmc_options["backend"]`` where it names one, else "numpy"; a GPMSAError where
            both are given and differ (an explicit "numpy" too), and, here, where a plug-in's
            module does not declare an extension that the emulator (categorical inputs, a mean
            basis), ``constraint`` or ``mcmc_options["fixed"]`` already give
            (``gpmsa.backends.check_extensions``).
        constraint: optional callable of native theta (q,) -> bool, False where theta is not
            allowed: zero prior mass there. On the grid, for one parameter the density is cut at
            the boundary (located by bisection between nodes, to float precision), so that no
            mass lies outside; for two parameters each cell the boundary crosses (corners of
            both verdicts) is split into N_SUB x N_SUB (``gpmsa.calibration.grid``), the
            constraint evaluated at the new nodes, and the density falls to zero across the
            split cells the boundary crosses (its only error: mass in that band, a quarter of
            a cell wide, may lie on the wrong side), and draws the constraint rejects are
            redrawn: none lies outside. A region of either verdict that touches no node (nor
            new node) is not seen by the density (draws are still checked). MCMC passes it to
            ``gpmsa.calibrate`` (every backend): where it rejects the start
            (the design's centre) give one inside as ``mcmc_options={"theta_init": [...]}``
            (native units; with ``"fast": False`` or torch, whose chains start at random,
            add ``"init": "gpmsa"`` where no random start lies inside). It is evaluated on
            the fixed grid once, here (on a refined grid, at the update).
        progress: show a tqdm bar on stderr ("Calibrator") over the grid's preparation
            here, in steps: per emulator parameter set (one with "point"; with "draws" about
            0.3 s each for the shipped band emulators, a minute for 200) its GP's Chebyshev
            plan, its predictor on the grid and, one continuous parameter, on the refined
            grid. The MCMC path prepares nothing here; its updates' chains show their bars
            with ``mcmc_options={"progress": True}``.
    """

    @underflow_as_zero
    def __init__(
        self,
        emulator,
        *,
        method: str = "auto",
        n_grid: int | None = None,
        emulator_params: str = "point",
        n_emulator_draws: int = N_EMULATOR_DRAWS,
        extrapolate: bool = False,
        n_draws: int = N_DRAWS,
        seed=None,
        mcmc_options: dict | None = None,
        backend: str | None = None,
        constraint=None,
        progress: bool = False,
    ) -> None:
        check_emulator(emulator, categorical_theta=True)
        progress = check_flag(progress, "progress")
        levels = theta_levels(emulator)  # unit scale per element, None: no categorical one
        std = emulator.standardizer
        self._categorical = [lv is not None for lv in levels or ()]
        self.constraint = constraints.make(constraint, std.t_min, std.t_max,
                                           tuple(emulator.t_names), self._categorical)  # fmt: skip
        if method not in METHODS:
            raise GPMSAError(f"method must be one of {METHODS}, got {method!r}")
        backend = _mcmc_backend(backend, mcmc_options)
        if backend in backends.names() and backend != "numpy" and method == "grid":
            raise GPMSAError(  # whether the backend's packages are installed or not
                "method='grid' runs on numpy; use method='mcmc' (or 'auto') with "
                f"backend={backend!r}"
            )
        backends.get(backend)  # unknown or not installed: a clear error now, not at update()
        if emulator_params not in EMULATOR_PARAM_MODES:
            raise GPMSAError(
                f"emulator_params must be one of {EMULATOR_PARAM_MODES}, got {emulator_params!r}"
            )
        q = emulator.t_unit.shape[1]
        if method == "grid" and q > 2:
            raise GPMSAError(f"method='grid' handles 1 or 2 calibration parameters, got q={q}")
        # a categorical theta with a continuous one: the grid has no constraint cut along the
        # continuous axis per level (it would ramp across the boundary's cell), so MCMC
        mixed = levels is not None and None in levels
        if method == "grid" and mixed and constraint is not None:
            raise GPMSAError(
                "method='grid' with a categorical and a continuous calibration parameter takes "
                "no constraint (its boundary would not be located between nodes): use "
                "method='mcmc' (or 'auto', which chooses it)"
            )
        self.emulator = emulator
        self._levels = levels
        grid_ok = q <= 2 and backend == "numpy" and not (mixed and constraint is not None)
        self.method = ("grid" if grid_ok else "mcmc") if method == "auto" else method
        self.backend = backend
        self.q = q
        self.extrapolate = check_flag(extrapolate, "extrapolate")
        self.n_draws = check_count(n_draws, "n_draws")
        check_memory(  # the draws of theta and lamOs and their grid cells, made lazily
            8.0 * 3 * self.n_draws * (q + 1),
            f"Calibrator(n_draws={self.n_draws}): the posterior's draws of {q + 1} parameters",
        )
        self._n_emulator_draws = check_count(n_emulator_draws, "n_emulator_draws")
        self.emulator_params = emulator_params
        self._entropy = np.random.SeedSequence(None if seed is None else run_seed(seed)).entropy
        self._count = 0
        self._updating = threading.RLock()  # updates take turns: each has its own count
        self._in_update = False  # an update runs (`update` refuses one from inside it)
        self.mcmc_options = _check_mcmc_options(mcmc_options, backend)
        user_options = sorted(self.mcmc_options)  # before the constraint joins them
        if constraint is not None:
            self.mcmc_options.setdefault("constraint", constraint)
        self._check_mcmc_path(backend)
        given = [k for k in _MCMC_ONLY if self.mcmc_options.get(k) is not None]
        if self.method == "grid" and given:  # options the grid would ignore
            k = given[0]
            chosen = " (method='auto' chooses it for 1 or 2 parameters)" if method == "auto" else ""
            raise GPMSAError(
                f"mcmc_options[{k!r}] {_MCMC_ONLY[k]}, and this Calibrator uses the exact "
                f"grid{chosen}, which {'' if k == 'fixed' else 'has no discrepancy and '}would "
                f"ignore it: use Calibrator(emu, method='mcmc', mcmc_options={{{k!r}: ...}}), or "
                f"gpmsa.calibrate(..., {k}=...)"
            )
        grid_given = n_grid is not None
        if n_grid is None:  # a categorical parameter with a continuous one: 129 per level
            n_grid = 129 if q == 1 or mixed else 65
        self.n_grid = check_count(n_grid, "n_grid", 3)
        self._check_path_options(method, grid_given, user_options)
        if self.method == "mcmc":
            return
        m, p_u = emulator.x_unit.shape[0], emulator.K.shape[1]
        kept = emulator.n_draws if emulator.draws else 0  # at most these draws are used
        n_sets = 1 if emulator_params == "point" else min(self._n_emulator_draws, max(kept, 1))
        # the axes: a categorical parameter's nodes are its levels (exact: no interpolation
        # between levels), a continuous one's n_grid equally spaced nodes (counted first: a
        # huge n_grid is refused by its memory below before an axis is made)
        G = math.prod(self.n_grid if lv is None else len(lv) for lv in (levels or [None] * q))
        # per parameter set: R_t on the grid and its product with alpha (G x m per component)
        # and Sigma_W's factor; once the Chebyshev degrees are known, `_check_predictor_memory`
        # adds the predictors' products H and the prepared refinement
        per_set = 8.0 * p_u * (2.0 * G * m + 2.0 * m * m)
        what = (f"Calibrator(n_grid={self.n_grid}): {G} grid nodes x {m} runs x {p_u} "
                f"components x {n_sets} emulator parameter set(s)")  # fmt: skip
        check_memory(n_sets * per_set + 8.0 * 8 * G, what)
        self._axes = [np.linspace(0.0, 1.0, self.n_grid) if lv is None else np.array(lv)
                      for lv in (levels or [None] * q)]  # fmt: skip
        self._theta_unit = mesh(self._axes)
        std = emulator.standardizer
        self.theta_grid = std.t_from_unit(self._theta_unit)
        if levels is not None:  # a categorical element's nodes: exactly its level codes
            self._codes = _level_codes(emulator)
            exact = mesh([a if c is None else c for a, c in zip(self._axes, self._codes,
                                                                  strict=True)])  # fmt: skip
            for k, c in enumerate(self._codes):
                if c is not None:
                    self.theta_grid[:, k] = exact[:, k]
        if q == 1:
            self.theta_grid = self.theta_grid[:, 0]
        self.theta_grid.flags.writeable = False  # `log_likelihood_grid` hands it out
        with one_thread():
            sets = emulator_param_sets(emulator, emulator_params, n_emulator_draws)
            # the bar's steps, per set: its GP and Chebyshev plan, its predictor on the grid
            # and, one continuous parameter, on the refined grid (a plan refused after its fit
            # or a plan's products on many nodes: any of them can take most of the time)
            steps = (3 if q == 1 and levels is None else 2) * len(sets)
            with progress_bar(progress, steps, "Calibrator", "step") as bar:
                self._gps, plans = [], []
                for prm in sets:
                    self._gps.append(fixed_gp(emulator, prm))
                    plans.append(chebyshev_plan(self._gps[-1]))
                    bar.update(1)
                refined = self._refined_axis(plans)
                _check_predictor_memory(self._gps, plans, G, refined, 8.0 * 8 * G, what)
                self._predictors = []
                for gp, plan in zip(self._gps, plans, strict=True):
                    self._predictors.append(GridPredictor(gp, self._theta_unit, plan))
                    bar.update(1)
                self._refined = self._refined_predictors(refined, plans, bar.update)
                bar.update(steps - bar.n)  # a set without a plan: no refined grid prepared
        mean, sd = emulator.priors.theta_moments(q)  # floats, or per element (q,)
        self._log_prior_theta = -0.5 * np.sum(((self._theta_unit - mean) / sd) ** 2, axis=1)
        if levels is not None:  # a categorical element: uniform over its levels (calibrate's)
            cont = [lv is None for lv in levels]
            mean, sd = emulator.priors.theta_moments(q, np.flatnonzero(cont))
            self._log_prior_theta = -0.5 * np.sum(
                ((self._theta_unit[:, cont] - mean) / sd) ** 2, axis=1
            )
        self._weights = trapezoid_weights(self.theta_grid) if q == 1 else None
        self._log_prior_norm = log_theta_norm(*emulator.priors.theta_prior(0))  # q = 1's
        self._min_step = _float_step(std, 0)  # one parameter: float64's resolution
        self._base_ok = None if self.constraint is None else self._allowed(self._theta_unit)
        self._base_cut = None
        if self._base_ok is not None and levels is None:  # all categorical: exact at the nodes
            self._base_cut = self._cut(self._axes, self._base_ok)

    def _refined_axis(self, plans: list) -> np.ndarray | None:
        """One parameter whose predictors need no solves per update (a Chebyshev plan for every
        parameter set): the unit-scale axis of the usual refinement (`grid.whole_refined_axis`),
        for which `_refined_predictors` prepares predictors; None otherwise."""
        if self.q != 1 or self._levels is not None or any(plan is None for plan in plans):
            return None
        return whole_refined_axis(self._axes[0])

    def _refined_predictors(
        self, axis: np.ndarray | None, plans: list, done=None
    ) -> tuple[np.ndarray, list[GridPredictor]] | None:
        """Predictors on the refined ``axis`` (`_refined_axis`), so that an update that refines
        so costs no dense solves either (the road case: 2.4 -> 1.5 ms, 2.5% of its updates);
        None without an axis (refined nodes get dense solves). ``done(1)`` is called after each
        predictor (a progress bar's ``update``)."""
        if axis is None:
            return None
        predictors = []
        for gp, plan in zip(self._gps, plans, strict=True):
            predictors.append(GridPredictor(gp, axis[:, None], plan))
            if done is not None:
                done(1)
        return axis, predictors

    def __repr__(self) -> str:
        """One line: the method, its backend, the calibration parameters (`repr_names`), the
        grid's nodes per axis (grid method), the emulator's parameters where they are its
        draws, and the updates made so far. Reads attributes only: no computation, and never
        raises (a half-built or odd Calibrator shows "?")."""
        try:
            parts = [f"method={self.method}", f"backend={self.backend}",
                     f"t={repr_names(self.emulator.t_names)}"]  # fmt: skip
            axes = getattr(self, "_axes", None)
            if self.method == "grid" and axes is not None:
                parts.append(f"grid={'x'.join(str(len(a)) for a in axes)} nodes")
            if self.emulator_params != "point":
                parts.append(f"emulator_params={self.emulator_params}")
            parts.append(f"updates={self._count}")
        except Exception:  # a repr never raises
            parts = ["?"]
        return f"Calibrator({', '.join(parts)})"

    def __getstate__(self) -> dict:
        """For pickle and ``copy``: all but the update lock (a copy gets its own)."""
        state = self.__dict__.copy()
        state.pop("_updating", None)
        state.pop("_in_update", None)  # a copy made inside an update is not in it
        return state

    def __setstate__(self, state: dict) -> None:
        """Unpickling (and ``copy.deepcopy``): one pickled before the prepared refinement
        (session 65; a saved BCR holds one) prepares it now, as a Calibrator built now does;
        ``theta_grid`` read-only again (numpy restores an array writable)."""
        self.__dict__.update(state)
        grid = self.__dict__.get("theta_grid")
        if isinstance(grid, np.ndarray):
            grid.flags.writeable = False
        self._updating = threading.RLock()
        self._in_update = False
        self.__dict__.setdefault("_levels", None)  # pickled before categorical grids (s73)
        self.__dict__.setdefault("_categorical", [])
        if "_refined" not in state and self.method == "grid":
            with one_thread():
                plans = [chebyshev_plan(gp) for gp in self._gps]
                self._refined = self._refined_predictors(self._refined_axis(plans), plans)

    def _check_path_options(self, method: str, grid_given: bool, user_options: list) -> None:
        """GPMSAError for an argument the chosen path (``self.method``; ``method`` as given)
        would take without effect: ``n_grid`` (``grid_given``) or an ``n_draws`` other than
        its default on the MCMC path (whose draws are ``gpmsa.calibrate``'s), the user's
        ``mcmc_options`` (``user_options``, their keys) with ``method="grid"`` given (with
        "auto" they wait for an emulator that needs MCMC), or an ``n_emulator_draws`` other
        than its default with the point estimate."""
        chosen = (" (method='auto' chooses MCMC here: more than 2 parameters, another backend "
                  "than numpy, or a constraint beside a categorical parameter)"
                  if method == "auto" else "")  # fmt: skip
        if self.method == "mcmc" and grid_given:
            raise GPMSAError(
                f"n_grid={self.n_grid} sets the nodes of the exact grid, and this Calibrator runs "
                f"MCMC{chosen}, which has no grid: leave n_grid out"
            )
        if self.method == "mcmc" and self.n_draws != N_DRAWS:
            raise GPMSAError(
                f"n_draws={self.n_draws} sets the draws a grid posterior makes, and this "
                f"Calibrator runs MCMC{chosen}, whose draws are its chains' kept sweeps: leave "
                "n_draws out and give mcmc_options={'n_samples': ..., 'n_burn': ...} (per chain)"
            )
        given = [k for k in user_options if k != "backend"]
        if method == "grid" and given:
            raise GPMSAError(
                f"mcmc_options {given} apply on the MCMC path, and method='grid' computes the "
                "posterior on its exact grid, which would ignore them: use method='mcmc' (or "
                "'auto'), or leave mcmc_options out"
            )
        mode = self.mcmc_options.get("emulator_params", self.emulator_params)
        mode = self.emulator_params if self.method == "grid" else mode
        check_draws_mode(mode, self._n_emulator_draws, "Calibrator")

    def _check_mcmc_path(self, backend: str) -> None:
        """GPMSAError now, not at every update, for MCMC settings ``gpmsa.calibrate`` refuses:
        the emulator's draws on another backend than numpy, or the draws with
        ``mcmc_options={"fast": False}`` (only the fast numpy sampler averages over them)."""
        if self.method != "mcmc":
            return
        opts = self.mcmc_options
        backend = opts.get("backend", backend)
        if backend != "numpy" and self.emulator_params == "draws":
            raise GPMSAError(
                f"emulator_params='draws' needs backend='numpy', got backend={backend!r}"
            )
        if self.emulator_params == "draws" and opts.get("fast") is False:
            raise GPMSAError("emulator_params='draws' needs the fast numpy sampler: drop "
                             "mcmc_options['fast'] = False")  # fmt: skip
        draws = opts.get("emulator_params", self.emulator_params) == "draws"
        _refuse_unused_sampler_options(opts, backend, draws)
        _refuse_placement(opts, backend)
        if backend not in backends.BUILTIN:  # a plug-in: the extensions it does not declare
            backends.check_extensions(backend, self._extensions())

    def _extensions(self) -> tuple[str, ...]:
        """The ``Problem.extensions`` that every MCMC update's problem will use, as far as the
        emulator and ``mcmc_options`` tell before observations come: categorical inputs, a
        mean basis, a theta constraint, and theta elements held (``fixed``, checked as
        ``gpmsa.calibrate`` checks it); discrepancy elements held are left to the update."""
        from gpmsa.calibration.calibrate import calibration_fixed

        opts = self.mcmc_options
        fixed = calibration_fixed(self.emulator, opts.get("fixed"), opts.get("discrepancy"))
        held = isinstance((fixed or {}).get("theta"), dict)  # some elements (all: the vector)
        return extensions_used(getattr(self.emulator, "categorical_mask", None),
                               getattr(self.emulator, "mean_basis", None),
                               opts.get("constraint"), held)  # fmt: skip

    # --- the exact likelihood on a grid ---------------------------------------------------------
    def _marginals(
        self, data: Observations, theta_unit: np.ndarray | None, outside: list | None = None
    ) -> list[LamOsMarginal]:
        """lamOs-marginal likelihoods per emulator parameter set on the fixed grid (None) or on
        the given unit-scale nodes (dense solves); ``outside`` collects each set's
        ``Fit.outside_sds`` (`outside_sds`), on `theta_probe`'s nodes where the fixed grid is
        coarser (its distance otherwise grew as the grid coarsened: n_grid=3 read an
        observation at 0.3 of the range 34 sds outside)."""
        out = []
        d = data.z.size
        refined = self._refined is not None and theta_unit is not None and np.array_equal(
            theta_unit[:, 0], self._refined[0])  # fmt: skip
        coarse = self.n_grid < probe_layout(self.q)[0]  # the fit is judged on the probe
        for k, (gp, pred) in enumerate(zip(self._gps, self._predictors, strict=True)):
            if theta_unit is None:
                mean, cov = pred.predict(data.x)
            elif refined:  # the usual refinement's nodes: prepared for
                mean, cov = self._refined[1][k].predict(data.x)
            else:
                mean, cov = gp.predict(data.x, theta_unit)
            if outside is not None and self._levels is not None:  # (fixed grid only)
                outside.append(self._level_outside(gp, mean, cov, data))
            elif outside is not None and theta_unit is None and coarse:
                probe = gp.predict(data.x, theta_probe(self.q))
                outside.append(outside_sds(*probe, data, probe_layout(self.q)))
            elif outside is not None:  # on the fixed grid (kept only there)
                outside.append(outside_sds(mean, cov, data, (self.n_grid,) * self.q))
            G = mean.shape[0]
            out.append(
                lamos_marginal(
                    mean.reshape(G, d),
                    _block_diag(cov),
                    data.z,
                    data.obs_chol,
                    data.lamos,
                    null=data.obs.n_null,
                )  # fmt: skip
            )
        return out

    def _level_outside(self, gp, mean: np.ndarray, cov: np.ndarray, data: Observations) -> float:
        """``Fit.outside_sds`` of the observation for a categorical theta from the fixed grid's
        predictive ``mean``, ``cov`` (emulator parameter set ``gp``): the continuous nodes of each
        level apart (a datum is met where its residual changes sign between neighbouring nodes of
        one level, never between levels), the nearest over the levels; with fewer continuous nodes
        than `theta_probe`'s, calibrate's probe (`fit_at_levels`)."""
        cont = [k for k, lv in enumerate(self._levels) if lv is None]
        if not cont:  # the nodes are the combinations of levels
            return outside_sds(mean, cov, data, None)
        if self.n_grid < probe_layout(1)[0]:
            fit = fit_at_levels(gp.predict, data, self._levels)
            if fit is not None:
                return fit.outside_sds
        shape = tuple(a.size for a in self._axes)
        rows = np.moveaxis(np.arange(mean.shape[0]).reshape(shape), cont[0], -1)
        return min(outside_sds(mean[r], cov[r], data, (r.size,)) for r in rows)

    @staticmethod
    def _combine(marginals: list[LamOsMarginal]) -> np.ndarray:
        """log of the likelihood averaged over the emulator parameter sets (G,)."""
        if len(marginals) == 1:
            return marginals[0].loglik
        ll = np.stack([m.loglik for m in marginals])
        peak = ll.max(axis=0)
        with np.errstate(under="ignore"):  # sets far below the best: 0
            return peak + np.log(np.mean(np.exp(ll - peak), axis=0))

    def _check_grid_method(self) -> None:
        if self.method != "grid":
            raise GPMSAError(
                "this Calibrator uses MCMC (q > 2 or method='mcmc'); no grid likelihood"
            )

    @underflow_as_zero
    def log_likelihood_grid(
        self, x_obs=None, y_obs=None, extrapolate: bool | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Exact log-likelihood of theta on the fixed grid, lamOs integrated out.

        Returns (theta_grid, loglik): theta_grid native units (read-only), (G,) for one parameter
        or (G, 2) for two (``Calibrator.theta_grid``); loglik (G,) = log p(u_obs | theta) with
        all normalising constants (the density of the reduced observation data u, standardised
        units), lamOs integrated against its prior (each window has its own lamOs); with
        unobserved directions (``ObsProblem.n_null``) a likelihood of theta, not a density.
        Successive independent windows multiply: add their logliks. x_obs, y_obs (or one ObsData)
        and ``extrapolate`` as ``update``'s. Raises GPMSAError for invalid input.
        """
        self._check_grid_method()
        data = reduce(self.emulator, x_obs, y_obs, self._extrapolate(extrapolate))
        seen: list[float] = []
        with one_thread():
            ll = self._combine(self._marginals(data, None, seen))
        fit = Fit(min(seen), 0.0)
        warn_if_outside(fit, far=far_value(self.emulator, data, fit))
        if np.any(np.isnan(ll)):
            raise GPMSAError("the likelihood could not be evaluated for this observation")
        grid = self.theta_grid.view()  # a read-only view of its own
        grid.flags.writeable = False
        return grid, ll

    # --- posterior ------------------------------------------------------------------------------
    def _prior_values(self, prior, theta_unit: np.ndarray, on_grid: bool) -> np.ndarray:
        """User log prior at unit-scale nodes (callable of native theta, or values on the grid,
        interpolated by `interp_log` off the grid)."""
        if prior is None:
            return np.zeros(theta_unit.shape[0])
        if callable(prior):
            native = self.emulator.standardizer.t_from_unit(theta_unit)
            constraints.round_levels(native, self._categorical)
            vals = as_float(prior(native[:, 0] if self.q == 1 else native), "prior(theta)")
            vals = vals.reshape(-1)
            if vals.size != theta_unit.shape[0]:
                raise GPMSAError(
                    f"prior(theta) must return one log density per node ({theta_unit.shape[0]}),"
                    f" got {vals.size}"
                )
        else:
            vals = as_float(prior, "prior")
            G, n = self._theta_unit.shape[0], self.n_grid
            shapes = [(G,)] + ([(n, n)] if self.q == 2 else [])  # (n, n): [first, second]
            if self._levels is not None and self.q == 2:  # rows: the first's nodes
                shapes = [(G,), tuple(a.size for a in self._axes)]
            if vals.shape not in shapes:
                raise GPMSAError(
                    f"prior must be log densities on the Calibrator's grid, of shape "
                    f"{' or '.join(map(str, shapes))} (theta_grid's order), got {vals.shape}"
                )
            vals = vals.reshape(-1)
            check_log_density(vals)
            if on_grid:
                if self._levels is None:  # not square with a categorical axis: not checked
                    _warn_if_narrow_prior(vals, self.n_grid, self.q)
            else:
                vals = interp_log(vals, self._axes[0], theta_unit, smooth=True)
        check_log_density(vals)
        return vals

    def _extrapolate(self, extrapolate: bool | None) -> bool:
        """An update's ``extrapolate``: None the constructor's setting, else a flag."""
        return self.extrapolate if extrapolate is None else check_flag(extrapolate, "extrapolate")

    @underflow_as_zero
    def update(
        self, x_obs=None, y_obs=None, prior=None, seed=None, extrapolate: bool | None = None
    ) -> Posterior:
        """Posterior of the calibration parameters (and lamOs) given one observation window.

        Args:
            x_obs: (n, p) known inputs, native units (e.g. [[v]]); None for an emulator
                without known inputs (p = 0), e.g. ``update(y_obs=[[f]])``.
            y_obs: (n, l_sim) observed outputs, native units (e.g. [[f]]). Or one
                ``gpmsa.ObsData`` as x_obs (y_obs None): experiments on their own index grids
                and with their own precisions (as ``gpmsa.calibrate`` takes it).
            prior: optional extra log prior of theta: log-density values on ``theta_grid`` (G,)
                (for two parameters also (n_grid, n_grid), rows the first parameter;
                interpolated where the grid is refined: in the log by the cubic through the
                four nodes around a point (per parameter) where they are finite and smooth
                (`gpmsa.calibration.local_cubic`: summed log-likelihoods of other windows
                stay accurate when narrower than a node spacing), linearly (bilinearly)
                otherwise, in the density next to a zero (-inf), so that the prior is zero
                beyond its zero nodes), or a callable of
                native theta ((k,) for one parameter, (k, 2) for two) returning (k,); on the
                MCMC path a callable only. It multiplies the emulator's theta prior
                (effectively uniform on the domain). For one parameter a callable's zero
                region (-inf) is cut at its edge, located by bisection as a constraint's
                boundary is; for two the cell at its edge ramps to zero (``constraint`` cuts
                exactly).
            seed: seed (an integer or a numpy Generator) of the lazily drawn samples, or of
                the MCMC (there it wins over
                ``mcmc_options["seed"]``; default: derived from the Calibrator's seed and a
                counter of its updates, an update that raises not counted).
            extrapolate: this update's x_obs rule (``Calibrator(extrapolate=)``'s): None (the
                default) the constructor's setting; True allows x_obs outside the emulator's x
                domain by more than ``EXTRAPOLATION_MARGIN`` (10 %) of a column's width (with
                an ExtrapolationWarning), False refuses it (GPMSAError naming the column).
                Within the margin x_obs is taken with the warning either way. The setting
                of the Calibrator is left as it is.

        Returns:
            Posterior; for the grid method its summaries of theta are exact (grid),
            ``info["resolution"]`` holds per parameter the node spacings per width of its
            marginal (the smaller of its sd and IQR / 1.349: a heavy tail does not hide an
            unresolved core) on the final grid (two parameters; ``grid.resolution``; under
            ``grid.UNRESOLVED_SD`` a warning names it) and ``info["log_evidence"]`` holds
            log p(u_obs) under the emulator's (normalised) theta prior times the given prior
            (as given, unnormalised), for one parameter. With ``emulator_params="draws"``,
            ``info["emulator_draws"]`` holds per draw of ``samples`` the position in
            ``emulator.draws`` of the emulator parameters drawn with it (by their likelihood at
            its node, as lamOs), set when the samples are drawn (lazily, on first access).

        Updates called from several threads take turns (a lock), each counted as one of a
        serial sequence; for the same draws whatever the order, pass each its ``seed``.
        """
        with self._updating:
            if self._in_update:  # this thread, from the prior or constraint of its update
                raise GPMSAError(
                    "Calibrator.update was called from inside an update of the same Calibrator "
                    "(by its prior= or constraint): the two would be counted as one and draw "
                    "with one seed; call update before, or use another Calibrator there (of "
                    "its own seed)"
                )
            self._in_update = True
            try:
                return self._update(x_obs, y_obs, prior, seed, extrapolate)
            finally:
                self._in_update = False

    def _update(self, x_obs, y_obs, prior, seed, extrapolate) -> Posterior:
        """`update`, under its lock."""
        count = self._count + 1  # counted once it succeeds
        extrapolate = self._extrapolate(extrapolate)
        if self.method == "mcmc":
            post = self._update_mcmc(x_obs, y_obs, prior, seed, count, extrapolate)
            self._count = count
            return post
        data = reduce(self.emulator, x_obs, y_obs, extrapolate)
        seen: list[float] = []
        with one_thread():
            margs = self._marginals(data, None, seen)
            outside = min(seen)
            fit = Fit(outside, 0.0)
            warn_if_outside(fit, far=far_value(self.emulator, data, fit))
            axes, theta, ok = self._axes, self._theta_unit, self._base_ok
            free = self._combine(margs) + self._log_prior_theta
            keep = None  # grid lines a refined grid keeps: where a gridded prior's zero ends
            if prior is not None:
                user = self._prior_values(prior, theta, True)
                free = free + user
                if not callable(prior) and self._levels is None and np.isneginf(user).any():
                    keep = zero_edges(self._axes, user)
            logp = constrained(free, ok)
            check_mass(logp)
            if self._levels is not None:  # exact at the levels; the continuous axis per level
                table = None if prior is None or callable(prior) else user
                return self._update_levels(data, free, ok, margs, outside, prior, table, seed,
                                           count)  # fmt: skip
            res = None  # two parameters: the resolution (grid.resolution) of the last grid
            why = "resolved"  # one parameter: why refinement ended (grid.refined_axis)
            for _ in range(MAX_REFINE if self.q == 2 else MAX_REFINE_ONE):
                if self.q == 1:
                    line = None if keep is None else keep[0]
                    finer, why = refined_axis(axes[0], logp, line, self._min_step)
                    finer, last = (None if finer is None else [finer]), why != "refine"
                else:
                    finer = refined_axes(axes, logp, keep)
                    last = finer is None  # resolved, or no refinement factor fits
                if last and self.q == 2:  # heavy tails may be what holds it: one last pass
                    res = resolution(axes, logp)
                    finer = tail_refined_axes(axes, logp, keep, res)
                if finer is None:
                    break
                axes = finer
                margs, free, ok, logp = self._on_grid(data, axes, prior)
                if last:
                    res = resolution(axes, logp)
                    break
        key = run_seed(seed) if seed is not None else (self._entropy, count)
        post = self._posterior(axes, free, ok, margs, key, prior)
        post.info["outside_sds"] = outside
        if prior is None or callable(prior):  # an array: maybe other windows' log-likelihood
            post.info.update(obs_values_sha256=data.values_sha256,
                             obs_layout_sha256=data.layout_sha256)  # fmt: skip
        if self.q == 1 and why != "resolved":  # passes, node budget or float64 ran out
            res = res or resolution(axes, logp)
            if why == "float":
                _warn_at_float(res[0], post.grids[self.emulator.t_names[0]], self.emulator)
            else:
                _warn_if_unresolved(res, tuple(self.emulator.t_names), self.n_grid)
        if self.q == 2:
            post.info["resolution"] = res = res or resolution(axes, logp)
            _warn_if_unresolved(res, tuple(self.emulator.t_names), self.n_grid)
            post.info["conditional_sds"] = sds = conditional_sds(axes, logp)
            _warn_if_ridge(sds, tuple(self.emulator.t_names), self.n_grid)
        self._count = count
        return post

    def _update_levels(
        self, data, free, ok, margs, outside, prior, table, seed, count
    ) -> Posterior:
        """The rest of ``update`` for a categorical theta (`_refine_levels`,
        `_level_posterior`; ``table``: a gridded prior's log values on the fixed grid (G,), or
        None): the ``count``-th update's Posterior, its records and warnings."""
        key = run_seed(seed) if seed is not None else (self._entropy, count)
        refined = self._refine_levels(data, constrained(free, ok), prior, table)
        post = self._level_posterior(free, ok, margs, key, refined)
        post.info["outside_sds"] = outside
        if prior is None or callable(prior):  # an array: maybe other windows' log-likelihood
            post.info.update(obs_values_sha256=data.values_sha256,
                             obs_layout_sha256=data.layout_sha256)  # fmt: skip
        if self.q == 2:
            _warn_if_level_unresolved(post.info["resolution"], tuple(self.emulator.t_names),
                                      self.n_grid)  # fmt: skip
        self._count = count
        return post

    def _refine_levels(self, data, logp: np.ndarray, prior, table) -> dict:
        """A categorical and a continuous parameter: per level holding MODE_MASS of the mass or
        more on the fixed grid (log posterior ``logp`` (G,)), the continuous axis refined as one
        parameter's is (`grid.refined_axis`, at most MAX_REFINE_ONE passes, each recomputing
        the posterior at that level on the finer axis, `_level_row`), where the fixed grid does
        not resolve its density given the level. ``table``: a gridded prior's log values on the
        fixed grid (G,) (interpolated along the level's nodes; the lines where it turns zero
        kept, `grid.zero_edges`), or None. Returns {level index: (unit-scale axis (k,), log
        posterior (k,), lamOs marginals)} of the refined levels ({} where none is)."""
        cont = [k for k, lv in enumerate(self._levels) if lv is None]
        if self.q != 2 or not cont:
            return {}
        c = cont[0]
        shape = tuple(a.size for a in self._axes)
        rows = np.moveaxis(logp.reshape(shape), c, -1)  # (levels, nodes)
        given = None if table is None else np.moveaxis(table.reshape(shape), c, -1)
        axis0 = self._axes[c]
        with np.errstate(under="ignore"):  # levels far below the best: 0
            mass = np.exp(rows - rows.max()) @ trapezoid_weights(axis0)
        step = _float_step(self.emulator.standardizer, c)
        out = {}
        for r in np.flatnonzero(mass >= MODE_MASS * mass.sum()):
            keep = None
            if given is not None and np.isneginf(given[r]).any():
                keep = zero_edges([axis0], given[r])[0]
            axis, row, margs = axis0, rows[r], None
            for _ in range(MAX_REFINE_ONE):
                finer, why = refined_axis(axis, row, keep, step)
                if finer is None:
                    break
                axis = finer
                user = None if given is None else given[r]
                margs, row = self._level_row(data, c, r, axis, prior, user)
                if why != "refine":
                    break
            if margs is not None:
                out[int(r)] = (axis, row, margs)
        return out

    def _level_row(self, data, c: int, r: int, axis: np.ndarray, prior, table) -> tuple:
        """The lamOs marginals and the log posterior (k,) at level ``r`` of the categorical
        parameter on the unit-scale ``axis`` (k,) of the continuous one (element ``c``):
        dense solves, the emulator's theta prior of the continuous element, the user's
        ``prior`` (``table``: its log values along that level on the fixed grid, interpolated
        as `_prior_values` interpolates a gridded prior; None: a callable, or none)."""
        theta = np.empty((axis.size, 2))
        theta[:, c], theta[:, 1 - c] = axis, self._axes[1 - c][r]
        margs = self._marginals(data, theta)
        mean, sd = self.emulator.priors.theta_prior(c)
        logp = self._combine(margs) - 0.5 * ((axis - mean) / sd) ** 2
        if table is not None:
            vals = interp_log(table, self._axes[c], axis[:, None], smooth=True)
            check_log_density(vals)
            logp = logp + vals
        elif prior is not None:
            logp = logp + self._prior_values(prior, theta, False)
        check_mass(logp)
        return margs, logp

    @underflow_as_zero  # a density's far tails underflow to 0 as intended
    def _level_posterior(
        self, free: np.ndarray, ok, margs: list, key, refined: dict | None = None
    ) -> Posterior:
        """The posterior on the fixed grid of a categorical theta, whose nodes (in 'ij' order)
        have the unconstrained log posterior ``free`` (G,), the constraint's verdicts ``ok``
        (G,) (None: none; only where every element is categorical: exact at the levels) and the
        lamOs marginals ``margs``; ``key`` seeds the lazy draws.

        A categorical element's marginal is a `LevelMarginal`: per level, the posterior's
        trapezoid integral over the continuous element's nodes at that level (1 where there is
        none); a continuous element's a `GridMarginal`, the sum over levels of the density at
        its nodes (piecewise linear between them). Draws: a level (or, all categorical, a node)
        by its probability, then the continuous element from its density given that level.
        ``refined`` (`_refine_levels`): the levels whose continuous axis was refined, with
        their axis, log posterior and lamOs marginals there, which replace the fixed grid's at
        those levels (the continuous marginal then on the union of the levels' nodes)."""
        std = self.emulator.standardizer
        names = tuple(self.emulator.t_names)
        shape = tuple(a.size for a in self._axes)
        logp = constrained(free, ok)
        refined = refined or {}
        top = max([float(logp.max())] + [float(row.max()) for _, row, _ in refined.values()])
        dens = np.exp(logp - top).reshape(shape)
        codes = self._codes
        native = [a * (std.t_max[k] - std.t_min[k]) + std.t_min[k] if c is None else c
                  for k, (a, c) in enumerate(zip(self._axes, codes, strict=True))]  # fmt: skip
        w = [trapezoid_weights(a) if c is None else np.ones(a.size)
             for a, c in zip(native, codes, strict=True)]  # fmt: skip
        cont = [k for k, c in enumerate(codes) if c is None]  # at most one (q <= 2)
        mass = dens * (w[0] if self.q == 1 else np.outer(w[0], w[1]))
        per_level = []  # per level: the continuous element's native nodes, density, weights
        if cont:
            c = cont[0]
            span = std.t_max[c] - std.t_min[c]
            rows = np.moveaxis(dens, c, -1)  # (levels, nodes)
            per_level = [(native[c], rows[r], w[c]) for r in range(rows.shape[0])]
            for r, (axis, row, _) in refined.items():
                x = axis * span + std.t_min[c]
                per_level[r] = (x, np.exp(row - top), trapezoid_weights(x))
        grids: dict = {}
        resolved = []
        for k, name in enumerate(names):
            other = tuple(j for j in range(self.q) if j != k)
            if self._codes[k] is not None:
                p = mass.sum(axis=other)
                for r in refined:
                    p[r] = per_level[r][2] @ per_level[r][1]
                grids[name] = LevelMarginal.from_probabilities(native[k], p)
                resolved.append(np.inf)
                continue
            if refined:  # the levels' densities, piecewise linear, summed on all their nodes
                x = np.unique(np.concatenate([a for a, _, _ in per_level]))
                x = x[np.concatenate(([True], np.diff(x) >= _float_step(std, k) * span))]
                total = sum(np.interp(x, a, d, left=0.0, right=0.0) for a, d, _ in per_level)
                with np.errstate(divide="ignore"):
                    grids[name] = trimmed_marginal(x, np.log(total), trapezoid_weights(x))[0]
            else:
                with np.errstate(divide="ignore"):
                    grids[name] = trimmed_marginal(native[k], np.log(dens.sum(axis=other)),
                                                   w[k])[0]  # fmt: skip
            # the worst resolved conditional of a level holding LEVEL_MASS of the mass or more
            p = np.moveaxis(dens, k, -1) @ w[k]
            for r in refined:
                p[r] = per_level[r][2] @ per_level[r][1]
            with np.errstate(divide="ignore"):
                res = [resolution([per_level[r][0]], np.log(per_level[r][1]))[0]
                       for r in np.flatnonzero(p >= LEVEL_MASS * p.sum())]  # fmt: skip
            resolved.append(min(res))
        inv_lamos = _expected_inverse_lamos(margs) if self.q == 1 else None
        log_evidence = None
        if self.q == 1:  # the levels' prior: uniform (calibrate's)
            top = float(logp.max())
            log_evidence = top + float(np.log(np.mean(np.exp(logp - top))))
        n_draws = self.n_draws

        def draw() -> dict[str, np.ndarray]:
            rng = np.random.default_rng(_seed_sequence(key))
            if not cont:  # a node by its probability
                cum = np.cumsum(mass.ravel())
                node = np.minimum(np.searchsorted(cum, rng.random(n_draws) * cum[-1],
                                                  side="right"), cum.size - 1)  # fmt: skip
                idx = np.unravel_index(node, shape)
                out = {name: native[k][idx[k]] for k, name in enumerate(names)}
                out["lamOs"], sets = _draw_lamos(margs, node, rng)
            else:  # a level, then the continuous element given it
                c = cont[0]
                lv = 1 - c
                level = grids[names[lv]].sample(rng, n_draws)
                li = np.searchsorted(native[lv], level)
                vals = np.empty(n_draws)
                for r in np.unique(li):
                    sel = li == r
                    x, row, wr = per_level[r]
                    with np.errstate(divide="ignore"):
                        gm = trimmed_marginal(x, np.log(row), wr)[0]
                    vals[sel] = gm.sample(rng, int(sel.sum()))
                lam = np.empty(n_draws)  # lamOs at each draw's nearest node of its level's grid
                sets = np.empty(n_draws, dtype=int)  # and the emulator parameter set with it
                base = ~np.isin(li, list(refined))
                if base.any():
                    ci = nearest(native[c], vals[base])
                    idx = (li[base], ci) if c == 1 else (ci, li[base])
                    lam[base], sets[base] = _draw_lamos(margs, np.ravel_multi_index(idx, shape),
                                                        rng)  # fmt: skip
                for r, (_, _, level_margs) in refined.items():
                    sel = li == r
                    if sel.any():
                        node = nearest(per_level[r][0], vals[sel])
                        lam[sel], sets[sel] = _draw_lamos(level_margs, node, rng)
                out = {names[lv]: level, names[c]: vals, "lamOs": lam}
            self._record_sets(into, sets)
            return {name: out[name] for name in (*names, "lamOs")}

        info = {
            "method": "grid",
            "expected_inv_lamOs": inv_lamos,
            "names": names + ("lamOs",),
            "n_nodes": int(free.size) + sum(a.size - self.n_grid for a, _, _ in refined.values()),
            "refined": bool(refined),
            "log_evidence": log_evidence,
            "levels": theta_levels_native(self.emulator),  # the codes as calibrate has them
            "emulator_params": self.emulator_params,
            **emulator_record(self.emulator),
            "units": dict(zip(self.emulator.t_names, self.emulator.t_units, strict=True)),
        }
        if self.q == 2:
            info["resolution"] = tuple(resolved)
        post = Posterior(grids=grids, draw=draw, info=info)
        into = post.info  # where draw records (not post: a cycle would outlive the update)
        return post

    def _on_grid(self, data, axes: list, prior) -> tuple:
        """The lamOs marginals, unconstrained log posterior (G,), constraint verdicts (G,) (None:
        no constraint) and log posterior (G,) at the nodes of the refined unit-scale ``axes``."""
        theta = mesh(axes)
        margs = self._marginals(data, theta)
        free = self._combine(margs) + self._theta_prior_at(theta, prior)
        ok = None if self.constraint is None else self._allowed(theta)
        logp = constrained(free, ok)
        check_mass(logp)
        return margs, free, ok, logp

    def _update_mcmc(self, x_obs, y_obs, prior, seed, count: int, extrapolate: bool) -> Posterior:
        """``update`` on the MCMC path, the ``count``-th update: ``gpmsa.calibrate``'s run
        (``sample_calibration``), its convergence judged with several chains only (one online
        chain: fast and silent), its draws never checked against the domain's bounds."""
        from gpmsa.calibration.calibrate import sample_calibration

        if prior is not None and not callable(prior):
            raise GPMSAError(
                "prior= on the MCMC path must be a callable of native theta returning log "
                "densities (values on a theta grid need method='grid': an MCMC Calibrator "
                "has no theta_grid)"
            )
        opts = dict(self.mcmc_options)
        auto = int(_seed_sequence((self._entropy, count)).generate_state(1)[0])
        if seed is not None:  # this update's seed wins over mcmc_options' and the default
            opts["seed"] = run_seed(seed)
        opts.setdefault("seed", auto)
        opts.setdefault("emulator_params", self.emulator_params)
        opts.setdefault("n_emulator_draws", self._n_emulator_draws)
        opts.setdefault("backend", self.backend)
        try:
            run = sample_calibration(self.emulator, x_obs, y_obs, extrapolate=extrapolate,
                                     log_prior=prior, **opts)  # fmt: skip
        except StartRejectedError as exc:  # calibrate's advice names its arguments, not ours
            given = all(k in opts and (v is ... or opts[k] == v) for k, v in exc.remedy.items())
            if given or not exc.remedy:  # the user's own start was rejected: as it is
                raise
            fields = ", ".join(f"{k!r}: {'[...]' if v is ... else repr(v)}"
                               for k, v in exc.remedy.items())  # fmt: skip
            which = "it" if len(exc.remedy) == 1 else "them"
            raise StartRejectedError(
                f"{exc} (a Calibrator takes {which} as mcmc_options={{{fields}}})", exc.remedy
            ) from exc
        if run.info["n_chains"] > 1:
            judge_convergence(run, f"gpmsa.calibrate (backend {opts['backend']!r})")
        return run.posterior()

    def _allowed(self, theta_unit: np.ndarray) -> np.ndarray:
        """(G,) bool: whether the constraint allows each unit-scale node (G, q)."""
        return self.constraint.allows(self.constraint.native(theta_unit))

    def _cut(self, axes: list, ok: np.ndarray) -> tuple[np.ndarray, ...] | ConstraintCut:
        """The constraint's boundary on the grid of unit-scale ``axes`` whose nodes have the
        verdicts ``ok`` (G,): its points between nodes (`_constraint_edges`) for one parameter,
        the grid with the cells it crosses split (`ConstraintCut`) for two."""
        if self.q == 1:
            return self._constraint_edges(axes[0], ok)
        return ConstraintCut.make(axes, ok, self._allowed)

    def _constraint_edges(
        self,
        nodes: np.ndarray,
        ok: np.ndarray,
        allows: Callable | None = None,
        levels: int = 1,
        what: str = "constraint (allowed and forbidden)",
    ) -> tuple[np.ndarray, ...]:
        """Where the constraint's status changes between the unit-scale nodes (k,) (one
        parameter; ``ok`` (k,) their status): (cells i (e,), first (e,), second (e,)), the
        boundary bracketed by adjacent floats in [nodes[i], nodes[i + 1]] (`_bisect`, ``levels``
        steps per call of ``allows``): ``first`` has the status of node i, ``second`` that of
        node i + 1. ``allows`` (unit-scale points (m,) -> status (m,) bool) gives the status
        between nodes (default: the constraint's). A point whose native value is its node's (an
        edge on a node, e.g. ``th[0] > t_min``) is that node. GPMSAError where a bracket ends
        in adjacent floats of one native value: ``what`` (named in it) answered both there."""
        allows = allows or (lambda points: self._allowed(points[:, None]))
        std = self.emulator.standardizer
        span, low = std.t_max[0] - std.t_min[0], std.t_min[0]  # native as `_posterior` has it
        cells = np.flatnonzero(ok[:-1] != ok[1:])
        first, second = _bisect(nodes[cells], nodes[cells + 1], ok[cells], allows, levels)
        same = np.flatnonzero(first * span + low == second * span + low)
        if same.size:  # both verdicts at one native theta: not a function of theta
            value = float(first[same[0]] * span + low)
            raise GPMSAError(
                f"Calibrator: the {what} gave both answers at "
                f"{self.emulator.t_names[0]} = {value!r}: it must be a function of theta alone, "
                "the same answer for the same theta (no random numbers or state)"
            )
        first = np.where(first * span + low == nodes[cells] * span + low, nodes[cells], first)
        second = np.where(
            second * span + low == nodes[cells + 1] * span + low, nodes[cells + 1], second
        )
        return cells, first, second

    def _with_prior_edges(
        self, axis: np.ndarray, total: np.ndarray, ok, margs: list, prior: Callable, base: bool
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One parameter, a callable ``prior`` that is zero somewhere on the unit-scale ``axis``
        (k,): `with_edges` with the edges of its zero region located as a constraint's are (by
        bisection between nodes, together with the constraint's verdict ``ok`` (k,), None:
        none), so that the density ends there instead of ramping to zero across the cell
        beyond. ``total`` (k,): the unconstrained log posterior at the nodes, the prior in it
        (not evaluated there again). The likelihood at a point inserted there is interpolated
        from its nodes (their lamOs marginals ``margs``), the prior evaluated at it."""
        theta = axis[:, None]
        emulator_prior = self._log_prior_theta if base else self._theta_prior_at(theta, None)
        free = self._combine(margs) + emulator_prior  # finite: no zeros of the user's prior

        def user(points: np.ndarray) -> np.ndarray:
            return self._prior_values(prior, points[:, None], False)

        def allows(points: np.ndarray) -> np.ndarray:
            if self.constraint is None:
                inside = np.ones(points.size, bool)
            else:
                inside = self._allowed(points[:, None])
            if inside.any():  # the prior only where the constraint allows
                inside[inside] = np.isfinite(user(points[inside]))
            return inside

        nonzero = np.isfinite(total)  # free is finite: the prior's zeros
        allowed = nonzero if ok is None else ok & nonzero
        levels = PRIOR_BISECT_LEVELS if self.constraint is None else 1  # its fn: point by point
        what = "prior (zero and not)"
        if self.constraint is not None:
            what = "constraint or the prior (allowed and forbidden, or zero and not)"
        edges = self._constraint_edges(axis, allowed, allows, levels, what)
        return with_edges(axis, free, allowed, edges, user, total)

    def _theta_prior_at(self, theta_unit: np.ndarray, prior) -> np.ndarray:
        """The emulator's theta prior plus the user's at refined unit-scale nodes."""
        mean, sd = self.emulator.priors.theta_moments(self.q)
        base = -0.5 * np.sum(((theta_unit - mean) / sd) ** 2, axis=1)
        return base if prior is None else base + self._prior_values(prior, theta_unit, False)

    def _posterior(self, axes: list, free: np.ndarray, ok, margs: list, key, prior) -> Posterior:
        """The grid posterior on the unit-scale ``axes``, whose nodes (in 'ij' order) have the
        unconstrained log posterior ``free`` (G,) (the user's ``prior`` in it), the constraint's
        verdict ``ok`` (G,) (None: no constraint) and the lamOs marginals ``margs``; ``key``
        seeds the lazy draws."""
        std = self.emulator.standardizer
        names = tuple(self.emulator.t_names)
        base = axes is self._axes
        native = [a * (std.t_max[k] - std.t_min[k]) + std.t_min[k] for k, a in enumerate(axes)]
        inv_lamos = None
        if self.q == 1:
            nodes, logd, lik = axes[0], constrained(free, ok), None
            if callable(prior) and np.isneginf(free).any():
                nodes, logd, lik = self._with_prior_edges(axes[0], free, ok, margs, prior, base)
            elif ok is not None:
                edges = self._base_cut if base else self._cut(axes, ok)
                nodes, logd, lik = with_edges(nodes, free, ok, edges)
            inserted = nodes.size > free.size
            x = native[0] if not inserted else nodes * (std.t_max[0] - std.t_min[0]) + std.t_min[0]
            w = self._weights if base and not inserted else trapezoid_weights(x)
            gm, kept = trimmed_marginal(x, logd, w)
            grids = {names[0]: gm}
            peak = float(logd.max())
            with np.errstate(under="ignore"):  # far tails: 0
                log_evidence = float(np.log(w @ np.exp(logd - peak))) + peak
            log_evidence -= float(np.log(std.t_max[0] - std.t_min[0])) + self._log_prior_norm
            inv_lamos = _expected_inverse_lamos(margs)
            if lik is not None or kept.stop - kept.start < x.size:
                lik = np.arange(x.size) if lik is None else lik
                inv_lamos = inv_lamos[lik][kept]
        else:
            shape = (axes[0].size, axes[1].size)
            cut = None if ok is None else self._base_cut if base else self._cut(axes, ok)
            with np.errstate(under="ignore"):  # a density's far tails underflow to 0
                if cut is None:
                    dens = np.exp(free - free.max()).reshape(shape)
                    split = native
                else:  # the free density, cut by the constraint on the split grid
                    logd = np.where(cut.live.ravel(), free, -np.inf)
                    dens = cut.density(np.exp(logd - logd.max()).reshape(shape))
                    split = [a * (std.t_max[k] - std.t_min[k]) + std.t_min[k]
                             for k, a in enumerate(cut.axes)]  # fmt: skip
            w = [trapezoid_weights(a) for a in split]
            with np.errstate(divide="ignore", under="ignore"):
                grids = {
                    names[0]: trimmed_marginal(split[0], np.log(dens @ w[1]))[0],
                    names[1]: trimmed_marginal(split[1], np.log(w[0] @ dens))[0],
                }
            log_evidence = None
        n_draws = self.n_draws

        def draw() -> dict[str, np.ndarray]:
            rng = np.random.default_rng(_seed_sequence(key))
            if self.q == 1:
                th = grids[names[0]].sample(rng, n_draws)
                out = {names[0]: th}
                node = nearest(x, th)
                node = node if lik is None else lik[node]
            elif ok is None:
                vals, node = draw_bilinear(native, dens, rng, n_draws)
                out = {name: vals[:, k] for k, name in enumerate(names)}
            else:  # no draw where the constraint forbids: redrawn
                vals = draw_allowed(split, dens, rng, n_draws, self.constraint.allows)
                out = {name: vals[:, k] for k, name in enumerate(names)}
                node = nearest(native[0], vals[:, 0]) * native[1].size
                node += nearest(native[1], vals[:, 1])
            out["lamOs"], sets = _draw_lamos(margs, node, rng)
            self._record_sets(into, sets)
            return out

        info = {
            "method": "grid",
            "expected_inv_lamOs": inv_lamos,
            "names": names + ("lamOs",),
            "n_nodes": int(free.size),
            "refined": not base,
            "log_evidence": log_evidence,
            "emulator_params": self.emulator_params,
            **emulator_record(self.emulator),  # its model_sha256, computed once per emulator
            "units": dict(zip(self.emulator.t_names, self.emulator.t_units, strict=True)),
        }
        post = Posterior(grids=grids, draw=draw, info=info)
        into = post.info  # where draw records (not post: a cycle would outlive the update)
        return post

    def _record_sets(self, info: dict, sets: np.ndarray) -> None:
        """With ``emulator_params="draws"``, ``info["emulator_draws"]`` of a grid posterior, set
        as its draws are made: per draw, the position in ``emulator.draws`` of the emulator
        parameter set drawn with it (``sets`` (n,): indices of the averaged sets), the record
        ``gpmsa.calibrate(..., emulator_params="draws")`` keeps (``draws=True`` predictions pair
        by it). The point estimate has none to record."""
        if self.emulator_params == "draws":
            info["emulator_draws"] = draw_positions(self.emulator, self._n_emulator_draws)[sets]


def log_theta_norm(theta_mean: float, theta_sd: float) -> float:
    """log of the integral over (0, 1) of exp(-((t - theta_mean) / theta_sd)**2 / 2): the
    normaliser of theta's truncated normal prior (unit scale), finite for every prior that
    ``Priors`` accepts: an interval narrow in sd units (theta_sd >> 1) by the midpoint rule with
    its second-order term (the difference of two normal CDFs would cancel to 0), a wider one by
    ``log_ndtr`` on the lower tail (a mean far outside (0, 1) underflows ``ndtr``)."""
    a, b = -theta_mean / theta_sd, (1.0 - theta_mean) / theta_sd
    h, c = (b - a) / 2.0, (a + b) / 2.0  # 2 h theta_sd = 1
    if h * max(1.0, abs(c)) < 1e-4:  # relative error O((h c)**4)
        return float(-0.5 * c * c + np.log1p((c * c - 1.0) * h * h / 6.0))
    if c > 0.0:  # by symmetry, where log_ndtr keeps its precision
        a, b = -b, -a
    lb, la = float(log_ndtr(b)), float(log_ndtr(a))
    with np.errstate(under="ignore"):  # a lower tail far below the upper one: 0
        return float(np.log(theta_sd * np.sqrt(2.0 * np.pi)) + lb + np.log1p(-np.exp(la - lb)))


def _warn_at_float(res: float, marginal, emulator) -> None:
    """Warn when the one-parameter posterior's sd spans fewer than UNRESOLVED_SD node spacings
    where refinement stopped at float64's resolution of the parameter (``marginal``: its
    GridMarginal, native units)."""
    if res < UNRESOLVED_SD:
        name, unit = emulator.t_names[0], emulator.t_units[0]
        k = int(np.argmax(marginal.density))
        h = float(np.diff(marginal.nodes)[max(k - 1, 0) : k + 1].max())
        warnings.warn(
            f"the posterior of {name} is narrower than the grid can represent: refinement "
            f"reached float64's resolution of {name} with its width (the smaller of its sd and "
            f"IQR / 1.349) spanning {numbers_text(res, UNRESOLVED_SD, digits=2)[0]} node "
            f"spacings (fewer than {UNRESOLVED_SD:g}); its "
            "sd, quantiles and draws are good "
            f"to about the node spacing there, {h:.3g}{f' {unit}' if unit else ''}",
            GridResolutionWarning,
            stacklevel=user_stacklevel(),
        )


def _warn_if_narrow_prior(table: np.ndarray, n_grid: int, q: int) -> None:
    """Warn when a prior given on the grid is narrower than its interpolation between nodes
    keeps accurate (`local_cubic.NARROW_PRIOR_SD`)."""
    sd, least = narrowest_sd(table, n_grid, q), NARROW_PRIOR_SD[q]
    if sd < least:
        warnings.warn(
            f"prior= given on the grid is narrower than the grid represents: its sd at its peak"
            f"{' (given the other parameter)' if q == 2 else ''} spans "
            f"{numbers_text(sd, least, digits=2)[0]} node spacings "
            f"(fewer than {least:g}); "
            f"between the nodes it is interpolated, so the posterior may be a tenth of its sd "
            f"or more off and too wide; pass prior= as a callable of theta, or use a Calibrator "
            f"with a larger n_grid (now {n_grid})",
            GridResolutionWarning,
            stacklevel=user_stacklevel(),
        )


def _warn_if_unresolved(res: tuple[float, ...], names: tuple, n_grid: int) -> None:
    """Warn when a marginal spans fewer than UNRESOLVED_SD node spacings per sd on the grid
    refinement ended with (`gpmsa.calibration.grid.resolution`)."""
    k = int(np.argmin(res))
    if res[k] < UNRESOLVED_SD:
        warnings.warn(
            f"the grid does not resolve the posterior of {names[k]}: its width (the smaller of its "
            f"sd and IQR / 1.349) spans {numbers_text(res[k], UNRESOLVED_SD, digits=2)[0]} "
            "node spacings (fewer than "
            f"{UNRESOLVED_SD:g}) on the grid refinement ended with, so "
            f"its quantiles, cdf and draws may be off by several per cent of an sd; use "
            f"method='mcmc' or another n_grid (now {n_grid})",
            GridResolutionWarning,
            stacklevel=user_stacklevel(),
        )


def _warn_if_level_unresolved(res: tuple[float, ...], names: tuple, n_grid: int) -> None:
    """Warn where the continuous parameter's density given a level (one holding LEVEL_MASS of
    the mass or more) spans fewer than UNRESOLVED_SD node spacings per width on the grid its
    refinement ended with (`Calibrator._refine_levels`)."""
    k = int(np.argmin(res))
    if res[k] < UNRESOLVED_SD:
        warnings.warn(
            f"the grid does not resolve the posterior of {names[k]} given the level of "
            f"{names[1 - k]}: its width spans {numbers_text(res[k], UNRESOLVED_SD, digits=2)[0]} "
            "node spacings (fewer than "
            f"{UNRESOLVED_SD:g}) on the grid refinement ended with, so its summaries, draws "
            f"and the levels' probabilities may be off; use a larger n_grid (now {n_grid}) or "
            f"method='mcmc'",
            GridResolutionWarning,
            stacklevel=user_stacklevel(),
        )


def _float_step(std, k: int) -> float:
    """The least spacing of refined nodes of calibration parameter ``k`` (unit scale): MIN_STEP_ULPS
    float64 spacings, in the unit scale and in its native units (``std``: the standardizer)."""
    lo, hi = float(std.t_min[k]), float(std.t_max[k])
    return MIN_STEP_ULPS * max(np.spacing(1.0), np.spacing(max(abs(lo), abs(hi))) / (hi - lo))


def _level_codes(emulator) -> list[np.ndarray | None]:
    """Per calibration parameter, its training levels (native codes, float) or None."""
    p = emulator.x_unit.shape[1]
    return [None if lv is None else np.asarray(lv, dtype=np.float64)
            for lv in emulator.levels[p:]]  # fmt: skip


def _warn_if_ridge(sds: tuple[float, float], names: tuple, n_grid: int) -> None:
    """Warn when the two-parameter posterior is a ridge narrower than the grid resolves: its sd
    along a parameter given the other spans fewer than RIDGE_SD node spacings
    (`conditional_sds`)."""
    k = int(np.argmin(sds))
    if sds[k] < RIDGE_SD:
        warnings.warn(
            f"the grid does not resolve the posterior (a ridge across both parameters, or a "
            f"peak narrower than refinement reaches): the sd of {names[k]} given "
            f"{names[1 - k]} spans {numbers_text(sds[k], RIDGE_SD, digits=2)[0]} node spacings "
            f"(fewer than {RIDGE_SD:g}), so its "
            f"summaries and draws may be off by a large fraction of an sd; use a larger n_grid "
            f"(now {n_grid}) or method='mcmc'",
            GridResolutionWarning,
            stacklevel=user_stacklevel(),
        )


def _seed_sequence(key) -> np.random.SeedSequence:
    """A SeedSequence from a seed or an (entropy, counter) pair."""
    if isinstance(key, tuple) and len(key) == 2 and isinstance(key[1], int):
        return np.random.SeedSequence(key[0], spawn_key=(key[1],))
    return np.random.SeedSequence(key)


def _block_diag(cov: np.ndarray) -> np.ndarray:
    """(G, p_u, n, n) per-component covariances -> (G, d, d) block-diagonal, d = p_u n."""
    G, p_u, n, _ = cov.shape
    if p_u == 1:
        return cov[:, 0]
    out = np.zeros((G, p_u * n, p_u * n))
    for c in range(p_u):
        out[:, c * n : (c + 1) * n, c * n : (c + 1) * n] = cov[:, c]
    return out


@underflow_as_zero  # a density's far tails underflow to 0 as intended
def _expected_inverse_lamos(margs: list[LamOsMarginal]) -> np.ndarray:
    """(G,) E[1/lamOs | data, theta node]: the observation-error variance (standardised units)
    expected at each theta node; several emulator parameter sets are weighted by their
    likelihood at the node."""
    per_set = np.stack(
        [
            np.exp(m.log_cond(np.arange(m.loglik.size)) - m.log_lam[None, :]).sum(axis=1)
            for m in margs
        ]
    )  # (J, G)
    if len(margs) == 1:
        return per_set[0]
    ll = np.stack([m.loglik for m in margs])  # (J, G)
    p = np.exp(ll - ll.max(axis=0, keepdims=True))
    return (p * per_set).sum(axis=0) / p.sum(axis=0)


@underflow_as_zero
def _draw_lamos(
    margs: list[LamOsMarginal], node: np.ndarray, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """lamOs draws from its conditional at the given theta nodes (log-grid cell jitter: within
    half a step of the node, inwards only at the end nodes, whose trapezoid cells are half ones,
    so that no draw lies beyond a bound of the lamOs prior that ends the grid); with several
    emulator parameter sets, each draw's set is chosen by its likelihood at the node (the
    mixture's joint draw of theta, the set and lamOs). Returns (lamOs (n,), set index (n,))."""
    k = np.zeros(node.size, dtype=int)
    if len(margs) > 1:
        ll = np.stack([m.loglik[node] for m in margs], axis=1)  # (n, J)
        p = np.exp(ll - ll.max(axis=1, keepdims=True))
        cum = np.cumsum(p, axis=1)
        k = (cum < rng.random(node.size)[:, None] * cum[:, -1:]).sum(axis=1)
    out = np.empty(node.size)
    for j in np.unique(k):
        sel = k == j
        s = margs[j].log_lam
        cum = np.cumsum(np.exp(margs[j].log_cond(node[sel])), axis=1)
        u = rng.random(int(sel.sum())) * cum[:, -1]
        idx = np.minimum((cum < u[:, None]).sum(axis=1), s.size - 1)
        jitter = (rng.random(idx.size) - 0.5) * (s[1] - s[0])
        jitter = np.where(idx == 0, np.abs(jitter), jitter)
        jitter = np.where(idx == s.size - 1, -np.abs(jitter), jitter)
        out[sel] = np.exp(s[idx] + jitter)
    return out, k


def _bisect(
    a: np.ndarray, b: np.ndarray, side: np.ndarray, allows: Callable, levels: int
) -> tuple[np.ndarray, np.ndarray]:
    """The brackets [a, b] (e,) of changes of status, each bisected to adjacent floats (at most
    BISECT_STEPS steps; ``side`` (e,) the status at a): ``levels`` steps per call of ``allows``
    (unit-scale points (m,) -> status (m,)), at the 2**levels - 1 midpoints those steps of each
    bracket may visit, so that the result is that of one point per step."""
    a, b, side = a.tolist(), b.tolist(), side.tolist()
    live, steps = list(range(len(a))), 0
    while live and steps < BISECT_STEPS:
        depth = min(levels, BISECT_STEPS - steps)
        mids = [_midpoints(a[j], b[j], depth) for j in live]
        status = allows(np.array(mids).ravel()).tolist()
        n, more = len(mids[0]), []
        for r, j in enumerate(live):
            a[j], b[j], go_on = _walk(a[j], b[j], mids[r], status[r * n : r * n + n], side[j])
            if go_on:
                more.append(j)
        live, steps = more, steps + depth
    return np.array(a, dtype=np.float64), np.array(b, dtype=np.float64)


def _midpoints(a: float, b: float, depth: int) -> list[float]:
    """The 2**depth - 1 midpoints that ``depth`` bisection steps of [a, b] may visit, in
    increasing order (each the midpoint of its neighbours at the step that makes it)."""
    points = [a, b]
    for _ in range(depth):
        finer = [a]
        for lo, hi in zip(points[:-1], points[1:], strict=True):
            finer += (0.5 * (lo + hi), hi)
        points = finer
    return points[1:-1]


def _walk(a: float, b: float, mids: list, status: list, side: bool) -> tuple[float, float, bool]:
    """Bisection steps of [a, b] through its ``_midpoints`` ``mids``, moving a up to a midpoint
    whose ``status`` is ``side`` (a's): the bracket, and whether it can be bisected further."""
    lo, hi = -1, len(mids)  # the bracket's ends' places among the midpoints
    while hi - lo > 1:
        k = (lo + hi) // 2
        if not a < mids[k] < b:
            return a, b, False
        if status[k] == side:
            a, lo = mids[k], k
        else:
            b, hi = mids[k], k
    return a, b, True


def _check_predictor_memory(
    gps: list, plans: list, n_nodes: int, refined: np.ndarray | None, other: float, what: str
) -> None:
    """ResourceLimitError before the grid's predictors are built where they, with the prepared
    refinement's (``refined``: its axis, or None) and Sigma_W's factors of every emulator
    parameter set, and ``other`` bytes, would need more than ``gpmsa.limits.MAX_MEMORY_BYTES``:
    their Chebyshev products H (nodes x (degree + 1)^2 per component) can be most of it."""
    total, peak = other, 0.0
    degree = 0
    for gp, plan in zip(gps, plans, strict=True):
        total += 8.0 * gp.p_u * gp.m * gp.m
        for nodes in (n_nodes,) if refined is None else (n_nodes, refined.size):
            kept, building = predictor_bytes(gp, nodes, plan)
            total += kept
            peak = max(peak, building)
        degree = max([degree] + ([] if plan is None else [cf.shape[0] - 1 for cf in plan]))
    extra = f", Chebyshev degree {degree}" if degree else ""
    extra += "" if refined is None else f", and {refined.size} nodes of a refined grid"
    check_memory(total + peak, what + extra)
