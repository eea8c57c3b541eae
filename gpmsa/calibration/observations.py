"""Checks and GPM/SA reduction of observations for calibration with a fixed emulator."""

from __future__ import annotations

import hashlib
import itertools
import math
import warnings
from dataclasses import dataclass

import numpy as np

from gpmsa import limits
from gpmsa.calibration.model import FixedGP, LamOsPrior
from gpmsa.errors import (
    ExtrapolationWarning,
    GPMSAError,
    OutsideEmulatorWarning,
    ResourceLimitError,
    numbers_text,
    user_stacklevel,
)
from gpmsa.model import categorical, far_values, kronecker
from gpmsa.model.data import (
    ObsData,
    as_float,
    by_column_names,
    check_finite,
    check_parameter_names,
    column_labels,
    default_labels,
    evenly_spaced,
    size_of,
    tensor_values,
    values_digest,
)
from gpmsa.model.far_values import OUTSIDE_SDS, FarValue, warn_far
from gpmsa.model.problem import (
    GLS_RIDGE,
    MAX_STD_OBS,
    SIGOBS_RIDGE,
    ObsProblem,
    check_scalar_index,
    reduce_obs,
)
from gpmsa.model.transforms import EXTRAPOLATION_MARGIN

EMULATOR_ATTRS = ("standardizer", "x_unit", "t_unit", "K", "w", "lam_sim", "params", "priors")
EMULATOR_PARAMS = ("betaU", "lamUz", "lamWs", "lamWOs")
EMULATOR_PARAM_MODES = ("point", "draws")
N_EMULATOR_DRAWS = 20
"""Default ``n_emulator_draws`` of ``gpmsa.calibrate`` and the Calibrator (``"draws"`` mode)."""
CLOSER_STARTS = 3
"""From how many of `theta_probe`'s best nodes `closer_fit` searches (three or more
parameters), before it calls an observation outside."""
CLOSER_ITERATIONS = 40
"""Most L-BFGS-B iterations of one `closer_fit` search (each costs about q + 1 predictions,
and its line search's): at 400 runs and six parameters, 14 data sets that the probe read
7-18 sds outside met a theta inside after 2-20 iterations, and searches run to the end took
23-47 (L-BFGS-B's own limit is 15,000)."""
LEVEL_PROBE_NODES = 1089
"""About how many theta values `fit_at_levels` predicts at in one call (`theta_probe`'s
most: 33 x 33), so that many combinations of levels cost time, not memory."""
LEVEL_PROBE_BUDGET = 8 * LEVEL_PROBE_NODES
"""Most theta values `fit_at_levels` looks at (8,712: eight of `theta_probe`'s largest
probe): with many combinations of levels the continuous parameters are probed more coarsely
(`continuous_probe`), and with more combinations than this the check and the lamOs start are
`theta_probe`'s, as for a continuous theta (off the levels: weaker)."""


@dataclass(frozen=True, eq=False)
class Observations:
    """One calibration's data, reduced: x (n, p) unit; z (d,) stacked u (component-major,
    d = n p_u);
    obs_chol (d, d) lower Cholesky factor of Sigma_obs; lamos the data-corrected lamOs prior;
    obs the ObsProblem for the samplers; values_sha256 the SHA-256 of the native x and y rows
    (`gpmsa.model.data.values_digest`: an ObsData of the same values has the same);
    layout_sha256 that of where they lie and how precise they are (`layout_digest`); values
    each experiment's y (native, in the emulator's y order), grids each one's index (None:
    the simulation grid) and precisions each one's observation-error precision (native, in
    that order; None: not given), which `far_value` reads."""

    x: np.ndarray
    z: np.ndarray
    obs_chol: np.ndarray
    lamos: LamOsPrior
    obs: ObsProblem
    os_corr: tuple[float, float]
    values_sha256: str
    layout_sha256: str
    values: tuple
    grids: tuple
    precisions: tuple


def check_emulator(emulator, categorical_theta: bool = False) -> None:
    """Raise GPMSAError unless ``emulator`` has what calibration needs (a categorical
    calibration parameter only where ``categorical_theta``: every backend samples one, numpy
    and torch with their joint level move, ``gpmsa.mcmc.level_moves``, pyro marginalised)."""
    missing = [a for a in EMULATOR_ATTRS if not hasattr(emulator, a)]
    if missing:
        raise GPMSAError(f"emulator lacks {missing}: calibration needs a gpmsa.Emulator")
    absent = [k for k in EMULATOR_PARAMS if k not in emulator.params]
    if absent:
        raise GPMSAError(f"emulator.params lacks {absent}; it needs {EMULATOR_PARAMS}")
    if emulator.t_unit.shape[1] < 1:
        raise GPMSAError("the emulator has no calibration parameter (t has 0 columns)")
    check_parameter_names(emulator.t_names, "the emulator's t_names")
    levels = getattr(emulator, "levels", None)
    if levels is not None and not categorical_theta:
        categorical.refuse_categorical_theta(
            levels, emulator.x_unit.shape[1], emulator.x_names + emulator.t_names, "calibration"
        )


def emulator_record(emulator) -> dict[str, str]:
    """What a calibration's Posterior info records of its emulator: {"emulator_sha256":
    ``Emulator.model_sha256``}; {} for an object with only the attributes calibration checks
    for (``check_emulator``), not a gpmsa.Emulator: it has no fingerprint to record."""
    sha = getattr(emulator, "model_sha256", None)
    return {"emulator_sha256": sha} if isinstance(sha, str) else {}


def check_draws_mode(mode: str, n_sets: int, where: str) -> None:
    """GPMSAError for an ``n_emulator_draws`` other than ``N_EMULATOR_DRAWS`` with
    ``emulator_params="point"`` (``mode``): the point estimate is one parameter set, so the
    number would have no effect. ``where``: the call that takes them, as the message names it."""
    if mode == "point" and n_sets != N_EMULATOR_DRAWS:
        raise GPMSAError(
            f"{where}: n_emulator_draws={n_sets} sets how many of the emulator's retained draws "
            "emulator_params='draws' averages the likelihood over; with emulator_params='point' "
            "(the default: its point estimate alone) it would have no effect: pass "
            "emulator_params='draws' as well, or leave n_emulator_draws out"
        )


