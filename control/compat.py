"""Checks that an emulator suits the loop it is asked to serve (vehicle, noise, feature, domain).

The training script (examples/train_emulator.py) and `control.training.fit_band_emulator` /
`fit_window_emulator` record in ``emulator.metadata``: ``vehicle``
(``model.describe()``), ``noise_std`` (m/s^2), ``feature`` (`control.FeatureSpec.to_dict`),
``block_scatter`` for the block feature (`control.BlockScatter`) and the campaign's ``road``
settings.
"""

from __future__ import annotations

import json
import warnings

import numpy as np

import gpmsa
import vehicle
from control.bcr import BCRSettings, check_gd_unit, emulator_domain
from control.errors import ControlError, ControlWarning, EmulatorMismatchError, user_stacklevel
from control.feature import FeatureSpec
from control.observation_model import (
    BlockScatter,
    check_emulator_inputs,
    check_feature_outputs,
    one_block_logliks,
)
from control.sensor_checks import SensorLimits
from control.simplex import Simplex
from control.validation import check_instance, is_real, replace_fields, within
from gpmsa.calibration.posterior import GridMarginal
from gpmsa.errors import numbers_text


def _canon(obj) -> str:
    return json.dumps(obj, sort_keys=True, default=str)


def _vehicle_diff(trained, model, label: str = "model") -> str:
    """The fields in which the vehicle the emulator was made for differs from ``model``'s
    (called ``label`` in the text)."""
    if not isinstance(trained, dict):
        return f"emulator {_canon(trained)} vs {label} {_canon(model.describe())}"
    used = model.describe()
    return ", ".join(
        f"{k}: {label} {_canon(used.get(k, '(none)'))} vs emulator "
        f"{_canon(trained.get(k, '(none)'))}"
        for k in sorted(set(trained) | set(used), key=lambda k: (k != "model", k))  # model first
        if _canon(trained.get(k)) != _canon(used.get(k))
    )


def _check_is_emulator(emulator, needs: tuple[str, ...] = ()) -> None:
    """ControlError for an argument that is not an emulator at all (a case name, a path, None),
    before any message about its records could send the user to retrain it; with ``needs``,
    also for one that lacks any of those attributes (an emulator's stand-in)."""
    lacks = [name for name in ("metadata", *needs) if not hasattr(emulator, name)]
    if lacks:
        raise ControlError(
            f"emulator must be a gpmsa.Emulator (gpmsa.load(path), or "
            f"control.shipped_emulator(case) for the shipped ones), got {emulator!r:.80} "
            f"({type(emulator).__name__}"
            + (")" if "metadata" in lacks else f", without {', '.join(lacks)})")
        )


_RECORDED_BY = {
    "feature": "control.training.fit_band_emulator and fit_window_emulator, and "
    "examples/train_emulator.py, record it; a gpmsa.fit of your own needs "
    "metadata={'feature': control.FeatureSpec().to_dict(), ...} (docs/robot.md, section 4)",
    "vehicle": "examples/train_emulator.py records it, as do control.training's "
    "fit_band_emulator and fit_window_emulator given vehicle=, the model the runs were "
    "simulated with; an emulator of a real robot's drives has no vehicle model to simulate",
}
"""What makes each record `_recorded` asks for (the remedy of its error)."""


def _recorded(emulator, key: str, what: str):
    """The emulator's metadata ``key``; EmulatorMismatchError saying it does not say ``what``
    when the record is missing."""
    _check_is_emulator(emulator)
    meta = dict(getattr(emulator, "metadata", None) or {})
    if key not in meta:
        raise EmulatorMismatchError(
            f"the emulator's metadata has no {key!r}: it does not say {what} ({_RECORDED_BY[key]})"
        )
    return meta[key]


def emulator_feature(emulator) -> FeatureSpec:
    """The feature the emulator was trained on (its metadata's ``feature``)."""
    record = _recorded(emulator, "feature", "what observation it was trained on")
    try:
        return FeatureSpec.from_dict(record)
    except (TypeError, ValueError) as exc:
        raise EmulatorMismatchError(f"the emulator's feature is malformed: {exc}") from exc


