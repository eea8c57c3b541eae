"""The emulator's likelihood of one block's feature vector, and the plausibility of the block.

The emulator (a gpmsa multivariate emulator, trained on the *expected* feature of a block: the
mean over many blocks of each training run) gives the mean mu(v, GD) of the feature; the
block-to-block scatter about it is a known observation covariance Sigma(v) learned from the same
campaign (`BlockScatter`). One block y at speed v has the likelihood

    p(y | GD) = t_nu(y; mu(v, GD), Sigma(v))   (a multivariate Student t; nu = inf: Gaussian)

evaluated on a grid of GD (uniform in log GD over the emulator's domain). mu is tabulated once on
(speed, GD) nodes from the emulator's point estimate and interpolated linearly in speed;
Sigma(v) likewise. Blocks are disjoint and their features nearly independent (lag-1 correlation
0.0-0.15; Sigma is the long-run covariance, so that pooled blocks are not over-counted).

Plausibility: the squared Mahalanobis distance of y from the nearest mu(v, GD) over the whole GD
domain; under the model d2 / K follows an F(K, nu) law (chi-square for nu = inf), so a block that
no GD in the domain explains has a tiny upper-tail probability.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special, stats
from scipy.linalg import cholesky, solve_triangular
from scipy.linalg.lapack import dpotrf

from control.errors import ControlError, EmulatorMismatchError
from control.feature import FeatureSpec
from control.sensor_checks import MAX_SPEED_MPS
from control.validation import float_array, is_integer, is_real, require_reals, within
from gpmsa.errors import numbers_text

MAX_TABLE_NODES = 1_000_000
"""Most (speed, GD) nodes of an ObservationModel's mean table (the default has 3,751)."""


@dataclass(frozen=True, eq=False)
class BlockScatter:
    """Covariance of one block's feature about its expected value, as a function of speed.

    Attributes:
        speed: (n,) speed nodes, m/s, increasing.
        cov: (n, K, K) covariance of the feature at each node (long-run: batch means of
            consecutive blocks, so that correlation between neighbouring blocks is included).
        dof: degrees of freedom nu of the Student-t block law (inf: Gaussian).
    """

    speed: np.ndarray
    cov: np.ndarray
    dof: float = np.inf

    def __post_init__(self) -> None:
        require_reals(self, ("dof",))
        s = float_array(self.speed, "speed")
        c = float_array(self.cov, "cov")
        if s.ndim != 1 or s.size < 2 or np.any(np.diff(s) <= 0) or not np.all(np.isfinite(s)):
            raise ControlError(f"speed must be >= 2 increasing finite nodes, got {s}")
        if c.ndim != 3 or c.shape[0] != s.size or c.shape[1] != c.shape[2]:
            raise ControlError(f"cov must have shape ({s.size}, K, K), got {c.shape}")
        if not np.all(np.isfinite(c)):
            raise ControlError("cov must hold finite, positive-definite matrices")
        scale = np.max(np.abs(c), axis=(1, 2), keepdims=True)
        if np.any(np.abs(c - c.transpose(0, 2, 1)) > 1e-10 * scale):
            raise ControlError("cov must hold symmetric matrices (a covariance)")
        if np.any(np.linalg.eigvalsh(c)[:, 0] <= 0):
            raise ControlError("cov must hold finite, positive-definite matrices")
        if not (self.dof > 2):
            raise ControlError(f"dof must be > 2 (or inf), got {self.dof}")
        object.__setattr__(self, "speed", s)
        object.__setattr__(self, "cov", c)
        object.__setattr__(self, "dof", float(self.dof))

    def to_dict(self) -> dict:
        """JSON-able form (stored in the emulator's metadata as ``block_scatter``)."""
        return {
            "speed_mps": self.speed.tolist(),
            "cov": self.cov.tolist(),
            "dof": None if np.isinf(self.dof) else self.dof,
        }

    @classmethod
    def from_dict(cls, d: dict) -> BlockScatter:
        """Inverse of `to_dict`."""
        try:
            dof = np.inf if d.get("dof") is None else float(d["dof"])
            return cls(np.asarray(d["speed_mps"], float), np.asarray(d["cov"], float), dof)
        except (AttributeError, KeyError, TypeError, ValueError, ControlError) as exc:
            raise EmulatorMismatchError(
                f"the emulator's block_scatter is malformed: {exc}"
            ) from exc