def emulator_param_sets(emulator, mode: str, n_sets: int) -> list[dict]:
    """The emulator parameter sets the calibration conditions on (point, or evenly spaced draws)."""
    if mode not in EMULATOR_PARAM_MODES:
        raise GPMSAError(f"emulator_params must be one of {EMULATOR_PARAM_MODES}, got {mode!r}")
    if mode == "point":
        return [emulator.params]
    idx = draw_positions(emulator, n_sets)
    return [{k: np.asarray(emulator.draws[k][i]) for k in EMULATOR_PARAMS} for i in idx]


def draw_positions(emulator, n_sets: int) -> np.ndarray:
    """The retained draws (their positions in ``emulator.draws``) that ``emulator_params="draws"``
    conditions on, in the order of its sets: ``n_sets`` evenly spaced (``evenly_spaced``);
    GPMSAError when the emulator kept none."""
    draws = getattr(emulator, "draws", None) or {}
    n = len(next(iter(draws.values()))) if draws else 0
    if n == 0:
        raise GPMSAError("emulator_params='draws' needs retained draws; this emulator has none")
    return evenly_spaced(n, n_sets, "n_emulator_draws")


def fixed_gp(emulator, params: dict | None = None) -> FixedGP:
    """The emulator's GP at ``params`` (default: its point estimate)."""
    prm = emulator.params if params is None else params
    kronecker.check_dense(emulator, "calibration (gpmsa.calibrate, gpmsa.Calibrator)")
    return FixedGP(
        emulator.x_unit, emulator.t_unit, emulator.w, emulator.lam_sim,
        prm["betaU"], prm["lamUz"], prm["lamWs"], prm["lamWOs"],
        getattr(emulator, "categorical_mask", None), getattr(emulator, "mean_basis", None),
    )  # fmt: skip


def _as_rows(value, name: str, ncols: int) -> np.ndarray:
    arr = as_float(value, name)
    if arr.ndim == 0 or (arr.ndim == 1 and arr.size == ncols):
        arr = arr.reshape(1, -1)
    elif arr.ndim == 1 and ncols == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[1] != ncols or arr.shape[0] == 0:
        raise GPMSAError(f"{name} must have shape (n, {ncols}), got {np.shape(value)}")
    check_finite(arr, name)
    return arr


def given_obs_data(x_obs, y_obs) -> ObsData | None:
    """The ``gpmsa.ObsData`` given in place of (x_obs, y_obs): as x_obs (positionally, as
    ``gpmsa.fit(data, obs)`` takes it) or as y_obs, the other None; None where neither is one.
    GPMSAError where an ObsData comes with the other argument too."""
    for what, value, other in (("x_obs", x_obs, y_obs), ("y_obs", y_obs, x_obs)):
        if isinstance(value, ObsData):
            if other is not None:
                raise GPMSAError(
                    f"{what} is a gpmsa.ObsData, which holds both x and y: pass it alone "
                    f"({'y_obs' if what == 'x_obs' else 'x_obs'}=None)"
                )
            return value
    return None


def layout_digest(grids: list, precisions: list | None, grid: np.ndarray) -> str:
    """SHA-256 of where experiments lie on the output grid (``ObsData.grids``) and of their
    precisions (``ObsData.precisions``): an index equal to the simulation ``grid`` counts as
    none (the same reduction). What ``gpmsa.calibrate`` records (info "obs_layout_sha256")
    beside the values' digest, so that a prediction conditioned on the same values placed or
    weighted otherwise is refused."""
    h = hashlib.sha256()
    for j, g in enumerate(grids):
        if g is None or (g.shape == grid.shape and np.array_equal(g, grid)):
            h.update(f"{j}:grid:simulation;".encode())
        else:
            h.update(f"{j}:grid{g.shape}:".encode())
            h.update(np.ascontiguousarray(g, dtype="<f8").tobytes())
    for j, lam in enumerate(precisions or []):
        h.update(f"{j}:precision{lam.shape}:".encode())
        h.update(np.ascontiguousarray(lam, dtype="<f8").tobytes())
    return h.hexdigest()


def check_x(
    emulator, x_obs, extrapolate: bool, what: str = "x_obs"
) -> tuple[np.ndarray, np.ndarray]:
    """x_obs native (n, p) and unit scale, with a joint fit's rule (``check_x_obs``) and the
    predictions': outside the emulator's x domain by up to ``EXTRAPOLATION_MARGIN`` (10 %) of
    a column's width an ``ExtrapolationWarning``; further a GPMSAError naming the column, or
    with ``extrapolate=True`` a warning. ``what``: the argument's name in messages. An emulator
    without known inputs (p = 0) takes None as one row of no columns (1, 0); a gpmsa.ObsData
    is refused (an x_new given as one; one given as x_obs or y_obs is the observations, which
    `given_obs_data` takes before this)."""
    if isinstance(x_obs, ObsData):
        raise GPMSAError(f"{what} is a gpmsa.ObsData: pass its inputs, {what}=obs.x")
    p = emulator.x_unit.shape[1]
    if x_obs is None and p == 0:
        x_obs = np.empty((1, 0))
    x = _as_rows(by_column_names(x_obs, emulator.x_names, what), what, p)
    levels = getattr(emulator, "levels", None)
    if levels is not None:
        categorical.check_levels(x, levels[:p], emulator.x_names, what)
    xu = emulator.standardizer.x_to_unit(x)
    out = (xu < 0.0) | (xu > 1.0)
    if out.any():
        far = (xu < -EXTRAPOLATION_MARGIN) | (xu > 1.0 + EXTRAPOLATION_MARGIN)
        j, k = (int(i) for i in np.argwhere(far if far.any() else out)[0])
        name = emulator.x_names[k]
        lo, hi = emulator.domain[name]
        v, lo, hi = numbers_text(x[j, k], lo, hi)
        msg = f"{what} {name}={v} lies outside the emulator's domain [{lo}, {hi}]"
        if far.any() and not extrapolate:
            raise GPMSAError(f"{msg} by more than {EXTRAPOLATION_MARGIN:.0%} of its width; pass "
                             "extrapolate=True to allow it")  # fmt: skip
        warnings.warn(
            msg + "; the emulator extrapolates", ExtrapolationWarning, stacklevel=user_stacklevel()
        )
    return x, xu