def check_feature(emulator, bcr: BCRSettings) -> None:
    """Raise `EmulatorMismatchError` naming each field in which the BCR's feature differs from
    the one the emulator was trained on."""
    trained = emulator_feature(emulator)
    check_feature_outputs(emulator, trained)
    diff = trained.same_as(bcr.feature)
    if diff:
        pairs = ", ".join(
            f"{k}: BCR {getattr(bcr.feature, k)!r} vs emulator {getattr(trained, k)!r}"
            for k in diff
        )
        raise EmulatorMismatchError(f"the BCR's feature differs from the emulator's ({pairs})")


def check_recorded_feature(emulator, bcr: BCRSettings) -> None:
    """`check_feature` where the emulator records its feature (metadata ``feature``); an
    emulator without that record (or a model without an emulator) is taken as it is."""
    if "feature" in (getattr(emulator, "metadata", None) or {}):
        check_feature(emulator, bcr)


def check_emulator(
    emulator,
    *,
    model=None,
    noise_std: float | None = None,
    bcr: BCRSettings | None = None,
    track=None,
    simplex: Simplex | None = None,
) -> None:
    """Raise `EmulatorMismatchError` or warn (`ControlWarning`) where the emulator does not fit.

    Each check runs where its argument is given (None skips it): ``model`` (the vehicle
    model), ``noise_std`` (the loop's accelerometer noise sd, m/s^2), ``bcr`` (the BCR's
    settings: its feature and method), ``track`` and ``simplex``.

    Errors: a GD domain below `control.bcr.GD_MIN_HI` (GDs in m^3, `check_gd_unit`); another
    vehicle model; another feature (name, block or window length, rate, bands, tapers); a track
    whose prescribed GD lies outside the emulator's GD domain; a Simplex whose top or safe speed
    lies outside the emulator's speed domain (the BCR learns nothing at such a speed: the robot
    would drive on an estimate that only ages), or whose GD_max is not below
    the emulator's highest GD (the posterior never exceeds that, so the estimate could never
    call for safety mode) or not above its lowest (every estimate exceeds that: safety mode for
    good, e.g. a GD band given in m^3). Warnings: a
    different noise level (the paper's Test Cases pair the noise-free emulator with noise-free
    data and the noisy one with noisy data; a mismatch biases GD, but a robustness study may
    want it); a track whose grid step or band top differs from the training roads' (metadata
    ``road``: the GD estimates are biased; on the paper's track a 2 cm grid read GD 500 as
    358); vehicle or noise metadata missing; a Simplex with ``risk=None`` whose GD_max lies
    above `top_reach` (the posterior mean, cut at the emulator's highest GD, seldom exceeds it
    even on rougher ground); one with ``risk`` = alpha whose GD_max lies above
    `top_quantile_reach` (the (1 - alpha) quantile seldom exceeds it) or, with ``bcr`` of
    method "window" (each window alone), below `bottom_quantile` at v_safe (that quantile
    exceeds it even on the emulator's smoothest ground; the default methods pool and read
    lower there).
    """
    speeds = ("x_names",) if simplex is not None else ()  # (the Simplex's against its domain)
    _check_is_emulator(emulator, needs=(*speeds, "t_names", "domain"))
    check_emulator_inputs(emulator)
    gd_name = emulator.t_names[0]
    check_gd_unit(tuple(map(float, emulator.domain[gd_name])), gd_name)
    if model is not None and not callable(getattr(model, "describe", None)):
        raise ControlError(
            f"model must be a vehicle model (e.g. vehicle.Jackal()), got {model!r:.60}"
        )
    if noise_std is not None and not (is_real(noise_std) and 0 <= noise_std < np.inf):
        raise ControlError(f"noise_std must be a finite real number >= 0, m/s^2, got {noise_std!r}")
    if bcr is not None:
        check_instance(bcr, "bcr", BCRSettings)
    if track is not None and not hasattr(track, "segments"):
        raise ControlError(f"track must be a roadgen Track, got {track!r:.60}")
    if simplex is not None:
        check_instance(simplex, "simplex", Simplex)
    meta = dict(getattr(emulator, "metadata", None) or {})
    if "feature" in meta:  # its outputs against its recorded feature (with bcr= or not)
        try:
            recorded = FeatureSpec.from_dict(meta["feature"])
        except (AttributeError, TypeError, ValueError):
            recorded = None  # (a malformed record: named where a BCR's feature is checked)
        if recorded is not None:
            check_feature_outputs(emulator, recorded)
    check_against(emulator, model=model, noise_std=noise_std, bcr=bcr, track=track,
                  simplex=simplex)  # fmt: skip