class ObservationModel:
    """Likelihood of GD on a grid for one block feature (see the module docstring).

    Args:
        emulator: a gpmsa Emulator with one known input (speed, m/s), one calibration parameter
            (GD) and K outputs (the feature), whose ``metadata["block_scatter"]`` holds the
            `BlockScatter` (or pass ``scatter``).
        scatter: the block scatter (default: from the emulator's metadata).
        n_grid: GD nodes, uniform in log GD over the emulator's GD domain.
        n_speed: speed nodes of the mean table over the emulator's speed domain.
    """

    # `_speed_terms` of the last speed; a class default, so that a model pickled before it
    # existed restores without it
    _last_speed: tuple | None = None

    def __init__(
        self, emulator, scatter: BlockScatter | None = None, n_grid: int = 121, n_speed: int = 31
    ) -> None:
        if not all(hasattr(emulator, a) for a in ("p", "q", "l_sim", "domain", "predict_mean")):
            raise ControlError(
                f"emulator must be a gpmsa.Emulator, got {emulator!r:.60} "
                f"({type(emulator).__name__})"
            )
        if scatter is not None and not isinstance(scatter, BlockScatter):
            raise ControlError(
                f"scatter must be a control BlockScatter or None, got {scatter!r:.60}"
            )
        check_emulator_inputs(emulator)
        if scatter is None:
            meta = getattr(emulator, "metadata", None) or {}
            if "block_scatter" not in meta:
                raise EmulatorMismatchError(
                    "the emulator's metadata has no 'block_scatter' (the per-block observation "
                    "covariance): it was not trained for the block feature; train it with "
                    "control.training.fit_band_emulator (your runs at known speed and GD) or "
                    "examples/train_emulator.py, which write it"
                )
            scatter = BlockScatter.from_dict(meta["block_scatter"])
        if scatter.cov.shape[1] != emulator.l_sim:
            raise EmulatorMismatchError(
                f"block_scatter is {scatter.cov.shape[1]}-dimensional but the emulator has "
                f"{emulator.l_sim} outputs"
            )
        _check_feature_length(emulator)
        if not (is_integer(n_grid) and n_grid >= 16):
            raise ControlError(f"n_grid must be an integer >= 16, got {n_grid}")
        if not (is_integer(n_speed) and n_speed >= 2):
            raise ControlError(f"n_speed must be an integer >= 2, got {n_speed}")
        if n_grid * n_speed > MAX_TABLE_NODES:
            raise ControlError(
                f"n_grid x n_speed = {n_grid * n_speed} nodes, above MAX_TABLE_NODES = "
                f"{MAX_TABLE_NODES} (the mean table: one emulator prediction per node)"
            )
        self.emulator = emulator
        self.scatter = scatter
        (v_lo, v_hi) = emulator.domain[emulator.x_names[0]]
        (g_lo, g_hi) = emulator.domain[emulator.t_names[0]]
        if not g_lo > 0:  # a given range, SimData(t_range=), may start at 0
            raise EmulatorMismatchError(
                f"the emulator's GD domain [{g_lo:g}, {g_hi:g}] must be positive: the block "
                "likelihood's grid is uniform in log GD (fit with a t_range starting above 0)"
            )
        self.speed_range = (float(v_lo), float(v_hi))
        self.gd = np.geomspace(g_lo, g_hi, int(n_grid))
        self.speed = np.linspace(v_lo, v_hi, int(n_speed))
        V, G = np.meshgrid(self.speed, self.gd, indexing="ij")
        mean = emulator.predict_mean(V.ravel(), G.ravel())
        self._mean = mean.reshape(self.speed.size, self.gd.size, -1)  # (S, G, K)
        self.dim = self._mean.shape[2]
        self._last = None
        nu, K = scatter.dof, self.dim
        self._log_norm = (
            -0.5 * K * np.log(2 * np.pi)
            if np.isinf(nu)
            else float(stats.multivariate_t.logpdf(np.zeros(K), np.zeros(K), np.eye(K), df=nu))
        )

    def _at(self, v: float) -> tuple[np.ndarray, np.ndarray]:
        """(mean (G, K), lower Cholesky factor of Sigma (K, K)) at speed v (linear in v)."""
        lo, hi = self.speed_range
        if not within(v, lo, hi):
            shown = numbers_text(v, lo, hi, digits=10)[0]  # (a narrow range: 1e-9 of its width)
            lo_text, hi_text = numbers_text(v, lo, hi)[1:]  # (:g, more where v reads as one)
            raise ControlError(
                f"speed {shown} m/s outside the emulator's range [{lo_text}, {hi_text}]"
            )
        x = _clip((v - lo) / (hi - lo) * (self.speed.size - 1), 0.0, self.speed.size - 1.0)
        i = min(int(x), self.speed.size - 2)
        a = x - i
        mean = (1 - a) * self._mean[i] + a * self._mean[i + 1]
        return mean, _cholesky_lower(_interp_cov(self.scatter, v))

    def _mahalanobis(self, y: np.ndarray, v: float) -> tuple[np.ndarray, float]:
        """Squared Mahalanobis distances of y from the mean at every GD node (G,), and half the
        log-determinant of Sigma(v). The last call is remembered (the BCR asks twice)."""
        return self._solve(y, v)[1]

    def _solve(self, y: np.ndarray, v: float) -> tuple:
        """(key, `_mahalanobis`'s pair, (the factor's inverse, the whitened residual at the
        nearest GD node)) of y at v: one tuple, so that a caller reads the parts of one call
        even where BCRs on other threads share this model."""
        y = np.asarray(y)
        last = self._last
        if last is not None and y.dtype == np.float64 and y.shape == (self.dim,) and is_real(v):
            key = (y.tobytes(), float(v))  # (the usual case: the y and v of the last call,
            if last[0] == key:  # checked then; a NaN v never equals itself)
                return last
        if y.shape != (self.dim,) or y.dtype.kind not in "iuf" or not np.all(np.isfinite(y)):
            raise ControlError(f"y must be {self.dim} finite numbers (K,), got {y!r}")
        y = y.astype(float, copy=False)
        if not (is_real(v) and np.isfinite(v)):
            raise ControlError(f"v must be a finite speed, m/s, got {v!r}")
        key = (y.tobytes(), float(v))
        if last is not None and last[0] == key:
            return last
        _, mean, inverse, half_logdet = self._speed_terms(float(v))
        r = inverse @ (y[None, :] - mean).T  # (K, G)
        d2 = np.sum(r**2, axis=0)
        out = d2, half_logdet
        self._last = last = (key, out, (inverse, r[:, int(np.argmin(d2))]))
        return last

    def _speed_terms(self, v: float) -> tuple:
        """(v, mean (G, K), the inverse of Sigma's lower Cholesky factor, half the
        log-determinant of Sigma) at speed v. The last speed's are remembered: a block at the
        speed of the one before (a steady speed command) reuses them (one tuple: see `_solve`)."""
        terms = self._last_speed
        if terms is not None and terms[0] == v:
            return terms
        mean, chol = self._at(v)
        # an explicit inverse of the 8 x 8 factor: a LAPACK triangular solve of this size costs
        # ~1 ms in OpenBLAS's threads, the product microseconds
        inverse = np.linalg.inv(chol)
        self._last_speed = terms = (v, mean, inverse, float(np.sum(np.log(np.diag(chol)))))
        return terms

    def loglik(self, y: np.ndarray, v: float) -> np.ndarray:
        """log p(y | GD) on ``self.gd`` (G,), all constants included.

        Args:
            y: (K,) the block's feature. v: the block's mean speed, m/s.
        """
        d2, half_logdet = self._mahalanobis(y, v)
        K, nu = self.dim, self.scatter.dof
        kernel = -0.5 * d2 if np.isinf(nu) else -0.5 * (nu + K) * np.log1p(d2 / nu)
        return self._log_norm + kernel - half_logdet

    def plausibility(self, y: np.ndarray, v: float) -> tuple[float, float]:
        """(d2, p): the smallest squared Mahalanobis distance of y over the GD domain and its
        upper-tail probability under the block law (F(K, nu) of d2 / K; chi-square(K) for a
        Gaussian). A small p means that no GD in the domain explains the block."""
        d2, _ = self._mahalanobis(y, v)
        d2_min = float(np.min(d2))
        K, nu = self.dim, self.scatter.dof
        p = special.chdtrc(K, d2_min) if np.isinf(nu) else special.fdtrc(K, nu, d2_min / K)
        return d2_min, float(p)

    def band_gain(self, y: np.ndarray, v: float, bands: slice) -> float:
        """The acceleration gain that a block's feature y (K,) at speed v (m/s) reads as against
        the GD domain: its log band powers (the channels ``bands``) less the emulator's mean
        ones, averaged over those channels, at the GD node where that offset is smallest, as a
        gain of the acceleration (exp(offset / 2)). 1 where some GD of the domain matches the
        block's level; below 1 for a block quieter than the smoothest GD explains (0.1: the
        acceleration of that smoothest ground read at a tenth), above for one louder than the
        roughest. For messages (an implausible block's likely unit slip), not for estimates."""
        mean = self._speed_terms(float(v))[1]
        offset = np.mean(np.asarray(y, dtype=float)[bands] - mean[:, bands], axis=1)  # (G,)
        return float(np.exp(offset[np.argmin(np.abs(offset))] / 2.0))

    def level_score(self, y: np.ndarray, v: float, direction: np.ndarray) -> float:
        """The residual of y from the mean at its best GD (the node of the smallest Mahalanobis
        distance) along ``direction`` (K,), in sds of that projection under Sigma(v) (the
        generalised least-squares estimate of a shift of y along ``direction``, standardised):
        about N(0, 1) or narrower under the model (the best GD absorbs part of any shift), and
        negative where y lies further below the mean along ``direction`` than a GD explains. The
        BCR's direction is that of a lower sensor gain (`BCR`'s quiet-signal check).

        Args:
            y: (K,) the block's feature. v: the block's mean speed, m/s.
            direction: (K,) finite, not all zero.
        """
        _, _, (inverse, residual) = self._solve(y, v)
        d = np.asarray(direction)
        if (d.shape != (self.dim,) or d.dtype.kind not in "iuf" or not np.all(np.isfinite(d))
                or not np.any(d)):  # fmt: skip
            raise ControlError(
                f"direction must be {self.dim} finite numbers (K,), not all zero, got {d!r}"
            )
        w = inverse @ d
        return float(w @ residual / np.sqrt(w @ w))