def _y_names(emulator) -> tuple[str, ...] | None:
    """The emulator's y_names (None for an object without them)."""
    names = getattr(emulator, "y_names", None)
    return None if names is None else tuple(names)


def check_y(emulator, y_obs) -> np.ndarray:
    """y_obs as a float array with its columns in the order of the emulator's ``y_names``: a
    table with named columns by name (`by_column_names`: other names are a GPMSAError), a pandas
    Series by its labels (`series_by_names`), an array as it is (by position), as is a table
    with a frame's default labels 0, 1, ... (`default_labels`, as `ObsData` reads its y). A
    numpy masked array is refused (`as_float`); so is a list of experiments of different
    lengths (`refuse_ragged`)."""
    refuse_ragged(y_obs)
    names = None if default_labels(column_labels(y_obs)) else _y_names(emulator)
    return as_float(by_column_names(y_obs, names, "y_obs"), "y_obs")


def refuse_ragged(y_obs) -> None:
    """GPMSAError pointing at gpmsa.ObsData when ``y_obs`` is a list of experiments of
    different lengths (SEPIA's ragged y_obs, each on its own grid)."""
    if not isinstance(y_obs, (list, tuple)):
        return
    y_obs = tensor_values(y_obs)  # (np.ndim reads a list of tensors that record gradients)
    try:
        if not all(np.ndim(e) == 1 for e in y_obs):
            return
    except ValueError:  # an experiment ragged itself: as_float refuses it
        return
    lengths = [size_of(e) for e in y_obs]
    if len(set(lengths)) > 1:
        raise GPMSAError(
            f"y_obs holds experiments of different lengths {lengths}: give observations on "
            "their own output grids as gpmsa.ObsData(x, y, index=[one grid per experiment]) in "
            "place of x_obs (y_obs left out)"
        )


def obs_inputs(emulator, x_obs, y_obs, what: str = "x_obs"):
    """``x_obs`` as given, or, where it is None and the emulator has no known inputs (p = 0), an
    (n, 0) array: one row per observation of ``y_obs`` (each a replicate of the one experiment,
    as SEPIA's dummy x; a scalar output reads every value of ``y_obs`` as one observation).
    GPMSAError when ``y_obs`` is None, or ``x_obs`` is None and the emulator has known inputs.
    Its callers take a gpmsa.ObsData given as either first (`given_obs_data`)."""
    if y_obs is None:
        hint = ""
        if x_obs is not None and emulator.x_unit.shape[1] == 0:
            hint = ("; this emulator has no known inputs, so give the outputs by name, "
                    "y_obs=... (the first positional argument is x_obs)")  # fmt: skip
        raise GPMSAError(f"y_obs is required: the observed outputs (n, l_sim), native units{hint}")
    if x_obs is not None:
        return x_obs
    p = emulator.x_unit.shape[1]
    if p > 0:
        raise GPMSAError(
            f"{what} is required: the emulator has p = {p} known input(s) "
            f"{list(emulator.x_names)}; only an emulator without known inputs (p = 0) takes none"
        )
    y = check_y(emulator, y_obs)
    if emulator.K.shape[0] == 1:
        n = y.size
    else:
        n = 1 if y.ndim < 2 else y.shape[0]
    return np.empty((n, 0))


def reduce(emulator, x_obs, y_obs, extrapolate: bool = False) -> Observations:
    """Check and reduce (x_obs, y_obs) for the no-discrepancy model of ``emulator``.

    y_obs: (n, l_sim) on the emulator's output grid (a scalar output takes (n, 1) or (n,)); a
    table with named columns (a pandas DataFrame) or a pandas Series is read by the emulator's
    ``y_names`` (`check_y`). x_obs: (n, p); None (or (n, 0)) for an emulator with p = 0
    (`obs_inputs`). Or a ``gpmsa.ObsData`` alone (`given_obs_data`): experiments on their own
    index grids and with their own precisions (`checked_obs_data`).
    """
    given = given_obs_data(x_obs, y_obs)
    if given is not None:
        return _reduce_obs_data(emulator, given, extrapolate)
    x_obs = obs_inputs(emulator, x_obs, y_obs)
    x, xu = check_x(emulator, x_obs, extrapolate)
    n = x.shape[0]
    std, K = emulator.standardizer, emulator.K
    l_sim = K.shape[0]
    y = check_y(emulator, y_obs)
    if l_sim == 1 and y.ndim == 2 and y.size == n:  # a scalar output as one row (1, n)
        y = y.reshape(n, 1)
    y = _as_rows(y, "y_obs", l_sim)
    if y.shape[0] != n:
        raise GPMSAError(f"y_obs must have one row per x_obs row ({n}), got {y.shape[0]}")
    _check_obs_values(n, K.shape[1])
    if l_sim == 1:  # GPM/SA's scalar-output reduction, as gpmsa.model.problem.reduce_obs
        with np.errstate(over="ignore"):  # an overflow is refused below, as far off
            u = (y - std.y_mean) / std.y_sd
        sig = np.eye(n) / (1.0 + SIGOBS_RIDGE)
        obs = ObsProblem(xu, u, np.zeros((n, 0)), sig, True, (np.ones((1, 1)),) * n, None)
        corr = (0.0, 0.0)
    else:
        obs, corr = reduce_obs(ObsData(x, y), std, K, None, emulator.x_names, x_checked=True)
    digests = values_digest(x, list(y)), layout_digest([None] * n, None, std.grid)
    return _observations(emulator, obs, corr, digests, xu, (tuple(y), (None,) * n, (None,) * n))