def check_against(
    emulator,
    *,
    model=None,
    noise_std: float | None = None,
    bcr: BCRSettings | None = None,
    track=None,
    simplex: Simplex | None = None,
) -> None:
    """`check_emulator`'s checks of the arguments given, in its order, without its checks of
    the emulator alone and of the arguments' kinds: for a caller that has run
    ``check_emulator(emulator)`` and checked its arguments already (`run_closed_loop`, whose
    own checks lie between these)."""
    meta = dict(getattr(emulator, "metadata", None) or {})
    if model is not None:
        if "vehicle" not in meta:
            warnings.warn(
                "emulator metadata has no 'vehicle'; cannot check it was made for "
                f"{model.describe().get('model', type(model).__name__)}",
                ControlWarning,
                stacklevel=user_stacklevel(),
            )
        elif _canon(meta["vehicle"]) != _canon(model.describe()):
            raise EmulatorMismatchError(
                f"emulator was made for another vehicle ({_vehicle_diff(meta['vehicle'], model)})"
            )
    if noise_std is not None:
        trained = _recorded_noise_std(meta)
        if trained is None:
            warnings.warn(
                "emulator metadata has no 'noise_std'", ControlWarning, stacklevel=user_stacklevel()
            )
        elif not np.isclose(trained, float(noise_std)):
            warnings.warn(
                f"noise_std = {noise_std:g} m/s^2 in the data but the emulator was trained with "
                f"noise_std = {trained:g}: the GD estimates will be biased",
                ControlWarning,
                stacklevel=user_stacklevel(),
            )
    if bcr is not None:
        check_feature(emulator, bcr)
    if track is not None:
        lo, hi = emulator.domain[emulator.t_names[0]]
        gds = [gd for _, gd in track.segments]
        outside = [gd for gd in gds if not lo <= gd <= hi]
        if outside:
            low, high = numbers_text(*outside, lo, hi)[-2:]
            raise EmulatorMismatchError(
                f"track GD {outside} outside the emulator's GD domain [{low}, {high}]"
            )
        differ = _track_road_mismatch(meta, track)
        if differ:
            warnings.warn(
                f"the track's road differs from the emulator's training roads ({differ}): the "
                "vehicle feels the short waves that a grid and a band hold, so the GD estimates "
                "will be biased (roadgen.track's default dx_m and band make the training roads')",
                ControlWarning,
                stacklevel=user_stacklevel(),
            )
    if simplex is not None:
        check_simplex(emulator, simplex, bcr)


def check_simplex(emulator, simplex: Simplex, bcr: BCRSettings | None = None) -> None:
    """`check_emulator`'s checks of a Simplex (speeds inside the speed domain, GD_max inside the
    GD domain: `EmulatorMismatchError`; GD_max out of the estimate's reach: `ControlWarning`),
    without its feature check: ``bcr`` only tells which estimator runs (method "window": the
    bottom of the domain is checked too), so a replay of an emulator that records no feature
    takes them. Each argument of the wrong kind is a `ControlError` naming it."""
    _check_is_emulator(emulator)
    check_emulator_inputs(emulator)
    check_instance(simplex, "simplex", Simplex)
    if bcr is not None:
        check_instance(bcr, "bcr", BCRSettings)
    _check_speeds(emulator, simplex)
    lo, hi = emulator_domain(emulator)[1]
    if not simplex.gd_max < hi:
        raise EmulatorMismatchError(
            f"Simplex gd_max = {simplex.gd_max:g} is not below the emulator's highest GD "
            f"{hi:g}: no GD estimate could exceed it, so safety mode would never start"
        )
    if not simplex.gd_max > lo:
        raise EmulatorMismatchError(
            f"Simplex gd_max = {simplex.gd_max:g} is not above the emulator's lowest GD "
            f"{lo:g}: every GD estimate exceeds it, so the robot would never leave safety "
            "mode; GD is in units of 1e-6 m^3 (Gd(n0) x 1e6: the paper's band is "
            "Simplex(gd_min=250, gd_max=350))"
        )
    _warn_if_out_of_reach(emulator, simplex, bcr is not None and bcr.method == "window")


