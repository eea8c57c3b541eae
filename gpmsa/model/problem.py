"""The sampling problem: everything a backend needs, in unit/standardised units."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.linalg import cho_factor, cho_solve

from gpmsa.errors import (
    ExtrapolationWarning,
    GPMSAError,
    ReductionWarning,
    numbers_text,
    user_stacklevel,
)
from gpmsa.model import categorical, index_points, kronecker
from gpmsa.model import fixed_elements as per_element
from gpmsa.model import mean_basis as mean_basis_mod
from gpmsa.model.basis import (
    basis_weights,
    discrepancy_bases,
    given_basis,
    interpolate_basis,
    pca_basis,
    variance_shares,
    warn_weight_scale,
)
from gpmsa.model.constraints import ThetaConstraint
from gpmsa.model.data import ObsData, SimData, array_text, as_float, check_finite
from gpmsa.model.discrepancy import check_groups, n_groups
from gpmsa.model.index_points import is_points
from gpmsa.model.priors import Priors
from gpmsa.model.transforms import EXTRAPOLATION_MARGIN, Standardizer

ORDER = ("theta", "betaV", "betaU", "lamVz", "lamUz", "lamWs", "lamWOs", "lamOs")
"""GPM/SA's sweep order; absent or fixed parameters are skipped."""

GLS_RIDGE = 1e-6
SIGOBS_RIDGE = 1e-8


@dataclass(frozen=True, eq=False)
class ObsProblem:
    """Observation side of the model, in unit/standardised units.

    x (n, p) unit inputs; u (n, p_u) and v (n, p_v) the reduced data (GLS of y_obs on [D, K]);
    sig_obs (N, N) the covariance of the stacked reduced data per unit lamOs (N = n (p_v + p_u),
    or n for a scalar output, where u and v share one block). p_v: number of discrepancy basis
    vectors (0: no discrepancy; a scalar output has v empty and p_v 0 or 1). scalar_out: a
    scalar simulation output (one value per experiment). y_std: each experiment's observed y
    on the standardised scale (for the figures; empty: not kept).
    The stacked order is GPM/SA's:
    v component 0 over all experiments, v component 1, ..., then u components likewise.
    K, D: per-experiment bases on the observation grids (D None without discrepancy).
    v_groups: the precision group of each discrepancy basis vector (GPM/SA's lamVzGroup;
    None: one group, `gpmsa.model.discrepancy`).
    n_null: the directions of the reduced data that no value observed (an experiment with fewer
    independent values than the n_c basis vectors it is reduced onto, or its discrepancy
    weights where its basis in a list is zero: it has no discrepancy). GPM/SA's reduction gives
    each a datum 0 of variance ~1e6 / lamOs, which adds ~log(lamOs) / 2 to the log-likelihood
    and pulls lamOs up; every likelihood takes ``null_term(lamOs)`` off again.
    """

    x: np.ndarray
    u: np.ndarray
    v: np.ndarray
    sig_obs: np.ndarray
    scalar_out: bool
    K: tuple[np.ndarray, ...]
    D: tuple[np.ndarray, ...] | None
    p_v: int = 0
    y_std: tuple[np.ndarray, ...] = field(repr=False, default=())
    v_groups: tuple[int, ...] | None = None
    n_null: int = 0

    def __post_init__(self) -> None:
        if not self.scalar_out and self.p_v != self.v.shape[1]:
            raise GPMSAError(f"p_v = {self.p_v} but v has {self.v.shape[1]} columns")
        if self.v_groups is not None and len(self.v_groups) != self.p_v:
            raise GPMSAError(f"p_v = {self.p_v} but v_groups has {len(self.v_groups)} entries")

    def null_term(self, lam_os: float) -> float:
        """-n_null log(lamOs) / 2: the unobserved directions' dependence on lamOs, which the
        log-likelihood of the reduced data takes off (0 without them)."""
        return -0.5 * self.n_null * math.log(lam_os) if self.n_null else 0.0

    @property
    def n_groups(self) -> int:
        """Number of discrepancy precision groups (1 without a discrepancy too)."""
        return n_groups(self.v_groups)

    @property
    def block_groups(self) -> tuple[int, ...]:
        """The group of each n-block that receives a discrepancy covariance (the p_v v blocks;
        a scalar output's one shared block); empty without a discrepancy."""
        if not self.p_v:
            return ()
        if self.scalar_out:
            return (0,)
        return self.v_groups or (0,) * self.p_v

    @property
    def n(self) -> int:
        """Number of experiments."""
        return self.x.shape[0]

    @property
    def z(self) -> np.ndarray:
        """Stacked reduced data (N,): [v comps; u comps], or u for a scalar output."""
        if self.scalar_out:
            return self.u[:, 0].copy()
        return np.concatenate([self.v.T.reshape(-1), self.u.T.reshape(-1)])