def _check_obs_values(n: int, p_u: int) -> None:
    """ResourceLimitError where n experiments of p_u basis components exceed
    ``limits.MAX_OBS_VALUES`` reduced values."""
    d = n * p_u
    if not d <= limits.MAX_OBS_VALUES:  # a NaN limit refuses too
        raise ResourceLimitError(
            f"x_obs/y_obs have {n} rows x {p_u} basis components = {d} reduced values, "
            f"above gpmsa.limits.MAX_OBS_VALUES = {limits.MAX_OBS_VALUES}: the exact likelihood "
            f"costs a {d} x {d} eigendecomposition per theta value (time ~ d^3); split the rows "
            "into windows and add their Calibrator.log_likelihood_grid (or pass one window's as "
            "the next one's prior=), or raise gpmsa.limits.MAX_OBS_VALUES"
        )


def checked_obs_data(emulator, obs: ObsData, extrapolate: bool) -> tuple[np.ndarray, np.ndarray]:
    """Check a ``gpmsa.ObsData`` given to calibration against ``emulator``; returns its x
    native (n, p) in the order of the emulator's x_names (`ObsData.inputs`) and on the unit
    scale. Its x as ``check_x``'s; a scalar output takes one value per experiment and no
    index (or its one point); a functional output's experiments lie on the simulation grid or
    on their own index within it (checked by the reduction)."""
    x, xu = check_x(emulator, obs.inputs(emulator.x_names), extrapolate, "the ObsData's input")
    _check_obs_values(x.shape[0], emulator.K.shape[1])
    if emulator.K.shape[0] == 1:
        check_scalar_index(obs.grids, emulator.standardizer.grid)  # None, or its one point
        sizes = sorted({e.size for e in obs.experiments} - {1})
        if sizes:
            raise GPMSAError(
                f"the emulator's output is a scalar: each ObsData experiment needs one value, "
                f"got {sizes[0]} (give y as a column (n, 1), one row per experiment)"
            )
    return x, xu


def _reduce_obs_data(emulator, obs: ObsData, extrapolate: bool) -> Observations:
    """``reduce`` for a ``gpmsa.ObsData``: GPM/SA's reduction of its experiments on their own
    grids (interpolated basis) and with their precisions (`gpmsa.model.problem.reduce_obs`)."""
    x, xu = checked_obs_data(emulator, obs, extrapolate)
    reduced, corr = reduce_obs(
        obs, emulator.standardizer, emulator.K, None, emulator.x_names,
        getattr(emulator, "levels", None), _y_names(emulator), x_checked=True,
        index_names=getattr(emulator, "index_names", None),
    )  # fmt: skip
    grids = obs.output_grids(getattr(emulator, "index_names", None))
    digests = (obs.values_digest(emulator.x_names, _y_names(emulator)),
               layout_digest(grids, obs.output_precisions(_y_names(emulator)),
                             emulator.standardizer.grid))  # fmt: skip
    precisions = obs.output_precisions(_y_names(emulator)) or [None] * obs.n
    native = tuple(obs.outputs(_y_names(emulator))), tuple(grids), tuple(precisions)
    return _observations(emulator, reduced, corr, digests, xu, native)


def _observations(
    emulator, obs: ObsProblem, corr, digests: tuple[str, str], xu, native: tuple[tuple, ...]
) -> Observations:
    """The ``Observations`` of a reduction ``obs`` (lamOs prior correction ``corr``; the data's
    values and layout ``digests``; ``native``: the experiments' y, grids and precisions);
    GPMSAError where its reduced data lie more than ``MAX_STD_OBS`` simulation sds from the
    mean (wrong units)."""
    z = obs.z
    far = ~(np.abs(z) <= MAX_STD_OBS)  # an overflow (inf, NaN) is far too
    if far.any():
        worst = np.max(np.abs(z))
        shown = (numbers_text(worst, MAX_STD_OBS, digits=3)[0] if np.isfinite(worst)
                 else "more than 1.8e308 (overflow)")  # fmt: skip
        raise GPMSAError(
            f"y_obs lies {shown} standard deviations of the simulation outputs from their "
            f"mean; allowed at most {MAX_STD_OBS:g} (wrong units?)"
        )
    base = emulator.priors.lamOs
    lamos = LamOsPrior(base.a + corr[0], base.b + corr[1], base.lower, base.upper)
    sig = obs.sig_obs
    chol = np.sqrt(sig) if sig.shape == (1, 1) else np.linalg.cholesky(sig)
    return Observations(xu, z, chol, lamos, obs, corr, *digests, *native)


@dataclass(frozen=True)
class Fit:
    """How well the emulator can explain an observation, over a set of theta values.

    outside_sds: the smallest over theta of the largest |z_i - mean_i| / sd_i over the reduced
        data's elements (sd_i: the emulator's predictive sd, nugget included, and where the
        data have values beyond their basis, the observation error those residuals estimate,
        `_residual_noise`): how many predictive sds the observation lies from the nearest
        emulator prediction at its x. Where nothing estimates the observation error (a scalar
        output; as many values as basis vectors) it is the largest over i of the smallest over
        theta, each datum against the emulator's range at its own x: one theta for all would
        read the data's own noise as a miss (30 scalar observations with noise 7% of the
        outputs' sd read 7.6 sds, 10 with 13% 10.9, while the posterior was the exact one,
        0.005-0.015 of the range wide). A single datum reads the same either way.
    excess_var: the smallest over theta of max(0, (||L^-1 (z - mean)||^2 - tr(L^-1 S L^-T)) / d)
        (Sigma_obs = L L^T): the observation-error variance per unit lamOs that the misfit beyond
        the emulator's own predictive variance needs (0 when some theta explains the data).
    """

    outside_sds: float
    excess_var: float