REACH_GRID = 121
"""GD nodes (uniform in log GD, as `ObservationModel`'s default grid) of
`one_observation_posteriors` for an emulator of the block feature."""

DOMAIN_ENDS = ("bottom", "top")
"""The ends of the emulator's GD domain that `one_observation_posteriors` reads at."""


def one_observation_posteriors(
    emulator, speeds, ends: tuple[str, ...] = ("top",)
) -> dict[str, list[GridMarginal]]:
    """Per end of the emulator's GD domain in ``ends`` ("bottom": its lowest GD, "top": its
    highest) and per speed in ``speeds`` (m/s, clipped to the speed domain; in their order): the
    posterior of GD, under a uniform prior on the domain, given one observation equal to the
    emulator's mean at (speed, that end): one block's feature (`one_block_logliks`) for an
    emulator with a ``block_scatter``, else one window (`gpmsa.Calibrator`'s grid). The ends
    share the work: one prediction of the block feature per speed, one Calibrator."""
    (v_lo, v_hi), (lo, hi) = emulator_domain(emulator)
    speeds = [float(v) for v in np.clip(speeds, v_lo, v_hi)]
    unknown = [end for end in ends if end not in DOMAIN_ENDS]
    if unknown or not ends:
        raise ControlError(f"ends must be some of {DOMAIN_ENDS}, got {ends!r}")
    meta = dict(getattr(emulator, "metadata", None) or {})
    if "block_scatter" in meta:
        gd = np.geomspace(lo, hi, REACH_GRID)
        scatter = BlockScatter.from_dict(meta["block_scatter"])
        at = tuple(0 if end == "bottom" else -1 for end in ends)
        rows = {v: one_block_logliks(emulator, scatter, v, gd, at) for v in set(speeds)}
        return {
            end: [GridMarginal.from_log_density(gd, rows[v][i]) for v in speeds]
            for i, end in enumerate(ends)
        }
    calibrator = gpmsa.Calibrator(emulator)
    out = {}
    for end in ends:
        reads = np.full(len(speeds), lo if end == "bottom" else hi)
        obs = np.asarray(emulator.predict_mean(np.asarray(speeds), reads))
        obs = obs.reshape(len(speeds), 1, -1)
        out[end] = [
            GridMarginal.from_log_density(*calibrator.log_likelihood_grid([[v]], y))
            for v, y in zip(speeds, obs, strict=True)
        ]
    return out


def top_reach(emulator, speeds) -> tuple[float, float]:
    """(level, sd): the highest GD_max that the BCR's posterior mean reliably exceeds on ground
    at or beyond the top b of the emulator's GD domain, ``level = b - sd``, with ``sd`` the
    largest over ``speeds`` (m/s, clipped to the speed domain) of the posterior sd of GD given
    one observation equal to the emulator's mean at (speed, b) (`one_observation_posteriors`).
    The posterior is cut at b, so its mean stays below it: for a likelihood rising steeply
    beyond b the mean sits at b - sd (docs/closed-loop.md, The Simplex, has the
    measurements)."""
    hi = emulator_domain(emulator)[1][1]
    return _mean_reach(one_observation_posteriors(emulator, speeds)["top"], hi)


def top_quantile_reach(emulator, speeds, risk: float) -> float:
    """The highest GD_max that the (1 - ``risk``) posterior quantile (a Simplex with
    ``risk``) reliably exceeds on ground at or beyond the top b of the emulator's GD domain:
    the smallest over ``speeds`` (m/s, clipped to the speed domain) of that quantile of the
    posterior given one observation equal to the emulator's mean at (speed, b)
    (`one_observation_posteriors`; docs/closed-loop.md, The Simplex, has the measurements)."""
    return _quantile(one_observation_posteriors(emulator, speeds)["top"], risk, min)