def one_block_logliks(
    emulator, scatter: BlockScatter, v: float, gd: np.ndarray, at: tuple[int, ...] = (-1,)
) -> np.ndarray:
    """log p(y | GD) (len(at), G) on the increasing GD nodes ``gd`` (G,), up to a constant, of
    one block at speed ``v`` (m/s) whose feature y is the emulator's mean at (v, ``gd[k]``), a
    row for each node index k in ``at``: what one block read at a node says (at the grid's ends:
    `control.compat.one_observation_posteriors`)."""
    mean = np.asarray(emulator.predict_mean(np.full(gd.size, float(v)), gd), dtype=float)
    mean = mean.reshape(gd.size, -1)  # (G, K)
    chol = _cholesky_lower(_interp_cov(scatter, v))
    diff = (mean[None, :, :] - mean[list(at)][:, None, :]).reshape(-1, mean.shape[1])
    d2 = np.sum(solve_triangular(chol, diff.T, lower=True) ** 2, axis=0).reshape(len(at), -1)
    nu, K = scatter.dof, mean.shape[1]
    return -0.5 * d2 if np.isinf(nu) else -0.5 * (nu + K) * np.log1p(d2 / nu)


def _check_feature_length(emulator) -> None:
    """EmulatorMismatchError where the emulator's metadata records a feature (``feature``)
    whose length is not its number of outputs (the BCR computes that feature from each block),
    or a malformed one; nothing recorded: nothing to check."""
    record = (getattr(emulator, "metadata", None) or {}).get("feature")
    if record is None:
        return
    try:
        feature = FeatureSpec.from_dict(record)
    except (AttributeError, TypeError, ValueError) as exc:
        raise EmulatorMismatchError(f"the emulator's feature is malformed: {exc}") from exc
    check_feature_outputs(emulator, feature)