@dataclass(frozen=True, eq=False)
class Problem:
    """What every sampler works on (unit scale inputs, standardised outputs).

    x_sim (m, p), t_sim (m, q) on [0, 1]; w (m, p_u) basis weights; lam_sim (p_u,) = diag(K^T K);
    priors (with data corrections); init: initial value of every parameter; fixed: names held
    at their init value; obs: the observation side (None: the sim-only emulator model).
    categorical: boolean mask (p + q,) of the categorical inputs (None: none); mean_basis: the
    weights' GP mean basis (None: zero mean); constraint: allowed region of unit-scale theta
    (None: all of it). See docs/categorical-and-constraints.md.
    fixed_elements: name -> the elements (index tuples) of a parameter not in ``fixed`` held at
    their init value, the others sampled (``gpmsa.model.fixed_elements``).
    separable: the factor structure of a separable design (``gpmsa.model.kronecker``; None:
    none), whose likelihood the numpy sampler takes through the factors.
    """

    x_sim: np.ndarray
    t_sim: np.ndarray
    w: np.ndarray
    lam_sim: np.ndarray
    priors: Priors
    init: dict[str, np.ndarray]
    fixed: frozenset[str] = frozenset()
    obs: ObsProblem | None = None
    categorical: np.ndarray | None = None
    mean_basis: mean_basis_mod.MeanBasis | None = None
    constraint: ThetaConstraint | None = None
    fixed_elements: dict[str, frozenset[tuple[int, ...]]] = field(default_factory=dict)
    separable: kronecker.Separable | None = None

    def __post_init__(self) -> None:
        """GPMSAError when per-element theta priors do not give one prior per calibration
        parameter, or per-group lamVz or betaV priors one per discrepancy precision group
        (``Priors.theta_moments``, ``Priors.lamvz_priors``, ``Priors.rhov_priors``), before any
        sampling."""
        self.priors.theta_moments(self.q)
        if self.obs is not None and self.obs.p_v:
            self.priors.lamvz_priors(self.obs.n_groups)
            self.priors.rhov_priors(self.obs.n_groups)

    @property
    def m(self) -> int:
        """Number of simulation runs."""
        return self.x_sim.shape[0]

    @property
    def p(self) -> int:
        """Number of known inputs."""
        return self.x_sim.shape[1]

    @property
    def q(self) -> int:
        """Number of calibration parameters."""
        return self.t_sim.shape[1]

    @property
    def p_u(self) -> int:
        """Number of emulator basis vectors."""
        return self.w.shape[1]

    @property
    def zt(self) -> np.ndarray:
        """Simulation design (m, p + q) = [x_sim, t_sim]."""
        return np.hstack([self.x_sim, self.t_sim])

    @property
    def names(self) -> tuple[str, ...]:
        """Parameters of this model in sweep order (fixed ones included)."""
        return tuple(n for n in ORDER if n in self.init)

    @property
    def extensions(self) -> tuple[str, ...]:
        """The features beyond GPM/SA's model this problem uses (categorical inputs, a mean
        basis, a theta constraint, held elements of a sampled parameter): the numpy and torch
        backends sample them, pyro some (``gpmsa.backends.pyro_backend.refuse_unsupported``),
        a plug-in those it declares (``gpmsa.backends.register``)."""
        return extensions_used(self.categorical, self.mean_basis, self.constraint,
                               any(self.fixed_elements.values()))  # fmt: skip

    @property
    def callables(self) -> list[str]:
        """The callables of this process the problem holds, by the argument that gave them (a
        theta constraint, a callable mean basis): its chains run in this process, one after
        another (``gpmsa.mcmc.parallel.in_this_process``: a lambda cannot go to a worker)."""
        mean = self.mean_basis
        return [name for name, on in (
            ("constraint", self.constraint is not None),
            ("mean_basis", mean is not None and mean.kind == "callable"),
        ) if on]  # fmt: skip

    @property
    def theta_levels(self) -> list[np.ndarray | None] | None:
        """Per calibration parameter, its levels on the unit scale if categorical (the design's
        values), else None; None when no calibration parameter is categorical."""
        if self.categorical is None or not self.categorical[self.p :].any():
            return None
        cat = self.categorical[self.p :]
        return [np.unique(self.t_sim[:, k]) if cat[k] else None for k in range(self.q)]

    def theta_log_prior(self, theta: np.ndarray) -> float:
        """Log prior of unit-scale theta (q,): the priors' truncated normal for the continuous
        elements; uniform over its levels (-inf off them) for a categorical one."""
        return theta_log_prior(self.priors, self.theta_levels, theta)

    def snap_theta(self, theta: np.ndarray) -> np.ndarray:
        """``theta`` (unit scale, (q,)) with each categorical element moved to its nearest level."""
        return categorical.snap_to_levels(theta, self.theta_levels or ())

    @property
    def sampled(self) -> tuple[str, ...]:
        """Parameters updated by the sampler, in sweep order."""
        return tuple(n for n in self.names if n not in self.fixed)

    def with_init(self, values: dict[str, np.ndarray], fixed: frozenset[str] | None = None):
        """A copy with some initial values replaced (and optionally a new fixed set)."""
        init = dict(self.init)
        for name, val in values.items():
            if name not in init:
                raise GPMSAError(f"unknown parameter {name!r}; this model has {self.names}")
            val = np.array(val, dtype=np.float64).reshape(init[name].shape)
            init[name] = val
        if fixed is None:
            return replace(self, init=init)
        held = {k: v for k, v in self.fixed_elements.items() if k not in fixed}
        return replace(self, init=init, fixed=frozenset(fixed), fixed_elements=held)

    def held_masks(self, names=None) -> dict[str, np.ndarray]:
        """name -> boolean mask (the parameter's shape) of its held elements, for each parameter
        the problem holds (``fixed``: every element; ``fixed_elements``: those), in ``names``
        (None: every parameter; a calibration passes its own, as its emulator's are held
        whole)."""
        out = {}
        for k in self.names:
            if (names is None or k in names) and (k in self.fixed or self.fixed_elements.get(k)):
                mask = np.full(self.init[k].shape, k in self.fixed)
                for idx in self.fixed_elements.get(k, ()):
                    mask[idx] = True
                out[k] = mask
        return out

    def with_fixed(self, values: dict) -> Problem:
        """A copy holding the parameters in ``values`` (name -> value on the model's scales,
        scalar or the parameter's shape) at those values; a value given as a dict element index
        -> value holds those elements only (``gpmsa.model.fixed_elements``; naming every
        element holds the whole parameter). GPMSAError naming an unknown parameter, a wrong
        shape or index, a non-finite value or one outside its prior's bounds."""
        if not isinstance(values, dict):
            raise GPMSAError(f"fixed must be a dict name -> value, got {type(values).__name__}")
        out, held = {}, {}
        for name, val in values.items():
            if name not in self.init:
                raise GPMSAError(f"fixed: unknown parameter {name!r}; this model has {self.names}")
            value = checked_fixed(name, val, self.init[name].shape, self.priors, self.theta_levels)
            if isinstance(value, dict):
                held[name] = value
            else:
                out[name] = value
        return self._holding(out, held)

    def _holding(self, whole: dict[str, np.ndarray], held: dict[str, dict]) -> Problem:
        """A copy with the parameters in ``whole`` fixed at those arrays and the elements in
        ``held`` (name -> index -> value) held, the theta constraint checked at the new start;
        a parameter whose every element ends up held is fixed whole."""
        values = dict(whole)
        for name, elements in held.items():
            arr = self.init[name].copy()
            for idx, x in elements.items():
                arr[idx] = x
            values[name] = arr
        if "theta" in values and self.constraint is not None:  # held elements: theta_init helps
            what = "fixed theta" if "theta" in whole else "fixed theta (held elements)"
            self.constraint.check_start(values["theta"], what)
        prob = self.with_init(values, self.fixed | frozenset(whole))
        merged = dict(prob.fixed_elements)
        for name, elements in held.items():
            merged[name] = merged.get(name, frozenset()) | frozenset(elements)
        full = {k for k, v in merged.items() if len(v) == self.init[k].size}
        merged = {k: v for k, v in merged.items() if k not in full}
        return replace(prob, fixed=prob.fixed | full, fixed_elements=merged)