def theta_probe(q: int) -> np.ndarray:
    """Unit-scale theta values (k, q) at which ``fit_of`` looks: 129 equally spaced for one
    parameter, a 33 x 33 grid for two, else the 3^q corners, edge midpoints and centre plus 256
    points of an unscrambled Sobol sequence."""
    if q == 1:
        return np.linspace(0.0, 1.0, probe_layout(1)[0])[:, None]
    if q == 2:
        axis = np.linspace(0.0, 1.0, probe_layout(2)[0])
        return np.column_stack([g.ravel() for g in np.meshgrid(axis, axis, indexing="ij")])
    from scipy.stats import qmc

    lattice = np.stack(np.meshgrid(*[[0.0, 0.5, 1.0]] * min(q, 6), indexing="ij"), -1)
    lattice = lattice.reshape(-1, min(q, 6))
    lattice = np.hstack([lattice, np.full((lattice.shape[0], q - lattice.shape[1]), 0.5)])
    sobol = qmc.Sobol(d=q, scramble=False).random(256)
    return np.vstack([lattice, sobol])


def closer_fit(predict, data: Observations, theta: np.ndarray, probe: tuple | None = None) -> Fit:
    """``Fit`` of the observation over ``theta`` (unit scale (G, q): `theta_probe`'s scattered
    nodes for three or more parameters; ``probe``: ``predict(data.x, theta)`` where the caller
    has it) and, where those nodes read it outside
    (``OUTSIDE_SDS``), over every theta that local searches (bounded L-BFGS-B on the unit cube
    of the sum of squared distances, `_distances`, at most ``CLOSER_ITERATIONS`` iterations)
    from its best nodes predict at, up to ``CLOSER_STARTS`` searches, until a theta reads the
    observation inside. A search stops at the first theta that reads it inside and needs no
    observation error beyond the emulator's (``excess_var`` 0: neither the verdict nor
    `lamos_start` can change), so ``outside_sds`` is then that theta's distance, below
    ``OUTSIDE_SDS`` but not the searches' best.
    ``predict(x, theta)``: ``FixedGP.predict``. Informative data (a functional output, a few
    experiments) pin theta far more tightly than 3^q + 256 scattered nodes are spaced: three
    experiments of 40 values made by the simulator at an interior theta of three parameters
    read 11-18 predictive sds outside, warned of as a units error, while the posterior was
    right (tests/gpmsa/test_outside_many_theta_s69.py). Searched to convergence, such data
    cost 250-460 predictions at q = 6 (400 runs: 3-16 s); stopped so, 29-218
    (tests/gpmsa/test_calib_fixes_s70.py)."""
    mean, cov = predict(data.x, theta) if probe is None else probe
    seen = _Nearest(data, mean, cov)
    if seen.inside():
        return seen.fit()
    from scipy.optimize import minimize

    def misfit(t: np.ndarray) -> float:
        dist = seen.add(*predict(data.x, t[None, :]))
        if seen.settled():
            raise _Settled
        total = float(np.sum(dist**2))
        return total if np.isfinite(total) else 1e300

    order = np.argsort(np.sum(_distances(mean, cov, data)[2] ** 2, axis=1), kind="stable")
    bounds = [(0.0, 1.0)] * theta.shape[1]
    options = {"maxiter": CLOSER_ITERATIONS}
    for i in order[:CLOSER_STARTS]:  # the best nodes first, until a theta reads inside
        try:
            minimize(misfit, theta[i], method="L-BFGS-B", bounds=bounds, options=options)
        except _Settled:
            break
        if seen.inside():  # this search's thetas read it inside: the verdict
            break
    return seen.fit()


class _Settled(Exception):
    """A `closer_fit` search met a theta that reads the observation inside and needs no
    observation error beyond the emulator's (excess_var 0): no further theta changes the
    verdict or the lamOs start (`lamos_start`)."""


class _Nearest:
    """`fit_of` over every theta predicted at so far, kept up to date one theta at a time: a
    datum judged on its own is as near as the nearest theta to it (``layout``: `fit_of`'s, of
    the first thetas only); a theta whose prediction is NaN is no nearer (np.fmin)."""

    def __init__(self, data: Observations, mean: np.ndarray, cov: np.ndarray,
                 layout: tuple[int, ...] | None = None, excess: bool = True):  # fmt: skip
        self.data, self.Linv = data, _chol_inverse(data) if excess else None
        resid, var, dist, self.alone = _distances(mean, cov, data)
        if self.alone:  # no error estimate: each datum on its own; a NaN prediction is no nearer
            self.nearest = np.fmin.reduce(dist, axis=0)
            if layout is not None:
                self.nearest[_crossed(resid, layout)] = 0.0
        else:
            self.nearest = np.fmin.reduce(np.max(dist, axis=1))
        self.excess = np.nan  # ``excess=False``: not computed (`outside_sds`)
        if excess:
            self.excess = float(np.fmin.reduce(_excess(resid, var, cov, self.data, self.Linv)))

    def add(self, mean: np.ndarray, cov: np.ndarray) -> np.ndarray:
        """Take the predictive at one more theta ((1, p_u, n), (1, p_u, n, n)); its distances
        (d,)."""
        resid, var, dist, _ = _distances(mean, cov, self.data)
        near = dist[0] if self.alone else np.max(dist[0])
        self.nearest = np.fmin(self.nearest, near)  # a NaN prediction is no nearer
        self.excess = min(self.excess, float(_excess(resid, var, cov, self.data, self.Linv)[0]))
        return dist[0]

    def inside(self) -> bool:
        return not float(np.max(self.nearest)) > OUTSIDE_SDS

    def settled(self) -> bool:
        return self.inside() and self.excess == 0.0

    def fit(self) -> Fit:
        return Fit(float(np.max(self.nearest)), self.excess)


def probe_layout(q: int) -> tuple[int, ...] | None:
    """The grid shape of `theta_probe`'s nodes ('ij' order), None for its scattered ones."""
    return {1: (129,), 2: (33, 33)}.get(q)


def fit_of(
    mean: np.ndarray, cov: np.ndarray, data: Observations, layout: tuple[int, ...] | None = None
) -> Fit:
    """``Fit`` of the observation from the emulator's predictive on some theta values:
    mean (G, p_u, n), cov (G, p_u, n, n) (``FixedGP.predict`` / ``GridPredictor.predict``).
    ``layout``: the theta values' grid shape ('ij' order, G nodes), where they form one: a
    datum judged on its own whose residual changes sign between neighbouring nodes (or between
    two nodes with only NaN predictions between them) is met between them (the predictive mean
    is continuous in theta), however far the nodes' means
    lie from it in predictive sds (an emulator with a negligible nugget read a datum exactly
    on the simulator 11 sds outside, between probe nodes)."""
    return _Nearest(data, mean, cov, layout).fit()


