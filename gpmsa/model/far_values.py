"""Observed values far beyond every simulation run's value at their output point: a missing-value
code such as -999, a spike or a units error among the data, which GPM/SA's reduction reads as
observation error (`far_value`; checked by ``gpmsa.calibrate``, the Calibrator and the studies
with a fitted emulator, and by a joint ``gpmsa.fit`` / ``gpmsa.fit_study`` before sampling);
and a simulation run's value far beyond every other run's (`far_run`; checked by every
``gpmsa.fit`` / ``gpmsa.fit_study`` before sampling)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from gpmsa.errors import OutlierRunWarning, OutsideEmulatorWarning, numbers_text
from gpmsa.model.basis import interpolate_basis

OUTSIDE_SDS = 5.0
"""An observation farther than this many predictive sds from every emulator prediction at its
x (over the whole theta domain) lies outside what the emulator has seen: a warning
(``OutsideEmulatorWarning``), and ``Posterior.info["outside_sds"]`` holds the distance. So
does an observed value this many of the outputs' sds beyond every simulation run's value at its
output point (`far_value`)."""
SCALAR_FAR_SDS = 100.0
"""How many of the outputs' sds beyond every simulation run's value a scalar output's datum
must lie for a joint fit (no fitted emulator, hence no predictive check) to name it
(`joint_far_value`). A scalar's data are not reduced through a basis, and noisy data lie
beyond the runs legitimately: 100 simulated experiments of stated noise sd 2 (5) output sds
reached 4.3 (13.8) sds beyond, and still narrowed theta (sd 0.11, 0.18; prior 0.29). A datum
100 sds beyond lies 4 of its stated sds away only where that sd is 25 output sds (data that
hardly inform theta), while a -999 code or a units error lies thousands of sds away. Where the
data state their noise (a precision), a datum must also lie beyond ``OUTSIDE_SDS`` of its own
noise sds, as on every path."""

FAR_RUN_RANGES = 20.0
"""How far beyond every other run's value at an output point a run's value must lie, in those
runs' range there, to be named (`far_run`). Measured on 1,000 designs of 12 independent outputs
each (10, 40 and 200 runs): normal and exponential outputs never reach it, Student-t(3) ones in
at most 0.1 % of designs and lognormal (sigma 1) ones in 0.2 % (10 runs; none at 40 or 200); a
lognormal of sigma 2 (outputs over ~3,000x) in 8-38 % and a Cauchy in 30-35 %: heavy tails that
one standardising sd and basis serve badly, where the warning's advice (emulate a transform)
holds. A -999 code among outputs of order 1 lies hundreds of ranges beyond; among outputs of
250-350 (temperatures in K), 12.5 (not named)."""
FAR_RUN_MIN_RUNS = 10
"""Fewer runs than this are not judged (`far_run`): a lognormal (sigma 1) output lies 20 ranges
beyond the others in 8 % of designs of 5 runs and 1.1 % of 9 runs."""
FAR_RUN_FLOOR = 0.1
"""The others' range at an output point is taken as at least this fraction of the runs' typical
range (`far_run`), so that a point where the other runs agree exactly or nearly (an output that
starts at 0 in every run, the flat ends of a steep step, a pulse's quiet stretches) does not
make a difference there of a millionth of the output's range look far. The typical range is
that of the scale the fit divides y by: with one sd over all outputs (``y_scale="scalar"``),
the largest over the output points of the range without each point's two top and two bottom
values (so that neither one run far beyond the others nor two set it); with each element's own
sd (``y_scale="columnwise"``, or a ``y_sd`` given per element), that element's own."""


@dataclass(frozen=True)
class FarValue:
    """One observed value beyond every simulation run's value at its output point (`far_value`):
    ``sds`` how far, in the outputs' sds there (the standardising scale); the experiment's
    position, the value (native), the runs' range there (native, interpolated onto an
    experiment's own index) and the point's text (None for a scalar output)."""

    sds: float
    experiment: int
    value: float
    low: float
    high: float
    point: str | None

    def text(self) -> str:
        """'y_obs[1] holds -999 at time 0.454545 s, 1.43e+03 sds ... there ([lo, hi])'."""
        side = "above" if self.value > self.high else "below"
        value, low, high = numbers_text(self.value, self.low, self.high)
        sds = numbers_text(self.sds, digits=3)[0]
        what = f"y_obs[{self.experiment}] = {value}, " if self.point is None else (
            f"y_obs[{self.experiment}] holds {value} at {self.point}, ")  # fmt: skip
        there = "" if self.point is None else " there"
        return (f"{what}{sds} sds of the simulation outputs {side} every simulation run's "
                f"value{there} ([{low}, {high}])")  # fmt: skip


def warn_far(
    far: FarValue, stacklevel: int, model: str | None = None, discrepancy: bool = False
) -> None:
    """Warn (``OutsideEmulatorWarning``) naming ``far`` (and the study ``model``'s label) as a
    missing-value code, an outlier or a units error; ``stacklevel`` as ``warnings.warn``'s in
    the function that calls this; ``discrepancy``: a discrepancy model is fitted too, which may
    take up the difference (a linear one, in a joint fit of experiments each 5 above the runs'
    outputs, up to 7 sds beyond every run: lamOs 3.5e3 and theta 0.58 +- 0.24 against
    0.600 +- 0.014 without the offset; one -999 among the data instead: lamOs 1.6e-5)."""
    by = "a large observation error (small lamOs)" + (" or the discrepancy" if discrepancy else "")
    warnings.warn(
        f"{'' if model is None else f'model {model!r}: '}{far.text()}: a missing-value "
        f"code, an outlier or a units error? The posterior explains it by {by} and theta "
        "falls back towards its prior; drop or correct the value",
        OutsideEmulatorWarning,
        stacklevel=stacklevel + 1,
    )


def far_value(
    y: np.ndarray,
    standardizer,
    experiments,
    grids,
    precisions=None,
    labels: tuple = (None, None, None),
    margin: float = OUTSIDE_SDS,
) -> FarValue | None:
    """The observed value farthest beyond the simulation runs' range at its output point, where
    it lies more than ``margin`` of the outputs' sds (``standardizer``'s scale there) beyond
    it; None where no value does. ``y``: the runs' outputs (m, l_sim), native;
    ``experiments``: each experiment's y (native, in the runs' y order) on its grid of
    ``grids`` (None: the simulation grid); the runs' range is interpolated onto an
    experiment's own index as the basis is. ``precisions``: each experiment's stated
    observation-error precision (native; None, or a None entry: not given), where a value must
    also lie more than ``OUTSIDE_SDS`` of its own noise sds beyond the runs (a value within its
    stated noise is no outlier; ``margin`` sets the outputs' sds only). ``labels``: (index
    names, index units, output names) as `SimData` gives them (None: not given); the output
    names are given where the outputs have no index (several named outputs), and then name the
    value's output.

    A value far outside every run (a missing-value code such as -999, a spike) among a
    functional observation's values lies mostly beyond the emulator's basis, where GPM/SA's
    reduction reads it as observation error (the lamOs prior's correction): it inflates that
    error so much that the predictive check reads the data inside (1.5 sds for one -999 among
    36 values), while lamOs drops and theta's posterior falls back to its prior."""
    y = np.asarray(y)
    std = standardizer
    lams = [None] * len(grids) if precisions is None else precisions
    low, high = np.min(y, axis=0), np.max(y, axis=0)  # the runs' range per output element
    if all(g is None for g in grids):  # on the simulation grid: at once
        values = np.asarray(experiments, dtype=np.float64).reshape(len(experiments), -1)
        with np.errstate(over="ignore", invalid="ignore"):
            sds = np.maximum(values - high, low - values) / std.y_sd
        if not np.max(sds) > margin:  # NaN: none (the common case, at once)
            return None
        for j, lam in enumerate(lams):
            sds[j] = _beyond_noise(sds[j], std.y_sd, lam, margin)
        at = int(np.argmax(sds))
        if not sds.flat[at] > margin:
            return None
        j, k = divmod(at, values.shape[1])
        worst = (float(sds.flat[at]), j, values[j, k], low[k], high[k], None, k)
    else:
        worst, ranges = None, np.column_stack([low, high])
        for j, (e, g, lam) in enumerate(zip(experiments, grids, lams, strict=True)):
            e = np.asarray(e, dtype=np.float64).reshape(-1)
            lo, hi = (ranges if g is None else interpolate_basis(ranges, std.grid, g)).T
            scale = std.sd_on(g)
            with np.errstate(over="ignore", invalid="ignore"):
                sds = _beyond_noise(np.maximum(e - hi, lo - e) / scale, scale, lam, margin)
            k = int(np.argmax(sds))
            if sds[k] > margin and (worst is None or sds[k] > worst[0]):
                worst = (float(sds[k]), j, e[k], lo[k], hi[k], g, k)
        if worst is None:
            return None
    sds, j, value, lo, hi, grid, k = worst
    index_names, index_units, y_names = labels
    point = None
    if y.shape[1] > 1 and grid is None and y_names:
        point = f"output {y_names[k]!r}"  # several outputs, no index: by the output's name
    elif y.shape[1] > 1:  # a functional output: where the value lies
        point = _point_text((std.grid if grid is None else grid)[k], index_names, index_units)
    return FarValue(sds, j, float(value), float(lo), float(hi), point)


def _beyond_noise(sds: np.ndarray, scale, lam: np.ndarray | None, margin: float) -> np.ndarray:
    """``sds`` (one experiment's distances beyond the runs, in the outputs' sds ``scale``) with
    those within ``OUTSIDE_SDS`` of the value's own stated noise sd set to 0 (none where no
    distance exceeds ``margin``, the outputs' sds the caller asks for): with a given
    observation-error precision ``lam`` (native; None: not given, the noise on the outputs'
    scale) a value that far outside every run is within its noise, no outlier (an output
    element the runs barely vary, scaled columnwise, observed with its real noise)."""
    if lam is None or not np.max(sds) > margin:
        return sds
    lam = np.atleast_2d(np.asarray(lam, dtype=np.float64))
    diagonal = np.diagonal(lam)
    if np.count_nonzero(lam) == np.count_nonzero(diagonal):  # one precision per value
        noise = 1.0 / np.sqrt(diagonal)
    else:
        noise = np.sqrt(np.diagonal(np.linalg.inv(lam)))
    with np.errstate(over="ignore", invalid="ignore"):
        return np.where(sds * scale > OUTSIDE_SDS * noise, sds, 0.0)


def joint_far_value(sim, obs, standardizer) -> FarValue | None:
    """`far_value` of a joint fit's observations ``obs`` (an ObsData) against the runs of
    ``sim`` (a SimData; ``standardizer`` its scales), before any emulator is fitted: beyond
    ``OUTSIDE_SDS`` for a functional output, ``SCALAR_FAR_SDS`` for a scalar one (with no
    predictive check to tell a noisy datum within reach from one beyond it)."""
    labels = (sim.index_names, sim.index_units, sim.y_names if sim.index is None else None)
    return far_value(
        sim.y, standardizer, obs.outputs(sim.y_names), obs.output_grids(sim.index_names),
        obs.output_precisions(sim.y_names), labels,
        OUTSIDE_SDS if sim.y.shape[1] > 1 else SCALAR_FAR_SDS,
    )  # fmt: skip


def _point_text(point, names=None, units=None) -> str:
    """An output index point as text: 'time 0.4545 s' by the index ``names`` and ``units``,
    'output index 0.4545' without names, '(a, b) (0.1, 0.2)' for points of several columns."""
    values = np.atleast_1d(np.asarray(point, dtype=np.float64))
    units = units or ("",) * values.size
    names = names or ("output index",)
    shown = [f"{v:.6g}" + (f" {u}" if u else "") for v, u in zip(values, units, strict=False)]
    if values.size == 1:
        return f"{names[0]} {shown[0]}"
    label = names[0] if len(names) == 1 else f"({', '.join(names)})"
    return f"{label} ({', '.join(shown)})"


@dataclass(frozen=True)
class FarRun:
    """A simulation run's value beyond every other run's at an output point (`far_run`):
    ``ranges`` how far, in the other runs' range there (at least ``FAR_RUN_FLOOR`` of
    ``typical``, the runs' typical range: `FAR_RUN_FLOOR`); the run's position, its value
    (native), the other runs' range there, the point's text (None for a scalar output) and at
    how many output points the run lies that far."""

    ranges: float
    run: int
    value: float
    low: float
    high: float
    point: str | None
    n_points: int
    typical: float

    def text(self) -> str:
        """'simulation run 7 (y[7]) holds -999 at time 0.4545 s, 900 times the other runs'
        range there ([0.045, 1.15]) below them'."""
        side = "above" if self.value > self.high else "below"
        value, low, high = numbers_text(self.value, self.low, self.high)
        where = "" if self.point is None else f" at {self.point}"
        more = self.n_points - 1
        also = f"; it lies that far at {more} more output point(s)" if more else ""
        if self.high - self.low >= FAR_RUN_FLOOR * self.typical:
            ranges = numbers_text(self.ranges, digits=3)[0]
            how = f"{ranges} times the other runs' range there ([{low}, {high}]) {side} them"
        else:  # the other runs (nearly) agree there: the distance against their typical range
            gap = numbers_text(abs(self.value - (self.high if side == "above" else self.low)),
                               self.typical, digits=3)  # fmt: skip
            how = (f"{gap[0]} {side} every other run's value there ([{low}, {high}]), whose "
                   f"range reaches {gap[1]} elsewhere")  # fmt: skip
        return f"simulation run {self.run} (y[{self.run}]) holds {value}{where}, {how}{also}"


def far_run(sim, grid) -> FarRun | None:
    """The simulation run whose value lies farthest beyond every other run's at an output point,
    where more than ``FAR_RUN_RANGES`` times the other runs' range there (at least
    ``FAR_RUN_FLOOR`` of the typical range of the scale the fit divides y by); None where none
    does, or with fewer than ``FAR_RUN_MIN_RUNS`` runs. ``sim``: a SimData (its y native, its
    labels); ``grid``: its output index points (the standardizer's grid).

    One such value (a missing-value code, a failed run) sets the outputs' scale and the
    emulator's basis: one -999 among 40 runs of 12 outputs of order 0.3 made the emulator's
    predictions at held-out inputs 86 off (RMS; 0.001 without it), unwarned."""
    y = np.asarray(sim.y, dtype=np.float64)
    m = y.shape[0]
    if m < FAR_RUN_MIN_RUNS:
        return None
    s = np.sort(y, axis=0)
    spread = s[-3] - s[2]  # each point's range without its two top and two bottom values
    own = sim.y_scale == "columnwise" or np.size(sim.y_sd) > 1  # each element's own sd
    typical = spread if own else np.full(spread.shape, spread.max())
    floor = FAR_RUN_FLOOR * typical
    with np.errstate(divide="ignore", invalid="ignore", under="ignore"):  # (under: ratio ~0)
        above = (s[-1] - s[-2]) / np.maximum(s[-2] - s[0], floor)
        below = (s[1] - s[0]) / np.maximum(s[-1] - s[1], floor)
    ratios = np.nan_to_num(np.vstack([above, below]), nan=0.0, posinf=0.0)  # 0/0, x/0: unjudged
    far = ratios > FAR_RUN_RANGES
    if not far.any():
        return None
    side, k = np.unravel_index(int(np.argmax(ratios)), ratios.shape)
    run = int(np.argmax(y[:, k]) if side == 0 else np.argmin(y[:, k]))
    low, high = (s[0, k], s[-2, k]) if side == 0 else (s[1, k], s[-1, k])
    runs = np.vstack([np.argmax(y, axis=0), np.argmin(y, axis=0)])
    point = None
    if y.shape[1] > 1 and sim.index is None and sim.y_names:
        point = f"output {sim.y_names[k]!r}"
    elif y.shape[1] > 1:
        point = _point_text(np.asarray(grid)[k], sim.index_names, sim.index_units)
    n_points = int(np.count_nonzero(np.any(far & (runs == run), axis=0)))
    return FarRun(float(ratios[side, k]), run, float(y[run, k]), float(low), float(high), point,
                  n_points, float(typical[k]))  # fmt: skip


def warn_far_run(far: FarRun, stacklevel: int, model: str | None = None) -> None:
    """Warn (``OutlierRunWarning``) naming ``far`` (and the study ``model``'s label);
    ``stacklevel`` as ``warnings.warn``'s in the function that calls this."""
    warnings.warn(
        f"{'' if model is None else f'model {model!r}: '}{far.text()}: a missing-value code, "
        "a failed run or a units error? Such a value sets the outputs' scale and the "
        "emulator's basis, and its predictions everywhere suffer: drop or correct the run "
        "(for an output with heavy tails, emulate a transform of it, such as its log)",
        OutlierRunWarning,
        stacklevel=stacklevel + 1,
    )