def bottom_quantile(emulator, speed: float, risk: float) -> float:
    """The (1 - ``risk``) quantile of the posterior of GD given one observation equal to the
    emulator's mean at (``speed``, a), a the lowest GD of its domain
    (`one_observation_posteriors`): what a Simplex with ``risk`` compares with GD_max on the
    smoothest ground the emulator knows."""
    return _quantile(one_observation_posteriors(emulator, [speed], ("bottom",))["bottom"], risk)


def _mean_reach(top: list[GridMarginal], hi: float) -> tuple[float, float]:
    """(b - sd, sd) of `top_reach` from the posteriors at the domain's top b = ``hi``."""
    sd = max(post.sd() for post in top)
    return hi - sd, sd


def _quantile(posts: list[GridMarginal], risk: float, pick=max) -> float:
    """``pick`` (min or max) over ``posts`` of their (1 - ``risk``) quantiles."""
    return pick(float(post.ppf(1.0 - risk)) for post in posts)


def _risk_above(posts: list[GridMarginal], gd_max: float) -> float:
    """The smallest over ``posts`` of P(GD > ``gd_max``): a risk at or below it puts every
    posterior's (1 - risk) quantile at or above ``gd_max``, one above it puts some below."""
    return min(1.0 - float(post.cdf(gd_max)) for post in posts)


def _risk_text(low: float, high: float, up: bool) -> str | None:
    """A risk in [``low``, ``high``] and in (0, 1) as text: ``low`` rounded up (``up``) or
    ``high`` rounded down, to the fewest significant digits (2 to 6) that stay in that range
    (a risk that serves both ends of the domain); None where none does."""
    x = low if up else high
    if not 0 < x < 1:
        return None
    for sig in range(2, 7):
        digits = sig - 1 - int(np.floor(np.log10(x)))
        scaled = x * 10.0**digits
        value = (np.ceil(scaled) if up else np.floor(scaled)) / 10.0**digits
        if low <= value <= high and 0 < value < 1:
            return f"{value:.{max(digits, 0)}f}"
    return None


def _remedies(gd_max_text: str | None, risk_text: str | None, op: str) -> str:
    """The end of a reach warning: the GD_max and the risk (``op``: "<=" or ">=" it) that
    serve, either None where none serves both ends of the domain."""
    uses = [text for text in (gd_max_text, risk_text and f"risk {op} {risk_text}") if text]
    if not uses:
        return "no GD_max or risk serves both ends of this emulator's domain"
    return "use " + ", or ".join(uses)