def outside_sds(
    mean: np.ndarray, cov: np.ndarray, data: Observations, layout: tuple[int, ...] | None = None
) -> float:
    """`fit_of`'s ``outside_sds`` alone, the same number: its ``excess_var`` (a solve and a
    trace of L^-1 S L^-T per theta value, d^3 each: 0.4 s of a 3.6 s two-parameter update with
    40 observations) is not computed. What a Calibrator's update reads (`warn_if_outside`)."""
    return float(np.max(_Nearest(data, mean, cov, layout, excess=False).nearest))


def _chol_inverse(data: Observations) -> np.ndarray | None:
    """L^-1 (d, d) of ``data.obs_chol``, which `_excess` needs; None for one datum (d = 1)."""
    if data.z.size == 1:
        return None
    from scipy.linalg import solve_triangular

    return solve_triangular(data.obs_chol, np.eye(data.z.size), lower=True)


def _excess(resid, var, cov, data: Observations, Linv: np.ndarray | None) -> np.ndarray:
    """Per theta value (G,), the observation-error variance (unit lamOs) beyond the emulator's
    that the residuals need (`Fit.excess_var`): `_distances`' resid and var (G, d), the
    predictive cov (G, p_u, n, n), ``Linv`` `_chol_inverse`'s."""
    G, p_u, n = cov.shape[:3]
    L = data.obs_chol
    d = data.z.size
    if d == 1:
        s2 = float(L[0, 0]) ** 2
        y2, tr = resid[:, 0] ** 2 / s2, var[:, 0] / s2
    else:
        from scipy.linalg import solve_triangular

        y2 = np.sum(solve_triangular(L, resid.T, lower=True) ** 2, axis=0)
        tr = np.zeros(G)
        for c in range(p_u):  # tr(L^-1 S L^-T), S block-diagonal over components
            blk = Linv[:, c * n : (c + 1) * n]
            tr += np.einsum("ai,gij,aj->g", blk, cov[:, c], blk)
    return np.maximum(0.0, (y2 - tr) / max(d - data.obs.n_null, 1))  # observed directions


def _distances(mean: np.ndarray, cov: np.ndarray, data: Observations) -> tuple:
    """`fit_of`'s misfit on G theta values: the residuals (G, d) and predictive variances
    (G, d), projected onto the observed directions; the distances |resid| / sd (G, d), sd with
    `_residual_noise`; and whether each datum is judged on its own (no error estimate)."""
    G, p_u, n = mean.shape
    m = mean.reshape(G, p_u * n)
    var = np.diagonal(cov, axis1=2, axis2=3).reshape(G, p_u * n)
    resid = data.z[None, :] - m
    noise = _residual_noise(data)
    P = _observed_projector(data.obs)
    if P is not None:  # the unobserved directions' stand-in 0 is no miss
        full = np.zeros((G, p_u * n, p_u * n))
        for c in range(p_u):
            full[:, c * n : (c + 1) * n, c * n : (c + 1) * n] = cov[:, c]
        resid = resid @ P
        var = np.einsum("ij,gjk,ik->gi", P, full, P)
        noise = (P * P) @ np.broadcast_to(noise, p_u * n)  # diag(P diag(noise) P), P symmetric
    var = np.maximum(var, 1e-300)
    with np.errstate(over="ignore"):
        dist = np.abs(resid) / np.sqrt(var + noise)
    return resid, var, dist, bool(np.ndim(noise) == 0 and noise == 0.0)


def continuous_probe(n_cont: int, n_combos: int):
    """(nodes (k, n_cont), grid shape or None) at which `level_probe_blocks` probes the
    continuous parameters for ``n_combos`` combinations of levels: `theta_probe`'s where
    n_combos x k is within `LEVEL_PROBE_BUDGET`, else the finest coarser one that is (one or
    two parameters: 33, 9, 3 nodes an axis; more: the 3^n lattice of corners, edge midpoints
    and centre), else the centre alone; None where even that is over the budget."""
    if n_cont == 0:
        candidates = [(np.zeros((1, 0)), None)]
    else:
        full = theta_probe(n_cont)
        candidates = [(full, probe_layout(n_cont))]
        if n_cont <= 2:
            for n in (33, 9, 3):
                if n < probe_layout(n_cont)[0]:
                    axes = np.meshgrid(*[np.linspace(0.0, 1.0, n)] * n_cont, indexing="ij")
                    candidates.append((np.column_stack([a.ravel() for a in axes]), (n,) * n_cont))
        else:
            candidates.append((full[: 3 ** min(n_cont, 6)], None))  # theta_probe's lattice
        candidates.append((np.full((1, n_cont), 0.5), None))
    for base, layout in candidates:
        if n_combos * base.shape[0] <= LEVEL_PROBE_BUDGET:
            return base, layout
    return None


