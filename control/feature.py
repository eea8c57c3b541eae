"""The observation the BCR makes of a block of front-axle accelerations.

Two features (the emulator records which one it was trained on; training and BCR agree through
`FeatureSpec`):

- ``"log_band_power"`` (default): log band powers of one short block (125 samples, ~1 s at
  120 Hz): a multitaper (DPSS, NW = 2, 3 tapers) power spectrum summed over 8 bands between 1.5
  and 60 Hz. The vector carries 2.5-3x the information about GD per second of driving of the
  paper's log f (docs/closed-loop.md, `benchmarks/feature_information.py`): the spectrum's shape
  changes with GD (the 2-7 Hz bands grow faster than GD, the 7-10 Hz resonance band saturates),
  which one variance cannot see. Then the block's 90% and 98% quantiles, each minus the block's
  mean (in g): the upper tail of the distribution, where a wheel that left the ground lands,
  which a spectrum cannot see; they add 14-17% to the information per second of the bands
  (`BAND_QUANTILES`; ``quantiles=()`` is the band vector alone).
- ``"log_var"``: y = log f, f = var(a) normalised by T over a 1,000-sample window (the paper's
  eq. 5; the log makes the multiplicative window scatter additive). ``"var"``: f itself.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, overload

import numpy as np

from control.errors import ControlError
from control.validation import (
    check_instance,
    float_array,
    is_choice,
    require_integers,
    require_reals,
)
from gpmsa.errors import numbers_text

FEATURES = ("log_band_power", "log_var", "var")
SCALAR_FEATURES = ("log_var", "var")
BAND_EDGES_HZ = (1.5, 4.5, 7.0, 10.0, 14.0, 20.0, 30.0, 45.0, 60.0)
BAND_QUANTILES = (0.9, 0.98)
"""Levels of the block quantiles the band feature appends by default (`FeatureSpec.quantiles`).
The upper tail holds what the band powers miss: held out, they add 14-17% to the information
per second about GD (benchmarks/feature_information.py, section 4), the lower tail and the
flight time nothing (docs/closed-loop.md, "Which feature")."""
STANDARD_GRAVITY = 9.80665
"""g, m/s^2: the unit of the feature's quantiles (of the order of the log band powers' spread).
The standard value (a unit, fixed in the emulator files' training data), not the vehicle
model's gravity (`vehicle.models.GRAVITY`, physics)."""
MAX_BLOCK_SAMPLES = 4096
"""Longest block or window (34 s at 120 Hz, 4 s at 1 kHz). The sensor checks' level check
compares every segment of a block with the rest, so its cost grows as the square of the block:
~0.25 s a block at this length, 0.1 ms at the default 125 samples."""


@dataclass(frozen=True)
class FeatureSpec:
    """What the BCR computes from a block of samples (recorded in the emulator's metadata).

    Attributes:
        name: one of FEATURES.
        block_samples: samples per block (the paper's window: 1,000; the band feature: 125).
        rate_hz: accelerometer rate, Hz.
        bands_hz: band edges, Hz (``log_band_power`` only): K + 1 increasing values <= rate / 2.
        taper_nw: time-bandwidth product of the DPSS tapers.
        n_tapers: number of DPSS tapers (<= 2 NW - 1).
        quantiles: levels in (0, 1), increasing (``log_band_power`` only): the block's
            quantiles at these levels, each minus the block's mean and in units of g
            (`STANDARD_GRAVITY`), appended to the band vector. They see the shape of the
            acceleration's distribution (the landings of a wheel that left the ground), which a
            spectrum cannot; the mean taken off makes them blind to an accelerometer's offset,
            as the band powers are. None (default): `BAND_QUANTILES` for ``log_band_power``,
            none for the window features; ``()``: the band vector alone (the feature of
            emulator files written before this field existed).

    ``bands_hz`` and ``quantiles`` are taken as any sequence of numbers (a list, an array) and
    stored as tuples of floats, ``quantiles`` always one (None given: its default).
    """

    name: str = "log_band_power"
    block_samples: int = 125
    rate_hz: float = 120.0
    bands_hz: tuple[float, ...] = BAND_EDGES_HZ
    taper_nw: float = 2.0
    n_tapers: int = 3
    quantiles: tuple[float, ...] = None  # type: ignore[assignment]  # None: made the default

    if TYPE_CHECKING:  # what the constructor takes (the fields above: what it stores)

        def __init__(
            self,
            name: str = "log_band_power",
            block_samples: int = 125,
            rate_hz: float = 120.0,
            bands_hz: Sequence[float] | np.ndarray = BAND_EDGES_HZ,
            taper_nw: float = 2.0,
            n_tapers: int = 3,
            quantiles: Sequence[float] | np.ndarray | None = None,
        ) -> None: ...

    def __post_init__(self) -> None:
        if not is_choice(self.name, FEATURES):
            raise ControlError(f"feature name must be one of {FEATURES}, got {self.name!r}")
        require_integers(self, ("block_samples", "n_tapers"))
        require_reals(self, ("rate_hz", "taper_nw"))
        # numpy scalars stored as Python numbers: to_dict is JSON-able, same_as symmetric
        for name, kind in (("block_samples", int), ("n_tapers", int), ("rate_hz", float),
                           ("taper_nw", float)):  # fmt: skip
            object.__setattr__(self, name, kind(getattr(self, name)))
        if not 16 <= self.block_samples <= MAX_BLOCK_SAMPLES:
            raise ControlError(
                f"block_samples must lie in [16, {MAX_BLOCK_SAMPLES}], got {self.block_samples}"
            )
        if not (np.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ControlError(f"rate_hz must be > 0 and finite, got {self.rate_hz}")
        edges = float_array(self.bands_hz, "bands_hz")
        if edges.ndim != 1 or not np.all(np.isfinite(edges)):
            raise ControlError(
                f"bands_hz must be a sequence of finite edges, Hz, got {self.bands_hz!r}"
            )
        object.__setattr__(self, "bands_hz", tuple(float(b) for b in edges))
        if self.name != "log_band_power":
            self._refuse_band_settings()
        else:
            nyquist = self.rate_hz / 2
            if edges.size < 2 or np.any(np.diff(edges) <= 0) or edges[0] < 0:
                raise ControlError(f"bands_hz must be >= 2 increasing edges >= 0, got {edges}")
            if edges[-1] > nyquist + 1e-9:
                top, nyquist_text = numbers_text(edges[-1], nyquist)
                raise ControlError(
                    f"bands_hz reach {top} Hz, above the Nyquist frequency {nyquist_text} Hz"
                )
            counts = _band_matrix(self.block_samples, float(self.rate_hz), self.bands_hz).sum(0)
            for lo, hi, count in zip(edges[:-1], edges[1:], counts, strict=True):
                if count == 0:
                    raise ControlError(
                        f"band [{lo:g}, {hi:g}) Hz holds no frequency bin of a "
                        f"{self.block_samples}-sample block at {self.rate_hz:g} Hz "
                        f"(bin spacing {self.rate_hz / self.block_samples:.3g} Hz)"
                    )
            if not (0 < self.taper_nw < self.block_samples / 2):
                raise ControlError(
                    f"taper_nw must lie in (0, block_samples / 2), got {self.taper_nw}"
                )
            if not (1 <= self.n_tapers <= max(1, int(2 * self.taper_nw) - 1)):
                raise ControlError(
                    f"n_tapers must lie in [1, 2 NW - 1] = [1, {int(2 * self.taper_nw) - 1}], "
                    f"got {self.n_tapers}"
                )
        if self.quantiles is None:
            default = BAND_QUANTILES if self.name == "log_band_power" else ()
            object.__setattr__(self, "quantiles", default)
        if isinstance(self.quantiles, str):
            raise ControlError(f"quantiles must be a sequence of levels, got {self.quantiles!r}")
        levels = float_array(self.quantiles, "quantiles")
        if levels.ndim != 1 or not np.all((levels > 0) & (levels < 1)):
            raise ControlError(
                f"quantiles must be a sequence of levels in (0, 1), got {self.quantiles!r}"
            )
        if np.any(np.diff(levels) <= 0):
            raise ControlError(f"quantiles must be increasing, got {self.quantiles!r}")
        if levels.size and self.name != "log_band_power":
            raise ControlError(
                f"quantiles go with the log_band_power feature only, not {self.name!r}"
            )
        object.__setattr__(self, "quantiles", tuple(float(q) for q in levels))

    def _refuse_band_settings(self) -> None:
        """ControlError for a band setting (bands, tapers) that differs from its default: the
        window features ignore them (the variance of the window, no spectrum)."""
        default = FeatureSpec.__dataclass_fields__
        for name in ("bands_hz", "taper_nw", "n_tapers"):
            value, usual = getattr(self, name), default[name].default
            if value != usual:
                raise ControlError(
                    f"{name} = {value!r} is ignored by the {self.name!r} feature (the window's "
                    f"variance, no spectrum): leave it at its default {usual!r}, or use "
                    "name='log_band_power'"
                )

    @property
    def dim(self) -> int:
        """Length K of the feature vector."""
        if self.name != "log_band_power":
            return 1
        return len(self.bands_hz) - 1 + len(self.quantiles)

    @property
    def block_s(self) -> float:
        """Duration of a block, s."""
        return self.block_samples / self.rate_hz

    def names(self) -> list[str]:
        """Output names for the emulator (``y_names``)."""
        if self.name != "log_band_power":
            return [self.name]
        e = self.bands_hz
        bands = [f"logP_{e[k]:g}_{e[k + 1]:g}Hz".replace(".", "p") for k in range(len(e) - 1)]
        return bands + [f"q{100 * q:g}_minus_mean".replace(".", "p") for q in self.quantiles]

    def units(self) -> list[str]:
        """Output units for the emulator (``y_units``)."""
        if self.name == "var":
            return ["(m/s^2)^2"]
        if self.name == "log_var":
            return ["log((m/s^2)^2)"]
        return ["log((m/s^2)^2)"] * (len(self.bands_hz) - 1) + ["g"] * len(self.quantiles)

    def to_dict(self) -> dict:
        """JSON-able form (the emulator metadata's ``feature``)."""
        return {**asdict(self), "bands_hz": list(self.bands_hz), "quantiles": list(self.quantiles)}

    @classmethod
    def from_dict(cls, d: dict) -> FeatureSpec:
        """Inverse of `to_dict`; also reads the older metadata form (name, window_samples).
        ControlError for a record that is not a mapping or lacks the name, the block length or
        the rate (both forms record them: their defaults would stand in unseen)."""
        if not isinstance(d, Mapping):
            raise ControlError(
                f"a feature record must be a mapping (FeatureSpec.to_dict), got {d!r:.60} "
                f"({type(d).__name__})"
            )
        d = dict(d)
        if "window_samples" in d and "block_samples" not in d:
            d["block_samples"] = d.pop("window_samples")
        for key in ("name", "block_samples", "rate_hz"):
            if key not in d:
                raise ControlError(f"the feature record has no {key!r}: {d!r:.80}")
        known = {k: d[k] for k in cls.__dataclass_fields__ if k in d}
        for key in ("bands_hz", "quantiles"):
            if key in known:
                if not isinstance(known[key], list | tuple):
                    raise ControlError(f"{key} must be a list of numbers, got {known[key]!r}")
                known[key] = tuple(known[key])
        known.setdefault("quantiles", ())  # written before the field existed: bands alone
        return cls(**known)

    def same_as(self, other: FeatureSpec) -> list[str]:
        """Names of the fields in which ``other`` differs (empty when they agree)."""
        check_instance(other, "other", FeatureSpec)
        diff = []
        for key in ("name", "block_samples", "rate_hz"):
            a, b = getattr(self, key), getattr(other, key)
            if a != b and not (isinstance(a, float) and np.isclose(a, b)):
                diff.append(key)
        if self.name == other.name == "log_band_power":
            for key in ("bands_hz", "taper_nw", "n_tapers", "quantiles"):
                a, b = np.ravel(getattr(self, key)), np.ravel(getattr(other, key))
                if a.shape != b.shape or not np.allclose(a, b):
                    diff.append(key)
        return diff


@lru_cache(maxsize=8)
def _tapers(n: int, nw: float, k: int) -> np.ndarray:
    from scipy.signal.windows import dpss  # here, not at import (tests/test_import_cost.py)

    return np.atleast_2d(dpss(n, nw, k))


@lru_cache(maxsize=8)
def _band_matrix(n: int, rate: float, edges: tuple[float, ...]) -> np.ndarray:
    """(n_bins, K) 0/1 matrix summing the one-sided spectrum's bins into the bands."""
    f = np.fft.rfftfreq(n, 1.0 / rate)
    e = np.asarray(edges)
    last = np.zeros(f.size, dtype=bool)
    last[f == e[-1]] = True
    cols = [(f >= lo) & (f < hi) for lo, hi in zip(e[:-1], e[1:], strict=True)]
    cols[-1] = cols[-1] | last
    return np.stack(cols, axis=1).astype(float)


def block_features(accel: np.ndarray, spec: FeatureSpec) -> np.ndarray:
    """The feature of each block.

    Args:
        accel: (n, B) blocks (or one block (B,)) of vertical front-axle acceleration, m/s^2,
            B = ``spec.block_samples``.
        spec: the feature.

    Returns:
        (n, K) features (K = ``spec.dim``); ``log_band_power`` in log((m/s^2)^2) (band power =
        the multitaper PSD integrated over the band), then the ``quantiles`` (block quantile
        minus block mean, g); a block with zero power in a band gives -inf there (the BCR
        treats it as a sensor fault).
    """
    check_instance(spec, "spec", FeatureSpec)
    a = np.atleast_2d(_samples(accel))
    if a.ndim != 2 or a.shape[1] != spec.block_samples:
        raise ControlError(
            f"accel must have shape (n, {spec.block_samples}) or ({spec.block_samples},), "
            f"got {np.shape(accel)}"
        )
    return features_of_blocks(a, spec)


def features_of_blocks(a: np.ndarray, spec: FeatureSpec) -> np.ndarray:
    """`block_features` of blocks ``a`` (n, B) float whose samples the caller checked (the
    BCR, in its loop)."""
    if spec.name != "log_band_power":
        return np.asarray(feature_of_variance(np.var(a, axis=1), spec.name))[:, None]
    x = a - a.sum(axis=1, keepdims=True) / a.shape[1]  # (a.mean's operations, no wrapper)
    w = _tapers(spec.block_samples, spec.taper_nw, spec.n_tapers)  # (k, B), unit energy each
    spectra = np.abs(np.fft.rfft(x[:, None, :] * w[None], axis=2)) ** 2  # (n, k, bins)
    # PSD (m/s^2)^2/Hz, two-sided scaling (the tapers' mean: np.mean's operations, no wrapper)
    power = spectra.sum(axis=1) / spectra.shape[1] / spec.rate_hz
    last = power.shape[1] if spec.block_samples % 2 else -1  # no Nyquist bin for odd B
    power[:, 1:last] *= 2.0  # one-sided
    band = power @ _band_matrix(spec.block_samples, spec.rate_hz, spec.bands_hz)
    with np.errstate(divide="ignore"):
        log_power = np.log(band * (spec.rate_hz / spec.block_samples))
    if not spec.quantiles:
        return log_power
    tails = _quantiles(x, spec.quantiles) / STANDARD_GRAVITY  # x: the mean taken off
    return np.concatenate([log_power, tails], axis=1)


def _samples(accel) -> np.ndarray:
    """``accel`` as a float array; ControlError unless it holds finite real numbers (no strings,
    bools, complex numbers, masked arrays, NaN or inf: the BCR's sample checks, for the public
    feature functions)."""
    arr = float_array(accel, "accel")
    if not np.all(np.isfinite(arr)):
        raise ControlError("accel holds NaN or inf: a block's feature needs finite samples, m/s^2")
    return arr


def _quantiles(x: np.ndarray, levels: tuple[float, ...]) -> np.ndarray:
    """(n, L) quantiles of each row of x (n, B) at ``levels``: numpy's default (linear) method,
    to the last bit, from a partition around the order statistics it interpolates (a twentieth
    of np.quantile's time for one block)."""
    below, above, kth, weight = _quantile_ranks(x.shape[1], levels)
    ordered = np.partition(x, kth, axis=1)
    low, high = ordered[:, below], ordered[:, above]
    step = high - low  # numpy interpolates from the nearer order statistic
    return np.where(weight < 0.5, low + step * weight, high - step * (1 - weight))


@lru_cache(maxsize=8)
def _quantile_ranks(
    n: int, levels: tuple[float, ...]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(order statistic below, above, both sorted and unique, the weight of the upper one) of
    each level's quantile of n values (`_quantiles`; read-only: every call shares them)."""
    position = np.asarray(levels) * (n - 1)
    below = np.floor(position).astype(int)
    above = np.minimum(below + 1, n - 1)
    out = below, above, np.unique(np.concatenate([below, above])), position - below
    for arr in out:
        arr.flags.writeable = False
    return out


def window_feature(accel: np.ndarray, feature: str = "log_var") -> float:
    """The paper's observation y of one window: "var" (f, eq. 5) or "log_var" (log f).

    Args:
        accel: (T,) vertical front-axle accelerations, m/s^2.
        feature: "var" or "log_var".

    Returns:
        y; NaN for "log_var" of a window with zero variance.
    """
    accel = _samples(accel)
    if accel.ndim != 1 or accel.size < 2:
        raise ControlError(f"accel must be 1-D with >= 2 samples, got shape {accel.shape}")
    return float(feature_of_variance(np.var(accel), feature))  # var: normalised by T (eq. 5)


@overload
def feature_of_variance(f: float | np.floating, feature: str = "log_var") -> float: ...
@overload
def feature_of_variance(
    f: np.ndarray | Sequence[float], feature: str = "log_var"
) -> np.ndarray: ...
def feature_of_variance(
    f: float | np.floating | np.ndarray | Sequence[float], feature: str = "log_var"
) -> float | np.ndarray:
    """The observation y of windows whose variance (normalised by T) is ``f``, (m/s^2)^2.

    The one map from f to y, shared by the BCR (``window_feature``) and emulator training, so
    that both see the same quantity. "log_var" of f <= 0 is NaN.
    """
    if not is_choice(feature, SCALAR_FEATURES):
        raise ControlError(f"feature must be one of {SCALAR_FEATURES}, got {feature!r}")
    f = float_array(f, "f")  # (None or a string is no variance: not NaN)
    if feature == "var":
        return f[()]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(f > 0, np.log(np.where(f > 0, f, 1.0)), np.nan)[()]