def check_feature_outputs(emulator, feature: FeatureSpec) -> None:
    """EmulatorMismatchError where the emulator's outputs cannot be ``feature`` (its recorded
    feature, which the BCR computes from each block or window): another number of outputs
    (``l_sim``), or an output unit label (``y_units``, where given) that names another
    transform or unit (`output_unit_slip`). An object without those attributes (a stand-in of
    an emulator's records) is not checked."""
    l_sim = getattr(emulator, "l_sim", None)
    if l_sim is not None and feature.dim != l_sim:
        raise EmulatorMismatchError(
            f"the emulator's metadata records the feature {feature.name!r} of {feature.dim} "
            f"output{'s' if feature.dim != 1 else ''} ({', '.join(feature.names())}), but the "
            f"emulator has {l_sim}: record the feature its outputs were computed as "
            "(metadata={'feature': control.FeatureSpec(...).to_dict(), ...}), or fit it on that "
            "feature's outputs"
        )
    cov = ((getattr(emulator, "metadata", None) or {}).get("block_scatter") or {}).get("cov")
    shape = np.shape(cov) if isinstance(cov, list | tuple | np.ndarray) else ()
    if len(shape) == 3 and shape[1] != feature.dim:
        raise EmulatorMismatchError(
            f"the emulator's block_scatter is {shape[1]}-dimensional but its feature "
            f"{feature.name!r} has {feature.dim} outputs: record the scatter of that feature's "
            "blocks (control.training.block_scatter; control.training.fit_band_emulator "
            "records both)"
        )
    labels = tuple(getattr(emulator, "y_units", None) or ())
    for k, (label, unit) in enumerate(zip(labels, feature.units(), strict=False)):
        why = output_unit_slip(str(label), unit)
        if why:
            raise EmulatorMismatchError(
                f"the emulator's y_units[{k}] = {label!r} ({feature.names()[k]}): {why}; the "
                f"BCR compares it with the feature {feature.name!r} of the IMU's samples in "
                f"{unit}, so every estimate would be biased: fit the emulator on that feature "
                f"(control.feature.block_features / window_feature of accelerations in m/s^2)"
            )