def extensions_used(categorical, mean_basis, constraint, held: bool) -> tuple[str, ...]:
    """The names of ``Problem.extensions`` that a problem with these ``categorical`` (mask or
    None), ``mean_basis``, ``constraint`` (None: without it) and ``held`` elements uses; a
    ``Calibrator`` names those its emulator and options give before any problem is built."""
    used = (("categorical inputs", categorical is not None),
            ("mean_basis", mean_basis is not None),
            ("theta constraint", constraint is not None),
            ("held elements", held))  # fmt: skip
    return tuple(name for name, on in used if on)


def theta_log_prior(priors: Priors, levels, theta) -> float:
    """Log prior of unit-scale theta (q,) under ``priors``: the truncated normal for the
    continuous elements; uniform over its levels (-inf off them) for a categorical one.
    ``levels``: per element its unit-scale levels or None (``Problem.theta_levels``); None:
    every element continuous."""
    if levels is None:
        return priors.log_prior("theta", theta)
    theta = np.asarray(theta, dtype=np.float64).reshape(-1)
    if any(lv is not None and not np.any(lv == v) for lv, v in zip(levels, theta, strict=True)):
        return -np.inf
    cont = [k for k, lv in enumerate(levels) if lv is None]
    return priors.log_theta(theta[cont], cont) if cont else 0.0