def _warn_if_out_of_reach(emulator, simplex: Simplex, one_observation: bool = False) -> None:
    """ControlWarning where the GD the Simplex compares with GD_max cannot serve it, from the
    posteriors of one observation at the ends of the emulator's GD domain
    (`one_observation_posteriors`) at its speeds (v_safe, their middle, v_max): with
    ``risk=None`` a GD_max above `top_reach` (the posterior mean seldom exceeds it); with
    ``risk`` = alpha a GD_max above `top_quantile_reach` (the (1 - alpha) quantile seldom
    exceeds it), or, for a BCR that estimates from each window alone (``one_observation``:
    method "window"), below `bottom_quantile` at v_safe (that quantile exceeds it even on the
    smoothest ground: much of the drive in safety mode; the default methods pool the blocks or
    windows of steady ground and read lower there). Each names a GD_max and a risk that serve
    both ends: risks at most P(GD > GD_max) at the top and at least that at the bottom; for a
    feature monotone in GD one observation at the bottom makes GD > GD_max no likelier than the
    uniform prior does and one at the top no less likely, so the two ranges meet. With
    ``risk=None`` a posterior sd is at most half the domain's width, so a GD_max at or below
    the domain's middle is not computed."""
    (_, _), (lo, hi) = emulator_domain(emulator)
    risk, gd_max = simplex.risk, simplex.gd_max
    if risk is None and gd_max <= (lo + hi) / 2:
        return
    if not callable(getattr(emulator, "predict_mean", None)):
        return  # not an emulator that predicts (a stand-in of its records)
    speeds = (simplex.v_safe, (simplex.v_safe + simplex.v_max) / 2, simplex.v_max)
    both = risk is not None and one_observation
    posts = one_observation_posteriors(emulator, speeds, DOMAIN_ENDS if both else ("top",))
    top = posts["top"]
    if risk is None:
        level, sd = _mean_reach(top, hi)
        if gd_max > level:
            reach = f"{np.floor(level):.0f}"  # (rounded down: a gd_max at it is within reach)
            warnings.warn(
                f"Simplex gd_max = {gd_max:g} lies above {reach}, the highest GD_max the "
                f"posterior mean reliably reaches with this emulator: on ground at its highest "
                f"GD {hi:g} or rougher the mean sits about {sd:.0f} below it (the posterior sd "
                f"of one observation there), so safety mode may seldom or never start; use "
                f"gd_max <= {reach}, or risk=alpha (safety mode when P(GD > GD_max) > alpha)",
                ControlWarning,
                stacklevel=user_stacklevel(),
            )
        return
    q = numbers_text(1 - risk, 1.0)[0]  # (0.999999999 for risk 1e-9, not 1)
    level, top_risk = _quantile(top, risk, min), _risk_above(top, gd_max)
    floor, bottom_risk = -np.inf, 0.0  # (a pooling BCR: the bottom is not checked)
    if both:
        bottom = posts["bottom"][:1]  # at v_safe: the speed of a robot held in safety mode
        floor, bottom_risk = _quantile(bottom, risk), _risk_above(bottom, gd_max)
    if gd_max > level:
        reach = np.floor(level)  # (rounded down: a gd_max at it is within reach)
        lower = f"gd_max <= {reach:.0f}" if reach >= floor else None
        warnings.warn(
            f"Simplex gd_max = {gd_max:g} lies above {reach:.0f}, the highest GD_max the {q} "
            f"posterior quantile (risk = {risk:g}) reliably reaches with this emulator: on "
            f"ground at its highest GD {hi:g} that quantile of one observation's posterior "
            f"reads {level:.1f}, so safety mode may seldom or never start; "
            + _remedies(lower, _risk_text(bottom_risk, top_risk, up=False), "<="),
            ControlWarning,
            stacklevel=user_stacklevel(),
        )
    if floor > gd_max:
        least = np.ceil(floor)
        higher = f"gd_max >= {least:.0f}" if least < hi and least <= level else None
        warnings.warn(
            f"Simplex gd_max = {gd_max:g} lies below {floor:.1f}, the {q} posterior quantile "
            f"(risk = {risk:g}) of one observation on ground at the emulator's lowest GD "
            f"{lo:g} at v_safe = {simplex.v_safe:g} m/s: an estimate from one window there "
            f"calls for safety mode even on the smoothest ground the emulator knows, so the "
            f"robot may spend much of its drive in safety mode (the default methods pool the "
            f"blocks or windows of steady ground and read lower there); "
            + _remedies(higher, _risk_text(bottom_risk, top_risk, up=True), ">="),
            ControlWarning,
            stacklevel=user_stacklevel(),
        )


def recorded_vehicle_mismatch(emulator, model, what: str = "the recording") -> str:
    """Why the emulator does not suit ``what``, a recording of a simulation of the vehicle
    ``model`` (naming each differing parameter); "" where it does, where ``model`` is None (no
    vehicle recorded) or where the emulator records no vehicle (metadata ``vehicle``)."""
    meta = dict(getattr(emulator, "metadata", None) or {})
    if (
        model is None
        or "vehicle" not in meta
        or _canon(meta["vehicle"]) == _canon(model.describe())
    ):
        return ""
    return (
        f"{what} was simulated with another vehicle than the emulator was made for "
        f"({_vehicle_diff(meta['vehicle'], model, 'recording')})"
    )