OTHER_SPEED_UNITS = frozenset(("km/h", "kmh", "kph", "km/hr", "kmph", "kmh^-1", "km*h^-1",
                               "km.h^-1", "km/hour", "mph", "mi/h", "ft/s", "fps", "ft/sec",
                               "mm/s", "cm/s", "in/s", "kn", "kt", "kts", "knot",
                               "knots"))  # fmt: skip
"""Speed unit labels (as `_unit_key` writes them) that are not m/s (`check_emulator_inputs`)."""

_PER_S2 = ("/s^2", "s^-2", "*s^-2", ".s^-2", "/s/s", "/sec^2")
_PER_S4 = ("^2/s^4", "^2s^-4", "^2*s^-4", "^2.s^-4", "^2/sec^4", "2/s4", "2s^-4")


def _spellings(length: str) -> tuple[set[str], set[str]]:
    """The unit keys of an acceleration in ``length`` per s^2 and of its power (squared)."""
    accel = {length + s for s in _PER_S2}
    return accel, {f"({a})^2" for a in accel} | {length + s for s in _PER_S4}


def _output_units() -> dict[str, tuple[str, str]]:
    """Output unit keys (`_unit_key`, a log transform taken off) -> (quantity, unit): the
    spellings of an acceleration ("accel") or its power ("power") in m/s^2, of the quantiles'
    g, and in the other units this knows (cm, mm, ft or in per s^2, gal, milli-g, g^2)."""
    accel, power = _spellings("m")
    known = {**dict.fromkeys(accel, ("accel", "m/s^2")), **dict.fromkeys(power, ("power", "m/s^2"))}
    known.update(dict.fromkeys(("g", "g0", "g_0", "gn", "g_n"), ("accel", "g")))
    for other in ("cm", "mm", "ft", "in"):
        accel, power = _spellings(other)
        known.update(dict.fromkeys(accel, ("accel", other + "/s^2")))
        known.update(dict.fromkeys(power, ("power", other + "/s^2")))
    for other in ("gal", "mg", "g"):
        if other != "g":
            known[other] = ("accel", other)
        known.update(dict.fromkeys((f"{other}^2", f"({other})^2"), ("power", other)))
    return known