def fixed_record(problem: Problem, names=None) -> dict:
    """``settings["fixed"]`` (``per_element.record``): name -> the value list of each parameter
    fixed whole (as files always held), or for one with held elements {"elements": [index,
    ...], "values": [...]} (model scales; theta unit scale), by name; ``names``: only these
    (None: every one the problem holds)."""
    values = {k: problem.init[k] for k in problem.fixed}
    values.update({k: {i: problem.init[k][i] for i in held}
                   for k, held in problem.fixed_elements.items()})  # fmt: skip
    return per_element.record({k: v for k, v in values.items() if names is None or k in names})


def checked_fixed(name: str, val, shape: tuple[int, ...], priors: Priors, theta_levels=None):
    """One entry of ``fixed=`` (``Problem.with_fixed``) checked: the parameter ``name`` of
    ``shape`` held at ``val`` (model scales; theta unit scale). Returns the whole array (a
    scalar, an array of ``shape``, or a dict naming every element), or for a dict naming some
    elements index -> value (``gpmsa.model.fixed_elements``). ``theta_levels`` as
    `theta_log_prior`'s. GPMSAError naming a wrong shape or index, a non-finite value or one
    outside its prior's bounds."""
    if isinstance(val, dict):
        elements = per_element.parse(name, val, shape)
        levels = (theta_levels or [None] * shape[0]) if name == "theta" else None
        per_element.check_values(name, elements, priors, levels)
        if len(elements) < math.prod(shape):
            return elements
        val = np.array(list(elements.values())).reshape(shape)  # C order: every element
    arr = as_float(val, f"fixed[{name!r}]")
    if arr.size == 1:
        arr = np.full(shape, float(arr.reshape(-1)[0]))
    elif [d for d in arr.shape if d != 1] != [d for d in shape if d != 1]:
        # another layout (a transposed betaU) would be reshuffled, not read
        raise GPMSAError(f"fixed[{name!r}] must be a scalar or have shape {shape}, got {arr.shape}")
    arr = arr.reshape(shape)
    if not np.all(np.isfinite(arr)):
        raise GPMSAError(f"fixed[{name!r}] must be finite, got {array_text(arr.ravel())}")
    is_theta = name == "theta"
    lp = theta_log_prior(priors, theta_levels, arr) if is_theta else priors.log_prior(name, arr)
    if lp == -np.inf:
        raise GPMSAError(
            f"fixed[{name!r}] = {array_text(arr.ravel())} lies outside its prior's bounds "
            "(zero prior density)"
        )
    return arr


def default_init(p: int, q: int, p_u: int, priors: Priors, obs: ObsProblem | None) -> dict:
    """GPM/SA's initial values (the table in docs/internals.md)."""
    lw = priors.lamWOs
    init = {
        "betaU": np.full((p + q, p_u), 0.1),
        "lamUz": np.ones(p_u),
        "lamWs": np.full(p_u, 1000.0),
        "lamWOs": np.array([min(max(100.0, lw.a / lw.b), 1e5 - 1.0)]),
    }
    if obs is not None:
        lo = priors.lamOs
        init["theta"] = np.full(q, 0.5)
        init["lamOs"] = np.array([max(20.0, lo.a / lo.b)])
        if obs.p_v > 0:
            init["betaV"] = np.full((p, obs.n_groups), 0.1)
            init["lamVz"] = np.full(obs.n_groups, 20.0)
    return init


