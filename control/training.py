"""Training data for the block feature: expected features and the block scatter from a campaign.

Each campaign run drives one fresh road at one (v, GD) for ``keep_s`` seconds
(`vehicle.run_campaign(..., keep_s=...)`). Its blocks give

- the run's mean feature: an estimate of the expected feature at (v, GD) with a Monte-Carlo error
  of about sd / sqrt(blocks); the emulator is fitted to these means, so its nugget describes that
  small error instead of one block's scatter;
- the run's block-to-block covariance about its mean, as a long-run covariance (batch means of
  ``batch`` consecutive blocks, times ``batch``), so that correlation between neighbouring
  blocks is counted when the filter pools them. Pooled over runs and smoothed in speed, it is
  the known observation covariance Sigma(v) of one block (`BlockScatter`), with the Student-t
  degrees of freedom that fit the blocks' squared Mahalanobis distances.

`fit_band_emulator` and `fit_window_emulator` make from such runs (a simulated campaign's, or a
robot's own drives at known GD) the emulator files the BCR, the replay and the closed loop read,
with the metadata they check (docs/robot.md, "From your robot's own drives").
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from control.bcr import GD_MIN_HI
from control.errors import ControlError
from control.feature import FeatureSpec, block_features
from control.observation_model import BlockScatter
from control.sensor_checks import MAX_ACCEL_MPS2
from control.validation import check_instance, float_array, is_integer, is_real
from gpmsa import Emulator
from gpmsa.errors import numbers_text

__gpmsa_wrapper__ = True
"""gpmsa's warnings in these fits (a ConvergenceWarning, an OutlierRunWarning) point at the
line that calls `fit_band_emulator` / `fit_window_emulator` (``gpmsa.errors.WRAPPER_MARK``)."""


@dataclass(frozen=True, eq=False)
class BlockStatistics:
    """Per-run block statistics of a campaign.

    Attributes:
        mean: (m, K) mean feature of each run.
        cov: (m, K, K) long-run block covariance of each run.
        features: (m, n_blocks, K) every block's feature.
    """

    mean: np.ndarray
    cov: np.ndarray
    features: np.ndarray


def _check_batch(batch) -> int:
    """``batch`` as an int >= 2 (a batch mean of one block is no batch); ControlError else."""
    if not is_integer(batch) or batch < 2:
        raise ControlError(f"batch must be an integer >= 2 (blocks per batch), got {batch!r}")
    return int(batch)


def block_statistics(accel: np.ndarray, spec: FeatureSpec, batch: int = 8) -> BlockStatistics:
    """Block features of each run's accelerations and their mean and long-run covariance.

    Args:
        accel: (m, n) accelerations of m runs, m/s^2 (e.g. ``Campaign.accel_measured``).
        spec: the block feature.
        batch: blocks per batch of the long-run covariance.
    """
    check_instance(spec, "spec", FeatureSpec)
    batch = _check_batch(batch)
    accel = float_array(accel, "accel")
    B = spec.block_samples
    if accel.ndim != 2 or accel.shape[1] < 2 * batch * B:
        raise ControlError(
            f"accel must be (runs, samples) with >= {2 * batch * B} samples per run (two batches "
            f"of {batch} blocks of {B}), got shape {accel.shape}"
        )
    if accel.shape[0] == 0:
        raise ControlError(f"accel holds no runs: shape {accel.shape}")
    if not np.all(np.isfinite(accel)):
        raise ControlError("accel holds non-finite values (failed runs?): leave those runs out")
    peak = float(np.max(np.abs(accel)))
    if peak > MAX_ACCEL_MPS2:  # its squares would overflow the band powers
        raise ControlError(
            f"accel reaches {numbers_text(peak, MAX_ACCEL_MPS2, digits=3)[0]} m/s^2, beyond any "
            "accelerometer's range "
            f"(MAX_ACCEL_MPS2 = {MAX_ACCEL_MPS2:g}; the BCR refuses such blocks as faults)"
        )
    n_blocks = accel.shape[1] // B
    blocks = accel[:, : n_blocks * B].reshape(-1, B)
    feats = block_features(blocks, spec).reshape(accel.shape[0], n_blocks, spec.dim)
    bad = ~np.all(np.isfinite(feats), axis=2)
    if bad.any():
        run, block = np.argwhere(bad)[0]
        raise ControlError(
            f"block {block} of run {run} gives a non-finite {spec.name} feature: it has no "
            "power in a band or is constant (a stuck or failed run?)"
        )
    return feature_statistics(feats, batch)


def feature_statistics(features: np.ndarray, batch: int = 8) -> BlockStatistics:
    """Each run's mean feature and long-run block covariance (batch means of ``batch``
    consecutive blocks, times ``batch``), from the features of its blocks.

    Args:
        features: (m, n_blocks, K) feature of every block of m runs (e.g. several channels'
            `block_statistics` features side by side), n_blocks >= 2 batch.
        batch: blocks per batch.
    """
    batch = _check_batch(batch)
    feats = float_array(features, "features")
    if feats.ndim != 3 or feats.shape[0] == 0 or feats.shape[1] < 2 * batch or not feats.shape[2]:
        raise ControlError(
            f"features must be (runs, blocks, K) with >= {2 * batch} blocks per run (two batches "
            f"of {batch}) and K >= 1, got shape {feats.shape}"
        )
    if not np.all(np.isfinite(feats)):
        raise ControlError("features hold non-finite values")
    mean = feats.mean(axis=1)
    dev = feats - mean[:, None, :]
    n_batch = feats.shape[1] // batch
    batches = dev[:, : n_batch * batch].reshape(feats.shape[0], n_batch, batch, -1).mean(axis=2)
    cov = np.einsum("rbi,rbj->rij", batches, batches) / (n_batch - 1) * batch
    return BlockStatistics(mean=mean, cov=cov, features=feats)


def block_scatter(
    speed: np.ndarray,
    stats_: BlockStatistics,
    nodes: np.ndarray | None = None,
    bandwidth: float = 0.15,
) -> BlockScatter:
    """Sigma(v) at speed nodes: the runs' long-run covariances averaged with Gaussian kernel
    weights in speed (``bandwidth``, m/s), and the Student-t dof fitted to the blocks.

    Args:
        speed: (m,) the runs' speeds, m/s.
        stats_: their `block_statistics`.
        nodes: >= 2 increasing speed nodes, m/s (default 16 over the runs' range).
    """
    check_instance(stats_, "stats_", BlockStatistics)
    speed = float_array(speed, "speed")
    if speed.shape != (stats_.mean.shape[0],) or not np.all(np.isfinite(speed)):
        raise ControlError(f"speed must hold one finite value per run ({stats_.mean.shape[0]})")
    if not (is_real(bandwidth) and np.isfinite(bandwidth) and bandwidth > 0):
        raise ControlError(f"bandwidth must be a finite speed > 0, m/s, got {bandwidth!r}")
    nodes = _scatter_nodes(nodes, speed, bandwidth)
    cov = np.einsum("sr,rij->sij", _kernel_weights(nodes, speed, bandwidth), stats_.cov)
    for node, c in zip(nodes, cov, strict=True):
        if not np.all(np.linalg.eigvalsh(c) > 1e-12 * max(float(np.trace(c)), 1e-300)):
            raise ControlError(
                f"the runs' block covariance at {node:g} m/s is singular: the runs near that "
                f"speed hold too few blocks to estimate the {c.shape[0]} x {c.shape[0]} "
                "covariance of the features (more runs or longer drives), or a feature (or a "
                "combination of them) does not vary from block to block"
            )
    return BlockScatter(nodes, cov, _fit_dof(speed, stats_, nodes, cov))


SINGULAR_WEIGHT = 1e-16
"""Share of a speed node's kernel weight (`weight_beyond_rank`) at or below which
`block_scatter` is certain to find the node's covariance singular, while no run's covariance
has a trace 1,000 times another's (measured: at most 14 times, over GD 1-2000 and 0.1-2 m/s)."""


def covariance_rank(n_blocks: int, batch: int = 8) -> int:
    """The most rank one run's `feature_statistics` covariance can have: its ``n_blocks // batch``
    batch means about the mean of all ``n_blocks`` blocks, one less where no block is left over
    (the batch means then sum to zero)."""
    n_batch = n_blocks // _check_batch(batch)
    return n_batch - 1 if n_blocks == n_batch * batch else n_batch


def weight_beyond_rank(
    speed: np.ndarray, run_rank: int, dim: int, nodes: np.ndarray, bandwidth: float = 0.15
) -> np.ndarray:
    """Per speed node, the share of `block_scatter`'s kernel weight that lies beyond the runs
    that cannot give its ``dim`` x ``dim`` covariance full rank: before any run is driven.

    Each run's covariance has rank at most ``run_rank`` (`covariance_rank`), so the
    ``ceil(dim / run_rank) - 1`` runs nearest a node leave a direction u that only the other
    runs see: the node's smallest eigenvalue is at most u' Sigma u <= share * rho * trace, rho
    the largest ratio of two runs' covariance traces. `block_scatter` refuses a node whose
    smallest eigenvalue is <= 1e-12 of its trace, so a share <= `SINGULAR_WEIGHT` is refused
    whatever the roads, while rho <= 1000. The share is 0 at every node where all the runs
    together cannot reach rank ``dim`` (runs * run_rank < dim).

    Args:
        speed: (m,) the runs' speeds, m/s (the design's).
        run_rank: rank of each run's covariance, >= 1.
        dim: the feature's outputs K.
        nodes: the speed nodes `block_scatter` will be given, m/s.
        bandwidth: its bandwidth, m/s.

    Returns:
        (nodes,) share of each node's weight on all but its ceil(dim / run_rank) - 1 nearest runs.
    """
    speed, nodes = float_array(speed, "speed").ravel(), float_array(nodes, "nodes").ravel()
    if not (is_integer(run_rank) and run_rank >= 1 and is_integer(dim) and dim >= 1):
        raise ControlError(f"run_rank and dim must be integers >= 1, got {run_rank!r}, {dim!r}")
    near = -(-int(dim) // int(run_rank)) - 1  # fewer runs than this reach rank dim
    w = np.sort(_kernel_weights(nodes, speed, bandwidth), axis=1)
    return w[:, : max(speed.size - near, 0)].sum(axis=1)


def _kernel_weights(nodes: np.ndarray, speed: np.ndarray, bandwidth: float) -> np.ndarray:
    """(nodes, runs) Gaussian kernel weights in speed, each node's summing to one."""
    w = np.exp(-0.5 * ((nodes[:, None] - speed[None, :]) / bandwidth) ** 2)
    return w / w.sum(axis=1, keepdims=True)


def _scatter_nodes(nodes, speed: np.ndarray, bandwidth: float) -> np.ndarray:
    """The speed nodes of `block_scatter` (default: 16 over the runs' speeds) as >= 2
    increasing finite speeds, each within 30 bandwidths of a run; ControlError naming them."""
    if nodes is None:
        if speed.min() == speed.max():
            raise ControlError(
                f"every run drove at {speed[0]:g} m/s: the default nodes span the runs' speeds, "
                "so give nodes (>= 2 increasing speeds, m/s, e.g. around that speed)"
            )
        nodes = np.linspace(speed.min(), speed.max(), 16)
    nodes = float_array(nodes, "nodes")
    if nodes.ndim != 1 or nodes.size == 0 or not np.all(np.isfinite(nodes)):
        raise ControlError(f"nodes must be >= 2 increasing finite speeds, m/s, got {nodes!r}")
    far = np.min(np.abs(nodes[:, None] - speed[None, :]), axis=1) > 30.0 * bandwidth
    if far.any():  # the kernel weights would all underflow
        raise ControlError(
            f"speed node {nodes[int(np.argmax(far))]:g} m/s lies more than 30 bandwidths "
            f"({bandwidth:g} m/s) from every run's speed: no run informs its covariance"
        )
    if nodes.size < 2 or np.any(np.diff(nodes) <= 0):
        raise ControlError(f"nodes must be >= 2 increasing finite speeds, m/s, got {nodes!r}")
    return nodes


def _fit_dof(speed, stats_: BlockStatistics, nodes, cov) -> float:
    """Student-t dof by maximum likelihood of the blocks' squared Mahalanobis distances about
    their run means (d2 / K ~ F(K, nu)); inf when the Gaussian fits as well."""
    K = stats_.mean.shape[1]
    d2 = []
    for r in range(speed.size):
        c = cov[int(np.argmin(np.abs(nodes - speed[r])))]
        dev = stats_.features[r] - stats_.mean[r]
        d2.append(np.einsum("bi,ij,bj->b", dev, np.linalg.inv(c), dev))
    x = np.concatenate(d2) / K

    def nll(log_nu: float) -> float:
        return -float(np.sum(stats.f.logpdf(x, K, np.exp(log_nu))))

    res = optimize.minimize_scalar(nll, bounds=(np.log(2.5), np.log(1000.0)), method="bounded")
    gauss = -float(np.sum(stats.chi2.logpdf(x * K, K) + np.log(K)))
    return float(np.exp(res.x)) if res.fun < gauss - 1.0 else np.inf


WINDOW_PRIORS_LAMWS = (1.0, 1e-3, 1.0, 1e5)
"""The window emulators' lamWs prior (GPM/SA's Gamma(a, b) with bounds): relaxed from GPM/SA's
lower bound of 60 to 1, so that the GP nugget describes the window-to-window scatter."""


_MIN_RUNS = 4
"""Fewest runs of an emulator of speed and GD (gpmsa.SimData's p + q + 2)."""


def _check_run_lengths(accel) -> None:
    """ControlError naming the remedy where ``accel`` is a list of runs of different lengths
    (as drives come; numpy would only say "inhomogeneous shape")."""
    if isinstance(accel, list | tuple) and accel and all(np.ndim(a) == 1 for a in accel):
        lengths = [len(a) for a in accel]
        if min(lengths) != max(lengths):
            raise ControlError(
                f"accel holds runs of different lengths ({min(lengths)} to {max(lengths)} "
                "samples): cut each to one length, e.g. n = min(map(len, accel)); "
                "accel = np.stack([a[-n:] for a in accel])"
            )


def _check_metadata(meta: dict, metadata) -> None:
    """ControlError unless ``metadata`` is None or a dict whose records the fit also writes
    (``meta``: noise_std, vehicle, feature, block_scatter) agree with the fit's."""
    if metadata is None:
        return
    if not isinstance(metadata, Mapping):
        raise ControlError(
            f"metadata must be a dict of further records (name -> JSON-able value), got "
            f"{type(metadata).__name__} {metadata!r:.60}"
        )
    for key, value in meta.items():
        if key in metadata and not _same_record(metadata[key], value):
            raise ControlError(
                f"metadata[{key!r}] = {metadata[key]!r:.60} differs from the {key} this fit "
                f"records, {value!r:.60} (from its arguments and runs): leave {key!r} out of "
                "metadata, or give the fit the value you mean"
            )


def _same_record(a, b) -> bool:
    """Whether two metadata records are equal (False where they cannot be compared)."""
    try:
        return bool(a == b)
    except (TypeError, ValueError):  # e.g. arrays of different shapes
        return False


def _training_runs(speed, gd, accel, noise_std, vehicle, metadata) -> tuple:
    """(speed, gd, accel) checked as m runs, and the metadata records every emulator gets:
    ``noise_std`` (m/s^2) and, where given, ``vehicle`` (a model's ``describe()``);
    ``metadata``, the further records, checked against them."""
    _check_run_lengths(accel)
    speed, gd, accel = (
        float_array(a, n) for a, n in ((speed, "speed"), (gd, "gd"), (accel, "accel"))
    )
    if accel.ndim != 2:
        raise ControlError(
            f"accel must be (runs, samples): one row per run, each cut to the same number of "
            f"samples (e.g. the shortest run's), got shape {accel.shape}"
        )
    m = accel.shape[0]
    for name, values in (("speed", speed), ("gd", gd)):
        if values.shape != (m,) or not np.all(np.isfinite(values) & (values > 0)):
            raise ControlError(
                f"{name} must hold one finite value > 0 per run of accel ({m}; speed in m/s, GD "
                f"in 1e-6 m^3), got {values.ravel()[:6]!r} (shape {values.shape})"
            )
    if m < _MIN_RUNS:
        raise ControlError(
            f"accel holds {m} run{'s' if m != 1 else ''}: an emulator of speed and GD needs "
            f">= {_MIN_RUNS} runs (gpmsa.SimData's p + q + 2), at >= 2 speeds and >= 2 GDs"
        )
    for name, values, unit, what in (("speed", speed, " m/s", "speeds"), ("gd", gd, "", "GDs")):
        if values.min() == values.max():
            raise ControlError(
                f"every run has {name} {values[0]:g}{unit}: the emulator learns how the "
                f"feature changes with speed and GD, so its runs need >= 2 {what} (its domain "
                "is their range)"
            )
    if gd.max() < GD_MIN_HI:  # every ISO 8608 road in m^3 lies below 1: a unit slip
        lo, hi = numbers_text(gd.min() * 1e6, gd.max() * 1e6)
        raise ControlError(
            f"gd is Gd(n0) in units of 1e-6 m^3 (ISO 8608's smoothest class, A, spans 0-32), "
            f"but every run's lies below {GD_MIN_HI:g} (largest {gd.max():g}): given in m^3? "
            f"Then gd * 1e6, in [{lo}, {hi}]"
        )
    if not (is_real(noise_std) and 0 <= noise_std < np.inf):
        raise ControlError(
            f"noise_std must be the accelerometer's noise sd, a finite number >= 0, m/s^2 (the "
            f"sd of its vertical axis standing still; 0: noise-free data), got {noise_std!r}"
        )
    meta: dict = {"noise_std": float(noise_std)}
    if vehicle is not None:
        if not callable(getattr(vehicle, "describe", None)):
            raise ControlError(
                f"vehicle must be None (a real robot: no model) or a vehicle model with "
                f"describe() (vehicle.Jackal, vehicle.HalfCar), got {vehicle!r:.60}"
            )
        meta["vehicle"] = vehicle.describe()
    _check_metadata(meta, metadata)
    return speed, gd, accel, meta


def fit_band_emulator(
    speed,
    gd,
    accel,
    *,
    noise_std: float,
    feature: FeatureSpec | None = None,
    vehicle=None,
    n_pc: int = 8,
    batch: int = 8,
    nodes=None,
    metadata: dict | None = None,
    **fit_options,
) -> Emulator:
    """The change-point BCR's emulator (the block feature) from m runs at known speed and GD.

    As examples/train_emulator.py fits its band emulators: each run's mean block feature
    (`block_statistics`) is the GP's output, through ``n_pc`` principal components; the block
    scatter Sigma(v) (`block_scatter`) goes into the metadata with ``feature``, ``noise_std``
    and, where given, ``vehicle``, the records the BCR and the loop's checks read.

    Args:
        speed: (m,) each run's speed, m/s (the robot drives it steadily).
        gd: (m,) each run's ground roughness GD, 1e-6 m^3 (Gd(n0) x 1e6; `roadgen.estimate_gd`).
        accel: (m, n) each run's vertical accelerations at the feature's rate (120 Hz by
            default), gravity removed, m/s^2; at least 2 ``batch`` blocks a run.
        noise_std: the accelerometer's noise sd, m/s^2 (the BCR's noise-floor check reads it).
        feature: the block feature (default `FeatureSpec()`, the shipped emulators').
        vehicle: the vehicle model the runs were simulated with, or None for a real robot's
            drives (the loop then has no vehicle to check against).
        n_pc: principal components (at most the feature's outputs).
        batch, nodes: of `block_statistics` and `block_scatter`.
        metadata: further records (the road, the design, ...); one of the records the fit
            writes (``noise_std``, ``vehicle``, ``feature``, ``block_scatter``) only with the
            fit's value.
        fit_options: passed to `gpmsa.fit` (``n_iter``, ``seed``, ``n_chains``, ``progress``
            for its tqdm bar, ...).

    Raises ControlError, before the fit, naming the argument: runs of different lengths (cut
    them to one), fewer than 4 runs, runs all at one speed or one GD, GDs all below `GD_MIN_HI`
    (given in m^3), a ``noise_std`` that is not a finite number >= 0, a ``metadata`` record
    that contradicts the fit's; and where `block_statistics` or `block_scatter` refuse the runs.
    The fit's warnings (a ``gpmsa.ConvergenceWarning``, say) point at the line that calls this.
    """
    import gpmsa

    feature = FeatureSpec() if feature is None else feature
    check_instance(feature, "feature", FeatureSpec)
    speed, gd, accel, meta = _training_runs(speed, gd, accel, noise_std, vehicle, metadata)
    stats_ = block_statistics(accel, feature, batch=batch)
    scatter = block_scatter(speed, stats_, nodes=nodes)
    data = gpmsa.SimData(
        x=speed[:, None], t=gd[:, None], y=stats_.mean,
        x_names=["v"], t_names=["GD"], y_names=feature.names(),
        x_units=["m/s"], t_units=["1e-6 m^3"], y_units=feature.units(),
    )  # fmt: skip
    meta.update(feature=feature.to_dict(), block_scatter=scatter.to_dict())
    _check_metadata(meta, metadata)
    return gpmsa.fit(data, n_pc=n_pc, metadata={**meta, **(metadata or {})}, **fit_options)


def fit_window_emulator(
    speed, gd, accel, *, noise_std: float, vehicle=None, metadata: dict | None = None,
    **fit_options,
) -> Emulator:  # fmt: skip
    """The paper's window emulator (y = log f, f the variance of a run's last 1,000 samples,
    `control.PAPER_WINDOW`) from m runs at known speed and GD, as examples/train_emulator.py
    fits it (the lamWs prior `WINDOW_PRIORS_LAMWS` unless ``fit_options`` gives ``priors``).

    Args and refusals as `fit_band_emulator`'s; each run of ``accel`` holds at least 1,000
    samples, its last 1,000 finite.
    """
    import gpmsa
    from control.bcr import PAPER_WINDOW
    from control.feature import feature_of_variance

    speed, gd, accel, meta = _training_runs(speed, gd, accel, noise_std, vehicle, metadata)
    n = PAPER_WINDOW.block_samples
    if accel.shape[1] < n or not np.all(np.isfinite(accel[:, -n:])):
        raise ControlError(
            f"accel must hold >= {n} finite samples per run (the paper's window), got shape "
            f"{accel.shape}"
        )
    f = np.var(accel[:, -n:], axis=1)
    data = gpmsa.SimData(
        x=speed[:, None], t=gd[:, None], y=feature_of_variance(f, "log_var")[:, None],
        x_names=["v"], t_names=["GD"], y_names=["log_f"],
        x_units=["m/s"], t_units=["1e-6 m^3"], y_units=["log((m/s^2)^2)"],
    )  # fmt: skip
    fit_options.setdefault("priors", gpmsa.Priors(lamWs=gpmsa.GammaPrior(*WINDOW_PRIORS_LAMWS)))
    meta["feature"] = PAPER_WINDOW.to_dict()
    _check_metadata(meta, metadata)
    return gpmsa.fit(data, metadata={**meta, **(metadata or {})}, **fit_options)