_OUTPUT_UNITS = _output_units()
_LOG_TRANSFORMS = (("10*log10", "log10"), ("10log10", "log10"), ("log10", "log10"),
                   ("log_10", "log10"), ("db", "log10"), ("log_e", "log"), ("loge", "log"),
                   ("log", "log"), ("ln", "log"))  # fmt: skip
"""Prefixes of an output unit key that name a transform: "log" the natural log (the feature's
log f), "log10" the log to base 10 or decibels (log f / ln 10, 10 log10 f)."""
_UNICODE = (("**", "^"), ("⁻¹", "^-1"), ("⁻²", "^-2"), ("⁻⁴", "^-4"), ("²", "^2"), ("⁴", "^4"),
            ("·", "*"), ("[", "("), ("]", ")"))  # fmt: skip


def _unit_key(label: str) -> str:
    """A unit label as `check_emulator_inputs` and `output_unit_slip` compare it: lower case,
    without spaces, "**" and superscripts as "^" ("m·s⁻²" as "m*s^-2"), brackets as
    parentheses."""
    key = "".join(str(label).split()).lower()
    for old, new in _UNICODE:
        key = key.replace(old, new)
    return key


def _unwrapped(key: str) -> str:
    """``key`` without one pair of parentheses around all of it."""
    if not (key.startswith("(") and key.endswith(")")):
        return key
    depth = 0
    for c in key[:-1]:
        depth += {"(": 1, ")": -1}.get(c, 0)
        if depth == 0:
            return key  # "(m/s^2)/(s)": the first pair closes before the end
    return key[1:-1]


def _output_kind(label: str) -> tuple[str, str | None, str | None] | None:
    """(transform, quantity, unit) an output unit label names: transform "" (none), "log" or
    "log10" (`_LOG_TRANSFORMS`); quantity and unit (`_output_units`) where the rest of it is a
    spelling this knows, else None. None for a label that names neither ("" included)."""
    key = _unit_key(label)
    transform = ""
    for prefix, name in _LOG_TRANSFORMS:
        if key.startswith(prefix):
            transform, key = name, _unwrapped(key[len(prefix) :])
            break
    quantity, unit = _OUTPUT_UNITS.get(key, (None, None))
    if not transform and quantity is None:
        return None
    return transform, quantity, unit


def output_unit_slip(label: str, unit: str) -> str:
    """Why an emulator output whose ``y_units`` label is ``label`` cannot be a feature channel
    of unit ``unit`` (`FeatureSpec.units`: "log((m/s^2)^2)", "(m/s^2)^2" or "g"), or "". Only
    a label that is a known spelling of another transform or unit (`_output_kind`) is refused:
    a power where the feature is its log (f, not log f), a log where it is the power, a log10
    or dB where it is the natural log, an acceleration where it is a power, a power or
    quantile in another unit. A label naming neither a transform nor a unit this knows ("log
    var", "g (9.81 m/s^2)", "") is taken."""
    got, want = _output_kind(label), _output_kind(unit)
    if got is None or want is None or got == want:
        return ""
    (transform, quantity, of), (w_transform, _, w_of) = got, want
    if w_of == "g":
        return "a quantile in another unit or transform, where the feature's are in g"
    if of not in (None, w_of):
        return f"an acceleration in another unit than {w_of}"
    if transform != w_transform:
        if not w_transform:
            return "a log power, where the feature is the power itself (f, not log f)"
        if transform == "log10":
            return (
                "a log10 (or dB) power, where the feature is its natural log (log f, not log10 f)"
            )
        if quantity == "power":
            return "a power itself, where the feature is its log (log f, not f)"
    if quantity == "accel":
        its = "its power" if not w_transform else "the log of its power"
        return f"an acceleration, where the feature is {its}"
    return ""