def check_x_obs(
    x_unit: np.ndarray,
    names: tuple[str, ...],
    x_native: np.ndarray | None = None,
    domain: tuple[np.ndarray, np.ndarray] | None = None,
) -> None:
    """Warn when observations lie outside the design range; refuse beyond
    ``EXTRAPOLATION_MARGIN``. ``x_native`` (n, p) and ``domain`` (the range's native ends,
    each (p,)): the messages name the value given and the range in native units, as
    calibration's ``check_x`` does (None: the unit scale)."""
    lo, hi = x_unit.min(axis=0), x_unit.max(axis=0)
    far = (lo < -EXTRAPOLATION_MARGIN) | (hi > 1 + EXTRAPOLATION_MARGIN)
    where = "x_obs lies outside the simulation design's range"
    if x_native is not None and domain is not None and ((lo < 0) | (hi > 1)).any():
        beyond = -EXTRAPOLATION_MARGIN if far.any() else 0.0
        j, k = (int(i) for i in np.argwhere((x_unit < beyond) | (x_unit > 1 - beyond))[0])
        v, lo_k, hi_k = numbers_text(x_native[j, k], domain[0][k], domain[1][k])
        where = f"x_obs {names[k]}={v} lies outside the simulation design's range [{lo_k}, {hi_k}]"
        if far.any():
            raise GPMSAError(
                f"{where} by more than {EXTRAPOLATION_MARGIN:.0%} of its width: a joint fit "
                "cannot extrapolate that far (gpmsa.calibrate of a fitted emulator takes "
                "extrapolate=True)"
            )
    if far.any():
        k = int(np.flatnonzero(far)[0])
        low, high = numbers_text(
            lo[k], hi[k], -EXTRAPOLATION_MARGIN, 1 + EXTRAPOLATION_MARGIN, digits=3
        )[:2]
        raise GPMSAError(
            f"x_obs column {names[k]} reaches {low}..{high} on the unit scale of the "
            f"design; allowed [{-EXTRAPOLATION_MARGIN}, {1 + EXTRAPOLATION_MARGIN}] (the emulator "
            "cannot extrapolate that far)"
        )
    if (lo < 0).any() or (hi > 1).any():
        warnings.warn(
            where + "; the emulator extrapolates there",
            ExtrapolationWarning,
            stacklevel=user_stacklevel(),
        )


MAX_STD_OBS = 1e6
"""Observations farther than this from the simulation mean (in its sds) are refused: wrong
units, not data (the samplers' squares would overflow or the fit be meaningless)."""


def check_scalar_index(grids, grid: np.ndarray) -> None:
    """GPMSAError naming the experiment whose index ``grids[j]`` is not a scalar output's one
    point ``grid``: an index there is None or that point (as ``ObsData`` documents), never
    another, which would be ignored."""
    for j, g in enumerate(grids):
        if g is not None and not np.array_equal(np.reshape(g, -1), grid.reshape(-1)):
            a, b = numbers_text(float(np.reshape(g, -1)[0]), float(grid.reshape(-1)[0]))
            a = a if np.size(g) == 1 else f"{np.size(g)} values ({a}, ...)"
            raise GPMSAError(
                f"the index of experiment {j} is {a}, but the simulation output is scalar, "
                f"one value at index {b}: a scalar output has no grid to observe it along; "
                "leave ObsData's index out"
            )