def level_probe_blocks(levels: list, nodes: int = LEVEL_PROBE_NODES):
    """The theta values at which `fit_at_levels` looks, for a categorical theta (``levels``:
    per parameter its unit-scale levels, None for a continuous one): every combination of the
    categorical parameters' levels, each crossed with the continuous ones' nodes
    (`continuous_probe`: `theta_probe`'s, coarser for many combinations; one node without
    them). Yields (theta (b k, q), b, layout): b combinations of k nodes each, about ``nodes``
    in all (at least one combination), and the continuous nodes' grid shape (`probe_layout`;
    None without continuous parameters or for scattered nodes). Yields nothing where the
    combinations alone exceed `LEVEL_PROBE_BUDGET`."""
    q = len(levels)
    cont = [k for k in range(q) if levels[k] is None]
    cat = [k for k in range(q) if levels[k] is not None]
    n_combos = math.prod(len(levels[k]) for k in cat)
    probe = continuous_probe(len(cont), n_combos)
    if probe is None:
        return
    base, layout = probe
    combos = np.array(list(itertools.product(*[levels[k] for k in cat])), dtype=float)
    step = max(1, nodes // base.shape[0])
    for start in range(0, combos.shape[0], step):
        chunk = combos[start : start + step]
        theta = np.empty((chunk.shape[0] * base.shape[0], q))
        theta[:, cont] = np.tile(base, (chunk.shape[0], 1))
        theta[:, cat] = np.repeat(chunk, base.shape[0], axis=0)
        yield theta, chunk.shape[0], layout


def fit_at_levels(predict, data: Observations, levels: list) -> Fit | None:
    """``Fit`` of the observation for a categorical theta, which takes its levels only: over
    `level_probe_blocks` (``predict(x, theta)``: ``FixedGP.predict``), in chunks, both numbers
    from the same predictions. Off its levels the predictive mean is no level's (the kernel's
    other-level correlation) and its sd about the prior's, so `theta_probe`'s nodes there read
    an observation that no level explains as within a few sds, and their excess_var (the lamOs
    start, `lamos_start`) is that of theta values the chain never visits. A datum judged on its
    own is met where its residual changes sign between neighbouring continuous nodes of one
    combination of levels (`fit_of`'s rule), never between levels. None where the combinations
    of levels exceed `LEVEL_PROBE_BUDGET` (`level_probe_blocks` yields none)."""
    nearest, best, excess, Linv, looked = None, np.inf, np.inf, None, False
    for theta, b, layout in level_probe_blocks(levels):
        Linv = _chol_inverse(data) if not looked else Linv
        looked = True
        mean, cov = predict(data.x, theta)
        resid, var, dist, alone = _distances(mean, cov, data)
        excess = min(excess, float(np.fmin.reduce(_excess(resid, var, cov, data, Linv))))
        if not alone:
            best = min(best, float(np.fmin.reduce(np.max(dist, axis=1))))
            continue
        k = theta.shape[0] // b
        near = np.fmin.reduce(dist.reshape(b, k, -1), axis=1)  # (b, d): per combination
        if layout is not None:
            for i in range(b):
                near[i, _crossed(resid[i * k : (i + 1) * k], layout)] = 0.0
        near = np.fmin.reduce(near, axis=0)
        nearest = near if nearest is None else np.fmin(nearest, near)
    if not looked:
        return None
    return Fit(best if nearest is None else float(np.max(nearest)), excess)


def _crossed(resid: np.ndarray, layout: tuple[int, ...]) -> np.ndarray:
    """Per datum (resid (G, d) on a grid of shape ``layout``), whether its residual is zero
    at a node or changes sign between two nodes along an axis with only NaN predictions (no
    sign known) between them."""
    r = np.sign(resid).reshape(*layout, -1)
    hit = np.any(r == 0, axis=tuple(range(len(layout))))
    for axis in range(len(layout)):
        known = _last_known(r, axis)
        lo = np.take(known, range(layout[axis] - 1), axis=axis)
        hi = np.take(r, range(1, layout[axis]), axis=axis)
        hit |= np.any(lo * hi < 0, axis=tuple(range(len(layout))))
    return hit


def _last_known(r: np.ndarray, axis: int) -> np.ndarray:
    """``r`` with each NaN replaced by the last value before it along ``axis`` that is not NaN
    (NaN where there is none)."""
    shape = [1] * r.ndim
    shape[axis] = r.shape[axis]
    index = np.where(np.isnan(r), 0, np.arange(r.shape[axis]).reshape(shape))
    index = np.maximum.accumulate(index, axis=axis)
    return np.take_along_axis(r, index, axis=axis)


def _observed_projector(obs: ObsProblem) -> np.ndarray | None:
    """The projector (d, d) onto the reduced data's observed directions, None where every
    direction is observed: per experiment, its Sigma_obs block's eigenvectors of variance
    above half the reduction's 1 / GLS_RIDGE are the unobserved ones (``ObsProblem.n_null``)."""
    if not obs.n_null or obs.scalar_out:
        return None
    d = obs.z.size
    n = obs.n
    P = np.eye(d)
    for e in range(n):
        idx = np.arange(d // n) * n + e
        w, V = np.linalg.eigh(obs.sig_obs[np.ix_(idx, idx)])
        N = V[:, w > 0.5 / GLS_RIDGE]
        P[np.ix_(idx, idx)] -= N @ N.T
    return P


def _residual_noise(data: Observations) -> np.ndarray | float:
    """Per reduced datum, the observation-error variance that the data's residuals beyond the
    basis estimate: diag(Sigma_obs) / lamOs at the mean of lamOs's prior corrected by them
    (``Observations.lamos``; GPM/SA's correction: their count and sum of squares); 0 where no
    value lies beyond the basis (a scalar output, or as many values as basis vectors), where
    the prior alone would set it. Projected onto a coarse or partial grid the noise grows, and
    without it data straight from the simulator read as far outside (8.6 sds on 10 points)."""
    if not data.os_corr[0] > 0:
        return 0.0
    lamos = data.lamos.shape / data.lamos.rate
    return np.sum(data.obs_chol**2, axis=1) / lamos


def far_value(emulator, data: Observations, fit: Fit | None = None) -> FarValue | None:
    """The observed value (of ``data.values``, on ``data.grids``) farthest beyond the
    simulation runs' range at its output point, where it lies more than ``OUTSIDE_SDS`` of the
    outputs' sds (the emulator's standardising scale there) beyond it, and that many of its
    own stated noise sds where the data give a precision (`gpmsa.model.far_values.far_value`);
    None where no value does, or for an object without
    the runs' outputs ``y``. A scalar output whose ``fit`` reads the data inside is not looked
    at (None): each datum is then within reach of the emulator at its x, and a Calibrator's
    update on the road case is spared the pass (10-20 us of 0.5 ms)."""
    y = getattr(emulator, "y", None)
    if y is None or (fit is not None and fit.outside_sds <= OUTSIDE_SDS and np.shape(y)[1] == 1):
        return None
    named = getattr(emulator, "y_names", None) if getattr(emulator, "index", 0) is None else None
    labels = (getattr(emulator, "index_names", None), getattr(emulator, "index_units", None), named)
    return far_values.far_value(y, emulator.standardizer, data.values, data.grids,
                                data.precisions, labels)  # fmt: skip


def warn_if_outside(
    fit: Fit,
    discrepancy: bool = False,
    model: str | None = None,
    far: FarValue | None = None,
) -> None:
    """Warn (``OutsideEmulatorWarning``) when the observation lies more than ``OUTSIDE_SDS``
    predictive sds from every emulator prediction at its x; ``discrepancy``: a discrepancy
    model is calibrated too (the warning says that it must explain the difference); ``model``:
    the study model's label the warning names. ``far``: the value farthest outside every
    simulation run (`far_value`), which the warning names; where the predictive check reads the
    data inside, a warning of its own. The warnings name the user's call, however deep the
    caller (`user_stacklevel`, found only when there is a warning to give)."""
    if fit.outside_sds <= OUTSIDE_SDS and far is not None:
        warn_far(far, user_stacklevel(), model, discrepancy)
    if fit.outside_sds > OUTSIDE_SDS:
        then = (
            "The discrepancy term and the observation error must then explain the difference "
            "(as they would a units error); if it is larger than the discrepancy you expect, "
            if discrepancy
            else "The posterior then explains it by a large observation error (small lamOs) "
            "and theta falls back towards its prior, or, just beyond the outputs' range, piles "
            "up at the theta bound nearest the observation; "
        )
        warnings.warn(
            f"{'' if model is None else f'model {model!r}: '}"
            f"y_obs lies {numbers_text(fit.outside_sds, OUTSIDE_SDS, digits=3)[0]} predictive "
            "sds from the nearest emulator "
            f"prediction at x_obs over the whole theta domain (more than {OUTSIDE_SDS:g})"
            f"{' (the emulator alone)' if discrepancy else ''}: the observation is outside "
            f"what the emulator has seen. {then}check the units, the feature and the "
            "emulator's domain" + ("" if far is None else f". The farthest value: {far.text()}"),
            OutsideEmulatorWarning,
            stacklevel=user_stacklevel(),
        )


def lamos_start(fit: Fit, prior: LamOsPrior) -> float:
    """A start of lamOs for the samplers: the prior's mean a/b (GPM/SA starts at max(20, a/b);
    here never above the mean: the prior as the data's values beyond the basis corrected it,
    with precisions declared 1e12 times too large, had mean 3.4e-9, and chains started at
    1/excess_var = 6e-6 never came down: theta 0.3993 +- 0.0023 against the exact 0.4038 +-
    0.0034), lowered to 1/excess_var when the observation needs a larger observation error
    than that (else an additive random walk started there never reaches the posterior,
    decades below, and theta sticks at a bound), and kept inside the prior's bounds (the
    middle of (lower, upper) where it would reach the upper bound: a chain started outside
    has no posterior mass)."""
    start = prior.shape / prior.rate
    if fit.excess_var > 0.0:
        start = min(start, 1.0 / fit.excess_var)
    if prior.lower > 0.0:
        start = max(start, 1.01 * prior.lower)
    if start >= prior.upper:
        start = 0.5 * (prior.lower + prior.upper)
    return start


def check_log_prior(value, names: tuple[str, ...], theta) -> float:
    """One log prior density from what a user's ``log_prior`` returned at one theta row (one
    number, in any shape or array type numpy reads): a float, or -inf; no real number (bools,
    complex values, text, None), NaN, +inf or a wrong size raise GPMSAError (a NaN is an error,
    not a zero density; a mask is not a log density)."""
    try:
        values = np.asarray(value)
    except (TypeError, ValueError) as exc:  # e.g. a ragged list
        raise GPMSAError(f"log_prior must return numbers, got {value!r}") from exc
    kind = values.dtype.kind
    if kind not in "iuf":
        got = "None" if value is None else f"{value!r} (dtype {values.dtype})"
        hint = " (a mask? return 0.0 where allowed, -inf elsewhere)" if kind == "b" else ""
        raise GPMSAError(f"log_prior must return real log densities, got {got}{hint}")
    if values.size != 1:
        raise GPMSAError(
            f"log_prior must return one log density per theta row, got {values.size} values"
        )
    val = float(values.reshape(-1)[0])
    if np.isnan(val) or val == np.inf:
        at = ", ".join(f"{n}={float(v):.6g}" for n, v in zip(names, np.ravel(theta), strict=False))
        raise GPMSAError(
            f"log_prior returned {val} at {at}: it must return a log density (a finite number, "
            "or -inf where the prior density is zero)"
        )
    return val


def theta_levels(emulator) -> list[tuple[float, ...] | None] | None:
    """Per calibration parameter, its training levels on the unit scale (None: continuous);
    None when no calibration parameter is categorical."""
    levels = getattr(emulator, "levels", None)
    p = emulator.x_unit.shape[1]
    if levels is None or all(lv is None for lv in levels[p:]):
        return None
    std = emulator.standardizer
    out: list[tuple[float, ...] | None] = []
    for k, lv in enumerate(levels[p:]):
        if lv is None:
            out.append(None)
            continue
        native = np.tile(std.t_min, (len(lv), 1))
        native[:, k] = lv
        out.append(tuple(float(v) for v in std.t_to_unit(native)[:, k]))
    return out


def theta_levels_native(emulator) -> dict[str, list[int]]:
    """Each categorical calibration parameter's training levels (native integer codes, as
    ``emulator.categorical`` and ``info["level_offsets"]`` hold them; floats before session 74)
    by name, as ``Posterior.info["levels"]`` records them (the Calibrator's grid too); {}
    without one."""
    levels = getattr(emulator, "levels", None)
    if levels is None:
        return {}
    p = len(emulator.x_names)
    return {str(name): [int(v) for v in lv]
            for name, lv in zip(emulator.t_names, tuple(levels)[p:], strict=True)
            if lv is not None}  # fmt: skip