def check_emulator_inputs(emulator) -> None:
    """EmulatorMismatchError where ``emulator``'s inputs are not what the BCR reads: one known
    input x, the speed (m/s), and one calibration parameter t, GD (1e-6 m^3), both continuous;
    a speed domain whose lowest speed lies beyond any ground robot's (`MAX_SPEED_MPS`: GD
    fitted as x and the speed as t); an x unit label (``x_units``, where given) naming another
    speed unit (`OTHER_SPEED_UNITS`). Attributes an object lacks (a stand-in of an emulator's
    records) are not checked."""
    x_names, t_names = getattr(emulator, "x_names", None), getattr(emulator, "t_names", None)
    if x_names is None or t_names is None:
        return
    x_names, t_names = list(x_names), list(t_names)
    if len(x_names) != 1 or len(t_names) != 1:
        raise EmulatorMismatchError(
            f"the BCR reads an emulator of one known input x, the speed (m/s), and one "
            f"calibration parameter t, GD (1e-6 m^3); this one has x = {x_names} and t = "
            f"{t_names}: fit gpmsa.SimData(x=speed[:, None], t=gd[:, None], ...) (as "
            "control.training.fit_band_emulator does), one emulator for each value of a "
            "further input (a payload, a second roughness parameter)"
        )
    categorical = sorted(getattr(emulator, "categorical", None) or {})
    if categorical:
        raise EmulatorMismatchError(
            f"the emulator's {' and '.join(map(repr, categorical))} "
            f"{'is' if len(categorical) == 1 else 'are'} categorical (SimData x_categorical / "
            "t_categorical): the BCR reads speed and GD as continuous inputs (it interpolates "
            "the speed and puts GD on a grid between the training values); fit them as "
            "continuous inputs"
        )
    domain = getattr(emulator, "domain", None)
    if domain is not None and x_names[0] in domain and t_names[0] in domain:
        v_lo, v_hi = (float(b) for b in domain[x_names[0]])
        if v_lo > MAX_SPEED_MPS:
            lo_text, hi_text = numbers_text(v_lo, v_hi)
            g_lo, g_hi = numbers_text(*(float(b) for b in domain[t_names[0]]))
            raise EmulatorMismatchError(
                f"the emulator's speed input x = {x_names[0]!r} spans [{lo_text}, {hi_text}], "
                f"beyond any ground robot's speed (MAX_SPEED_MPS = {MAX_SPEED_MPS:g} m/s), and "
                f"its GD t = {t_names[0]!r} spans [{g_lo}, {g_hi}]: GD fitted as x and the "
                "speed as t? x must be the speed (m/s) and t GD: fit "
                "gpmsa.SimData(x=speed[:, None], t=gd[:, None], ...)"
            )
    x_units = tuple(getattr(emulator, "x_units", None) or ())
    if x_units and _unit_key(x_units[0]) in OTHER_SPEED_UNITS:
        raise EmulatorMismatchError(
            f"the emulator's x_units = {x_units[0]!r}: the BCR reads the speed (x = "
            f"{x_names[0]!r}) in m/s, as odometry gives it, so a speed in another unit reads "
            "every block at the wrong speed: fit the emulator on the speed in m/s"
        )


def _clip(x: float, lo: float, hi: float) -> float:
    """np.clip of one float (without its array round trip: same value)."""
    return min(max(x, lo), hi)


def _cholesky_lower(c: np.ndarray) -> np.ndarray:
    """``scipy.linalg.cholesky(c, lower=True)`` of a finite symmetric matrix: the same LAPACK
    call (potrf) without the wrapper's checks, which cost more than factorising 10 x 10."""
    factor, info = dpotrf(c, lower=True, clean=True)
    if info != 0:  # not positive definite: scipy's own error
        return cholesky(c, lower=True)
    return factor


def _interp_cov(scatter: BlockScatter, v: float) -> np.ndarray:
    """Sigma(v): linear interpolation between the scatter's speed nodes (constant beyond)."""
    s = scatter.speed
    x = _clip(float(v), float(s[0]), float(s[-1]))
    i = min(int(np.searchsorted(s, x, side="right")) - 1, s.size - 2)
    a = (x - s[i]) / (s[i + 1] - s[i])
    return (1 - a) * scatter.cov[i] + a * scatter.cov[i + 1]