def reduce_obs(
    obs: ObsData,
    std: Standardizer,
    K: np.ndarray,
    discrepancy,
    x_names: tuple[str, ...],
    levels: categorical.Levels | None = None,
    y_names=None,
    groups=None,
    x_checked: bool = False,
    index_names: tuple[str, ...] | None = None,
) -> tuple[ObsProblem, tuple[float, float]]:
    """GPM/SA's reduction of the observations; also returns the lamOs prior correction (da, db).

    ``discrepancy``: None, "constant", "linear", one (l_obs, p_v) array, or a list of one
    (l_j, p_v) array per experiment on its own grid (`discrepancy_bases`: normalised jointly).
    ``groups``: the precision group of each discrepancy basis vector (`check_groups`; None:
    one group).

    ``levels``: the x columns' training levels (``SimData.levels``); an unseen level is refused.
    ``y_names``: the simulation outputs' names, by which a y table with named columns and no
    index is read (`ObsData.outputs`). ``x_checked``: the caller has checked x_obs against the
    domain and warned (calibration's ``check_x``, whose ``extrapolate=True`` allows any
    distance): no ``check_x_obs`` here. ``index_names``: the output index's column names
    (``SimData.index_names``), by which a point outside the simulation index is named and an
    index table's columns are read (`ObsData.output_grids`).
    """
    x_native = obs.inputs(x_names)
    if x_native.ndim != 2 or x_native.shape[1] != std.x_min.size:  # before x_to_unit broadcasts
        raise GPMSAError(f"x_obs must have shape (n, {std.x_min.size}), got {x_native.shape}")
    x = std.x_to_unit(x_native)
    if levels is not None:
        categorical.check_levels(x_native, levels[: x.shape[1]], x_names, "x_obs")
    if not x_checked:
        check_x_obs(x, x_names, x_native, (std.x_min, std.x_max))
    n, p_u = obs.n, K.shape[1]
    scalar = K.shape[0] == 1
    experiments = obs.outputs(y_names)
    obs_grids = obs.output_grids(index_names)  # a table's columns by the index's names
    for j, (e, g) in enumerate(zip(experiments, obs_grids, strict=True)):
        if not scalar and g is None and e.size != K.shape[0]:
            raise GPMSAError(
                f"experiment {j} has {e.size} values but the simulation output has {K.shape[0]}; "
                "give ObsData an index grid"
            )
    points = not scalar and (is_points(std.grid) or any(is_points(g) for g in obs_grids))
    for j, g in enumerate(obs_grids):  # refused naming the experiment and the point
        if points and g is not None:
            index_points.weights(std.grid, g, f"the index of experiment {j}", index_names)
    with np.errstate(over="ignore"):  # an overflow gives inf: refused just below
        ys = [std.y_to_std(e, g) for e, g in zip(experiments, obs_grids, strict=True)]
    for j, e in enumerate(ys):
        check_finite(e, f"y_obs[{j}] in standardised units")
    far = max(float(np.max(np.abs(e))) for e in ys)
    if far > MAX_STD_OBS:
        shown = numbers_text(far, MAX_STD_OBS, digits=3)[0]
        raise GPMSAError(
            f"y_obs lies {shown} standard deviations of the simulation outputs from their "
            f"mean; allowed at most {MAX_STD_OBS:g} (wrong units?)"
        )
    lamy = [np.eye(e.size) for e in ys]
    if obs.precisions is not None:
        lamy = [
            std.precision_to_std(lam, g)
            for lam, g in zip(obs.output_precisions(y_names), obs_grids, strict=True)
        ]
        _warn_if_vague(lamy)
    if scalar:
        if any(e.size != 1 for e in ys):
            raise GPMSAError("a scalar simulation output needs one value per experiment in y_obs")
        check_scalar_index(obs_grids, std.grid)
        u = np.array([e[0] for e in ys])[:, None]
        p_v = 0 if discrepancy is None else 1
        if p_v and not (isinstance(discrepancy, str) and discrepancy == "constant"):
            raise GPMSAError("a scalar output supports discrepancy=None or 'constant' only")
        sig = np.diag([1.0 / (lam[0, 0] + SIGOBS_RIDGE) for lam in lamy])
        Ks = tuple(np.ones((1, 1)) for _ in ys)
        Ds = tuple(np.ones((1, 1)) for _ in ys) if p_v else None
        check_groups(groups, p_v)  # one basis vector: one group
        v = np.zeros((n, 0))
        obs_p = ObsProblem(x, u, v, sig, True, Ks, Ds, p_v, tuple(ys))
        return obs_p, (0.0, 0.0)
    grids = [std.grid if g is None else g for g in obs_grids]
    _check_discrepancy_scales(discrepancy, grids)
    bases = discrepancy_bases(discrepancy, grids)  # a list: one per experiment, scaled jointly
    Ks, Ds, vs, us, blocks = [], [], [], [], []
    rank, total, ss = 0, 0, 0.0
    lo, hi = std.grid.min(), std.grid.max()
    for j, (e, g, lam) in enumerate(zip(ys, obs_grids, lamy, strict=True)):
        if not points and g is not None and not index_points.within(g, lo, hi):
            a, b, c, d = numbers_text(g.min(), g.max(), lo, hi)
            raise GPMSAError(
                f"{index_points.named(f'the index of experiment {j}', index_names)} reaches "
                f"[{a}, {b}], outside the simulation grid [{c}, {d}]; observations must lie "
                "within it"
            )
        Kj = interpolate_basis(K, std.grid, g)
        Dj = None if bases is None else bases[j]
        DK = Kj if Dj is None else np.hstack([Dj, Kj])
        A = DK.T @ lam @ DK
        ridge = A + GLS_RIDGE * np.eye(A.shape[0])
        with np.errstate(over="ignore", invalid="ignore"):
            rhs = DK.T @ lam @ e
            vu = cho_solve(cho_factor(ridge), rhs) if np.all(np.isfinite(rhs)) else rhs
            resid = e - DK @ vu
            ss += float(resid @ lam @ resid)
        if not (np.all(np.isfinite(vu)) and np.isfinite(ss)):  # huge precisions
            raise GPMSAError(
                f"y_obs[{j}] is too large for the emulator's basis: its projection overflows "
                "float64 (wrong units, or observation precisions?)"
            )
        rank += int(np.linalg.matrix_rank(A, hermitian=True))
        total += e.size
        blocks.append(
            cho_solve(cho_factor(ridge + SIGOBS_RIDGE * np.eye(A.shape[0])), np.eye(A.shape[0]))
        )
        p_v = 0 if Dj is None else Dj.shape[1]
        vs.append(vu[:p_v])
        us.append(vu[p_v:])
        Ks.append(Kj)
        Ds.append(Dj)
    p_v = vs[0].size
    if any(v.size != p_v for v in vs):
        raise GPMSAError("every experiment needs the same number of discrepancy basis vectors")
    v_groups = check_groups(groups, p_v)
    n_c = p_v + p_u
    sig = np.zeros((n * n_c, n * n_c))
    for e, blk in enumerate(blocks):
        idx = np.arange(n_c) * n + e
        sig[np.ix_(idx, idx)] = blk
    obs_p = ObsProblem(
        x, np.array(us), np.array(vs).reshape(n, p_v), sig, False,
        tuple(Ks), None if p_v == 0 else tuple(Ds), p_v, tuple(ys), v_groups, n * n_c - rank,
    )  # fmt: skip
    return obs_p, (0.5 * (total - rank), 0.5 * ss)