def check_recorded_vehicle(emulator, model=None, noise_std: float | None = None,
                           what: str = "the recording") -> None:  # fmt: skip
    """Check an emulator against the vehicle model and accelerometer noise sd (m/s^2) a
    recording of a simulation records (`control.robot.Recording.vehicle`, ``noise_std``; None:
    not recorded, nothing checked). `EmulatorMismatchError` naming each differing parameter
    where the emulator records a vehicle (metadata ``vehicle``) and ``model`` differs from it
    (`recorded_vehicle_mismatch`); `ControlWarning` where it records a noise sd other than
    ``noise_std``. An emulator without those records is taken as it is (a real robot's
    recording records neither)."""
    why = recorded_vehicle_mismatch(emulator, model, what)
    if why:
        raise EmulatorMismatchError(
            f"{why}: replay it with an emulator trained for that vehicle "
            "(examples/train_emulator.py), or, to replay it anyway, pass check_vehicle=False "
            "(terrain-replay --ignore-vehicle)"
        )
    trained = _recorded_noise_std(dict(getattr(emulator, "metadata", None) or {}))
    if noise_std is not None and trained is not None and not np.isclose(trained, noise_std):
        warnings.warn(
            f"{what} was simulated with noise_std = {noise_std:g} m/s^2 but the emulator was "
            f"trained with noise_std = {trained:g}: the GD estimates will be biased",
            ControlWarning,
            stacklevel=user_stacklevel(),
        )


def _check_speeds(emulator, simplex: Simplex) -> None:
    """EmulatorMismatchError naming the Simplex's speeds outside the emulator's speed domain."""
    lo, hi = (float(b) for b in emulator.domain[emulator.x_names[0]])
    speeds = {"v_safe": simplex.v_safe, "v_max": simplex.v_max}
    names = [name for name, speed in speeds.items() if not within(speed, lo, hi)]
    if names:
        *shown, low, high = numbers_text(*(speeds[name] for name in names), lo, hi)
        outside = [f"{name} = {text} m/s" for name, text in zip(names, shown, strict=True)]
        raise EmulatorMismatchError(
            f"the Simplex's {' and '.join(outside)} {'lies' if len(outside) == 1 else 'lie'} "
            f"outside the emulator's speed domain "
            f"[{low}, {high}] m/s: the BCR learns nothing at such a speed, so the robot would "
            f"drive on an estimate that only ages; use a Simplex whose speeds lie in the domain "
            f"(control.Simplex(v_max=..., v_safe=...)) or an emulator trained over them "
            f"(examples/train_emulator.py --speed-range)"
        )


def check_likelihood(emulator, likelihood) -> None:
    """Raise `EmulatorMismatchError` unless ``likelihood`` (an `ObservationModel` or a
    `gpmsa.Calibrator`, prepared to save the work per run) was prepared for ``emulator``: the
    same object, or one with the same metadata, domain and predictions (at the domain's corners
    and centre)."""
    prepared = getattr(likelihood, "emulator", None)
    if prepared is None:
        raise EmulatorMismatchError(
            f"likelihood must be an ObservationModel or a gpmsa.Calibrator made from the "
            f"emulator, got {type(likelihood).__name__}"
        )
    if prepared is emulator:
        return
    meta, other = (dict(getattr(e, "metadata", None) or {}) for e in (emulator, prepared))
    differ = sorted(
        k for k in set(meta) | set(other) if _canon(meta.get(k)) != _canon(other.get(k))
    )
    if differ:
        raise EmulatorMismatchError(
            f"the likelihood was prepared for another emulator (metadata differ in {differ})"
        )
    if _canon(emulator.domain) != _canon(prepared.domain) or not np.allclose(
        _probe(emulator), _probe(prepared), rtol=1e-12, atol=0.0
    ):
        raise EmulatorMismatchError(
            "the likelihood was prepared for another emulator (domains or predictions differ)"
        )


def _probe(emulator) -> np.ndarray:
    """The emulator's mean predictions at the corners and centre of its (speed, GD) domain."""
    (v_lo, v_hi), (g_lo, g_hi) = (emulator.domain[n] for n in emulator.x_names + emulator.t_names)
    v = np.array([v_lo, v_lo, v_hi, v_hi, (v_lo + v_hi) / 2])
    gd = np.array([g_lo, g_hi, g_lo, g_hi, (g_lo + g_hi) / 2])
    mean = emulator.predict_mean(v, gd)
    return np.asarray(mean, dtype=float)