def _check_discrepancy_scales(kind, grids: list[np.ndarray]) -> None:
    """GPMSAError where a "linear" discrepancy basis, normalised on each experiment's grid
    (`discrepancy_basis`), takes different scales on the experiments' grids: the same weights
    would mean a different discrepancy in each (and ``gpmsa.full_prediction`` refuses it)."""
    if not (isinstance(kind, str) and kind == "linear") or len(grids) < 2 or is_points(grids[0]):
        return  # index points: "linear" is refused by discrepancy_basis
    reach = [float(np.max(np.abs(g))) for g in grids]
    if not np.isclose(max(reach), min(reach), rtol=1e-12, atol=0.0):  # 0.1 + 0.2 is 0.3
        j, k = int(np.argmin(reach)), int(np.argmax(reach))
        low, high = numbers_text(reach[j], reach[k])
        raise GPMSAError(
            "discrepancy='linear' is normalised on each experiment's grid by its largest "
            f"|index|, which differs between them (experiment {j}: {low}, experiment "
            f"{k}: {high}), so the same weights would mean a different discrepancy in "
            "each: give every experiment a grid that reaches the same largest |index|, use "
            "discrepancy='constant', or pass the linear basis per experiment, which is "
            "normalised by one scale for all (as SEPIA's create_D_basis('linear') on ragged "
            "observations): discrepancy=[np.column_stack([np.ones(g.size), g]) for g in "
            "obs.grids]"
        )


def _warn_if_vague(precisions: list[np.ndarray]) -> None:
    """``ReductionWarning`` where the observation precisions, in standardised units, declare
    a median error sd above 1: larger than the spread of the simulation outputs. lamOs scales
    the precisions, but its prior (mean a / b, GPM/SA's 1000) holds it near its scale, so the
    posterior stays as vague as declared (a variance given for a precision: measured 12 times
    wider in theta)."""
    sd = float(np.median(np.concatenate([1.0 / np.sqrt(np.diag(lam)) for lam in precisions])))
    if sd > 1.0:
        warnings.warn(
            f"the observation precisions declare errors of sd {sd:.3g} simulation-output sds "
            "(median), larger than the simulation outputs' spread: precision is 1 / variance "
            "in the outputs' native units (a variance given for a precision?). lamOs scales "
            "it, but its prior holds it near its own scale",
            ReductionWarning,
            stacklevel=user_stacklevel(),
        )


@dataclass(frozen=True, eq=False)
class Prepared:
    """A problem with the transforms and basis that produced it; ``runs_sum_squares``: the
    standardised runs' sum of squares (what `variance_shares` divides)."""

    problem: Problem
    standardizer: Standardizer
    K: np.ndarray
    runs_sum_squares: float

    @property
    def variance_shares(self) -> np.ndarray:
        """(p_u,) the share of the standardised runs' variance each basis vector holds,
        ||w_j||^2 ||K_j||^2 / ||Y||^2 (orthogonal columns: they add up to the basis's share)."""
        return variance_shares(self.problem.w, self.problem.lam_sim, self.runs_sum_squares)

    def __repr__(self) -> str:
        prob, shares = self.problem, self.variance_shares
        shown = ", ".join(f"{v:.3%}" for v in shares[:6]) + (", ..." if shares.size > 6 else "")
        obs = "none" if prob.obs is None else f"{prob.obs.n} experiment(s)"
        return (
            f"Prepared(m={prob.m} runs, p={prob.p}, q={prob.q}, l_sim={self.K.shape[0]}, "
            f"p_u={self.K.shape[1]} basis vectors holding {np.sum(shares):.3%} of the runs' "
            f"variance [{shown}], observations: {obs})"
        )