def emulator_vehicle(emulator):
    """The vehicle model the emulator was trained for (its metadata's ``vehicle``, as
    ``model.describe()`` recorded it), e.g. to run the closed loop with a user's emulator;
    EmulatorMismatchError when the record is missing or malformed."""
    record = _recorded(emulator, "vehicle", "which vehicle it was trained for")
    try:
        return vehicle.from_description(record)
    except (vehicle.VehicleError, TypeError) as exc:
        raise EmulatorMismatchError(f"the emulator's vehicle record is malformed: {exc}") from exc


def emulator_noise_std(emulator) -> float | None:
    """The accelerometer noise sd the emulator was trained with (metadata ``noise_std``), m/s^2;
    None when it is missing, not a positive number, or 0 (noise-free training data)."""
    _check_is_emulator(emulator)
    value = _recorded_noise_std(dict(getattr(emulator, "metadata", None) or {}))
    return value if value is not None and value > 0 else None


def _track_road_mismatch(meta: dict, track) -> str:
    """How ``track``'s road differs from the emulator's training roads (metadata ``road``): its
    grid step ``dx_m`` and the top of its band (cycles/m; a ``band`` of None is the grid's
    Nyquist limit), each named where it differs by more than 0.1 %; "" where both agree, and
    where the metadata or the track does not say (a record that is not a positive number)."""
    road = meta.get("road")
    if not isinstance(road, dict) or not is_real(road.get("dx_m")):
        return ""
    dx_trained = float(road["dx_m"])
    band = road.get("band")
    if band is None:
        top_trained = 0.5 / dx_trained if dx_trained > 0 else np.nan
    elif isinstance(band, list | tuple) and len(band) == 2 and is_real(band[1]):
        top_trained = float(band[1])
    else:
        top_trained = np.nan
    dx = getattr(track, "dx_m", None)
    band = getattr(getattr(track, "settings", None), "band", None)
    top = band[1] if isinstance(band, list | tuple) and len(band) == 2 else None
    differ = []
    for name, mine, trained, unit in (
        ("dx_m = ", dx, dx_trained, " m"),
        ("band up to ", top, top_trained, " cycles/m"),
    ):
        known = is_real(mine) and np.isfinite(trained) and trained > 0
        if known and not abs(float(mine) - trained) <= 1e-3 * trained:
            ours, theirs = numbers_text(mine, trained, digits=3)
            differ.append(f"{name}{ours}{unit} against {theirs}{unit}")
    return "; ".join(differ)


def _recorded_noise_std(meta: dict) -> float | None:
    """The metadata's ``noise_std`` as a finite float; None when it is missing or not a finite
    real number (a bool, a string, an integer beyond 64 bits: `is_real` refuses those, so the
    conversion cannot overflow)."""
    value = meta.get("noise_std")
    if not is_real(value):
        return None
    value = float(value)
    return value if np.isfinite(value) else None


def bcr_settings_for(emulator, **overrides) -> BCRSettings:
    """BCR settings for the emulator's recorded feature: method "changepoint" for the block
    feature (log_band_power); for a window feature (log_var, var) method "filter": the paper's
    windows, disjoint and interleaved, combined by a grid filter (`control.tracker`; the
    default before the change-point method), not the paper's estimator of each window alone:
    pass ``method="window"`` for that (as examples/closed_loop.py does for "the paper's
    method"). The sensor checks know the sensor's noise sd from the emulator's training noise
    (`emulator_noise_std`: the noise-floor check). ``method=``, ``sensor=`` and any other
    `BCRSettings` field may be overridden; a ``sensor=`` given replaces the emulator's noise sd
    too, so set its ``noise_sd_mps2`` (the sensor's own, if lower than the training noise) to
    keep that check."""
    feature = overrides.pop("feature", None)
    if feature is None:
        feature = emulator_feature(emulator)
    method = overrides.pop("method", None)
    if method is None:  # (BCRSettings refuses a feature that is not a FeatureSpec)
        block = getattr(feature, "name", None) == "log_band_power"
        method = "changepoint" if block else "filter"
    sensor = overrides.pop("sensor", None)
    if sensor is None:
        sensor = SensorLimits(noise_sd_mps2=emulator_noise_std(emulator))
    return replace_fields(BCRSettings(feature=feature, method=method, sensor=sensor), overrides)