def prepare(
    sim: SimData,
    obs: ObsData | None = None,
    *,
    priors: Priors | None = None,
    n_pc: int | float | None = None,
    discrepancy=None,
    mean_basis=None,
    discrepancy_groups=None,
    basis=None,
) -> Prepared:
    """Standardise, build the PCA basis and weights, reduce observations, set priors and inits.

    ``basis``: the emulator basis K (l_sim, p_u) in standardised output units (`given_basis`)
    instead of the runs' PCA (``n_pc``); not both. ``mean_basis``: None (zero mean),
    "constant", "linear" or a callable of unit-scale [x, t] (n, p + q) -> (n, k)
    (``gpmsa.model.mean_basis``). Categorical inputs come from ``sim``.
    ``priors``: before the data corrections (``corrected=False``; an Emulator's ``priors``,
    corrected for its own data, are refused). ``discrepancy_groups``: `reduce_obs`'s groups.
    """
    if not isinstance(sim, SimData):
        raise GPMSAError(f"data must be a gpmsa.SimData, got {type(sim).__name__}")
    if obs is not None and not isinstance(obs, ObsData):
        raise GPMSAError(f"obs must be a gpmsa.ObsData or None, got {type(obs).__name__}")
    if priors is not None and not isinstance(priors, Priors):
        raise GPMSAError(f"priors must be a gpmsa.Priors or None, got {priors!r}")
    if priors is not None and priors.corrected:
        raise GPMSAError(
            "priors are already data-corrected (corrected=True, as an Emulator's .priors): their "
            "lamWOs and lamOs priors hold the corrections of the data they were fitted to, and "
            "would not be corrected for these data; pass the priors as set before fitting "
            "(gpmsa.Priors(...), corrected=False)"
        )
    if basis is not None and n_pc is not None:
        raise GPMSAError(f"give n_pc (a PCA basis) or basis, not both; got n_pc={n_pc!r}")
    std = Standardizer.from_sim(sim)
    y_std = std.y_to_std(sim.y)
    base = Priors() if priors is None else priors
    K = pca_basis(y_std, n_pc) if basis is None else given_basis(basis, sim.l_sim)
    w = basis_weights(y_std, K)
    if basis is not None and sim.l_sim > 1:
        warn_weight_scale(w, base.lamUz)
    lam_sim = np.sum(K**2, axis=0)
    m, p_u = w.shape
    wos = (0.5 * (sim.l_sim - p_u) * m, 0.5 * float(np.sum((y_std - w @ K.T) ** 2)))
    if sim.l_sim == 1:
        wos = (0.0, 0.0)
    obs_p, os_corr = (None, (0.0, 0.0))
    levels = sim.levels
    if obs is not None:
        obs_p, os_corr = reduce_obs(obs, std, K, discrepancy, sim.x_names, levels, sim.y_names,
                                    discrepancy_groups, index_names=sim.index_names)  # fmt: skip
    elif discrepancy_groups is not None:
        check_groups(discrepancy_groups, 0)  # refused: no discrepancy without observations
    priors = base.with_data(wos, os_corr)
    init = default_init(sim.p, sim.q, p_u, priors, obs_p)
    x_unit, t_unit = std.x_to_unit(sim.x), std.t_to_unit(sim.t)
    basis = mean_basis_mod.make(mean_basis, sim.p + sim.q, sim.m)
    if basis is not None:  # refused before sampling, not at the first prediction
        mean_basis_mod.check_rank(basis, np.hstack([x_unit, t_unit]), sim.x_names + sim.t_names)
    sep = None
    if sim.separable is not None:  # the unit design keeps the native one's product
        if obs is not None or basis is not None:
            kronecker.refuse("observations (obs=)" if obs is not None else "a mean_basis")
        names = sim.x_names + sim.t_names
        sep = kronecker.structure(np.hstack([x_unit, t_unit]), sim.separable, names)
    prob = Problem(
        x_unit, t_unit, w, lam_sim, priors, init, frozenset(), obs_p,
        categorical.mask(levels), basis, separable=sep,
    )  # fmt: skip
    if obs is not None and prob.theta_levels is not None:  # a categorical theta starts at a level
        prob = prob.with_init({"theta": prob.snap_theta(init["theta"])})
    return Prepared(prob, std, K, float(np.sum(y_std**2)))
