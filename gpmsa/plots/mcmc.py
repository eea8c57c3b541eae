"""MCMC traces, autocorrelations and the pair plot of the calibration parameters."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING

import numpy as np

from gpmsa.calibration.posterior import Posterior, recorded_units
from gpmsa.errors import GPMSAError
from gpmsa.mcmc import diagnostics
from gpmsa.mcmc.sampler import Chains
from gpmsa.model.data import as_float, check_count
from gpmsa.plots._figure import axis_label, check_bins, figure, series_colours
from gpmsa.predictive.joint import calibration_posterior

if TYPE_CHECKING:
    from matplotlib.figure import Figure

NUISANCE = ("lamOs", "lamVz")
"""Posterior names that are not calibration parameters (with ``betaV`` and ``betaV[k]``)."""


def _scalar_series(name: str, arr: np.ndarray) -> dict[str, np.ndarray]:
    """name -> (n_chains, n_draws) per element of arr (n_chains, n_draws, *shape)."""
    flat = arr.reshape(arr.shape[0], arr.shape[1], -1)
    if flat.shape[2] == 1:
        return {name: flat[:, :, 0]}
    shape = arr.shape[2:]
    return {f"{name}[{','.join(map(str, np.unravel_index(i, shape)))}]": flat[:, :, i]
            for i in range(flat.shape[2])}  # fmt: skip


def _series(source) -> dict[str, np.ndarray]:
    """Every scalar parameter of an Emulator, Posterior or Chains: name -> (chains, draws)."""
    out: dict[str, np.ndarray] = {}
    if isinstance(source, Chains):
        for k, v in source.draws.items():
            out.update(_scalar_series(k, np.asarray(v)))
        return out
    if isinstance(source, Posterior):
        if source.chains is not None:
            return {k: np.atleast_2d(np.asarray(v)) for k, v in source.chains.items()}
        return {k: np.asarray(v)[None, :] for k, v in source.samples.items()}
    if hasattr(source, "draws") and hasattr(source, "settings"):
        n = source.n_draws
        if n == 0:
            raise GPMSAError("this emulator kept no posterior draws to trace")
        n_ch = int(source.settings.get("n_chains", 1) or 1)
        per = n // n_ch if n % n_ch == 0 else n
        n_ch = n // per
        if source.calibration:
            post = calibration_posterior(source)
            for k, v in post.samples.items():
                out[k] = np.asarray(v).reshape(n_ch, per)
        for k, v in source.draws.items():
            out.update(_scalar_series(k, np.asarray(v).reshape(n_ch, per, *v.shape[1:])))
        return out
    raise GPMSAError(
        f"source must be a gpmsa.Emulator, Posterior or Chains, got {type(source).__name__}"
    )


def _units(source) -> dict[str, str]:
    """name -> unit of the calibration parameters where ``source`` records them (a Posterior's
    ``info["units"]``, as calibrate and Calibrator write it, read by ``recorded_units``; a joint
    fit's t_units)."""
    if isinstance(source, Posterior):
        return recorded_units(source.info)
    if getattr(source, "calibration", None) and hasattr(source, "t_units"):
        return {k: v for k, v in zip(source.t_names, source.t_units, strict=True) if v}
    return {}


def _name_list(names, available: list[str]) -> list[str]:
    """``names`` (one parameter name, or a sequence of them) as a non-empty list of strings;
    GPMSAError otherwise, listing the ``available`` names."""
    if isinstance(names, np.ndarray) and names.ndim == 0:  # not iterable, though it says so
        names = names.item()
    if isinstance(names, str):
        return [names]
    if isinstance(names, (bytes, Mapping)) or not isinstance(names, Iterable):
        raise GPMSAError(
            f"names must be a parameter name (str) or a sequence of names, got {names!r} "
            f"({type(names).__name__}); available: {available}"
        )
    names = list(names)
    bad = [n for n in names if not isinstance(n, str)]
    if bad:
        raise GPMSAError(
            f"names must hold parameter names (str), got {bad[0]!r} ({type(bad[0]).__name__}); "
            f"available: {available}"
        )
    if not names:
        raise GPMSAError(f"names is empty; available: {available}")
    return names


def _pick(series: dict, names, max_params: int) -> list[str]:
    max_params = check_count(max_params, "max_params")
    if names is None:
        return list(series)[:max_params]
    names = _name_list(names, list(series))
    picked = []
    for n in names:
        hits = [k for k in series if k == n or k.startswith(f"{n}[")]
        if not hits:
            raise GPMSAError(f"unknown parameter {n!r}; available: {list(series)}")
        picked.extend(hits)
    return picked


def traces(source, names=None, *, max_params: int = 12, bins: int = 40) -> Figure:
    """Trace (per chain) and histogram of each scalar parameter: a Figure.

    Args:
        source: a gpmsa.Emulator (its retained draws; a joint fit's calibration draws first), a
            Posterior (its chains), a Chains, or a study (its pooled posterior's chains).
        names: a parameter name or a sequence of names to show (a name selects all its
            elements, e.g. "betaU"); default: the first ``max_params`` scalars.
        max_params: rows at most when ``names`` is None.
        bins: histogram bins.

    Example:
        >>> import numpy as np, gpmsa
        >>> post = gpmsa.Posterior({"t": np.random.default_rng(0).normal(size=200)})
        >>> fig = gpmsa.plots.traces(post)
        >>> len(fig.axes)
        2
    """
    source = _calibration_source(source)
    series, units = _series(source), _units(source)
    picked = _pick(series, names, max_params)
    bins = check_bins(bins, len(picked), "plots.traces")
    fig = figure(9.0, 1.6 * len(picked) + 0.6)
    axes = np.atleast_2d(fig.subplots(len(picked), 2, width_ratios=[3, 1], squeeze=False))
    for row, name in zip(axes, picked, strict=True):
        chains = series[name]
        colours = series_colours(len(chains))
        for c, ch in enumerate(chains):
            row[0].plot(ch, lw=0.6, color=colours[c],
                        label=f"chain {c}" if len(chains) > 1 else None)  # fmt: skip
        row[0].set_ylabel(axis_label(name, units.get(name, "")))
        row[1].sharey(row[0])
        draws = chains.reshape(-1)
        row[1].hist(draws, bins=diagnostics.histogram_bins(draws, bins), orientation="horizontal",
                    color="0.6")  # fmt: skip
        row[1].tick_params(labelleft=False)
    axes[-1, 0].set_xlabel("retained draw")
    axes[-1, 1].set_xlabel("count")
    if len(series[picked[0]]) > 1:
        axes[0, 0].legend(fontsize="small", loc="upper right")
    return fig


def autocorrelation(source, names=None, *, max_params: int = 12, max_lag: int = 40) -> Figure:
    """Autocorrelation of each scalar parameter's draws against the lag, a line per chain, the
    bulk ESS in each panel's title (SEPIA's ``plot_acf``): a Figure.

    The dashed band, +-1.96 / sqrt(draws per chain), is where independent draws' estimates fall
    95% of the time. A fitted emulator's draws are its retained ones, so that a lag counts
    ``settings["thin"]`` sweeps; a calibration's chains count every sweep after burn-in.

    Args:
        source: as ``traces``: a gpmsa.Emulator, a Posterior, a Chains, or a study.
        names: a parameter name or a sequence of names (a name selects all its elements);
            default: the first ``max_params`` scalars.
        max_params: panels at most when ``names`` is None.
        max_lag: the largest lag shown (in draws; at most draws per chain - 1).

    Example:
        >>> import numpy as np, gpmsa
        >>> ar = np.zeros(500); e = np.random.default_rng(0).normal(size=500)
        >>> for i in range(1, 500): ar[i] = 0.9 * ar[i - 1] + e[i]
        >>> fig = gpmsa.plots.autocorrelation(gpmsa.Posterior({"t": ar}), max_lag=20)
        >>> fig.axes[0].get_title().startswith("t: ESS")
        True
    """
    series = _series(_calibration_source(source))
    picked = _pick(series, names, max_params)
    max_lag = check_count(max_lag, "max_lag")
    n_draws = series[picked[0]].shape[1]
    if n_draws < 2:
        raise GPMSAError(f"autocorrelation needs >= 2 draws per chain, got {n_draws}")
    lags = np.arange(min(max_lag, n_draws - 1) + 1)
    n_cols = min(3, len(picked))
    n_rows = -(-len(picked) // n_cols)
    fig = figure(3.2 * n_cols + 0.4, 2.3 * n_rows + 0.4)
    axes = fig.subplots(n_rows, n_cols, squeeze=False, sharex=True, sharey=True).ravel()
    band = 1.96 / np.sqrt(n_draws)
    for ax, name in zip(axes, picked, strict=False):
        chains = series[name]
        colours = series_colours(len(chains))
        for c, acf in enumerate(diagnostics.autocorrelation(chains)):
            ax.plot(lags, acf[: lags.size], lw=1.0, color=colours[c],
                    label=f"chain {c}" if len(chains) > 1 else None)  # fmt: skip
        ax.axhline(0.0, color="0.3", lw=0.6)
        ax.axhspan(-band, band, color="0.85", zorder=0)
        ess = diagnostics.ess(chains)
        ess_text = "constant" if np.isnan(ess) else f"{ess:.0f} of {chains.size}"
        ax.set_title(f"{name}: ESS {ess_text}", fontsize="medium")
    for ax in axes[len(picked) :]:
        ax.set_axis_off()
    for ax in axes[-n_cols:]:
        ax.set_xlabel("lag (draws)")
    for ax in axes[::n_cols]:
        ax.set_ylabel("autocorrelation")
    if len(series[picked[0]]) > 1:
        axes[0].legend(fontsize="small", loc="upper right")
    return fig


def _check_truth(truth, names) -> dict[str, float]:
    """``truth`` (None or name -> finite value) of parameters among ``names`` (the
    posterior's); GPMSAError naming an unknown parameter or a value that is not a finite
    number."""
    if truth is None:
        return {}
    if not isinstance(truth, dict):
        raise GPMSAError(f"truth must be a dict name -> value, got {type(truth).__name__}")
    unknown = sorted(set(truth) - set(names), key=str)
    if unknown:
        raise GPMSAError(f"truth: unknown parameter(s) {unknown}; the posterior has {list(names)}")
    out = {}
    for name, value in truth.items():
        arr = as_float(value, f"truth[{name!r}]")
        if arr.ndim != 0 or not np.isfinite(arr):
            raise GPMSAError(f"truth[{name!r}] must be one finite number, got {value!r}")
        out[name] = float(arr)
    return out


def _is_calibration_parameter(name: str, names) -> bool:
    """Whether a posterior name (of ``names``, the posterior's) is a calibration parameter (or
    a study's group mean or sd of one), not a noise or discrepancy parameter (lamOs, lamVz,
    betaV, plain or with an index or a study's label in brackets) nor a hierarchical
    parameter's unit-scale precision NAME.lam (beside its NAME.mu); a calibration parameter
    named, say, "betaVel" or "a.lam" is shown."""
    if name.split("[", 1)[0] in (*NUISANCE, "betaV"):
        return False
    return not (name.endswith(".lam") and f"{name[:-4]}.mu" in names)


def _calibration_source(source):
    """A Study's pooled posterior for a study (a duck type: plots import no study code), else
    ``source``."""
    if hasattr(source, "member_posterior") and isinstance(
        getattr(source, "posterior", None), Posterior
    ):
        return source.posterior
    return source


def theta_pairs(source, names=None, *, truth: dict | None = None, bins: int = 30) -> Figure:
    """Pair plot of the calibration parameters: histograms on the diagonal, draws below it.

    Args:
        source: a Posterior, a study (its pooled posterior), or an Emulator from a joint fit
            (its calibration draws).
        names: a parameter name or a sequence of names (default: every calibration
            parameter, i.e. not lamOs, lamVz, betaV, nor a study's per-model lamOs[LABEL] or a
            hierarchical parameter's unit-scale precision NAME.lam; its group mean NAME.mu and
            sd NAME.sd are shown).
        truth: name -> value to mark (e.g. the value a synthetic case was made with).
        bins: histogram bins.

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> post = gpmsa.Posterior({"a": rng.normal(size=300), "b": rng.normal(size=300)})
        >>> fig = gpmsa.plots.theta_pairs(post, truth={"a": 0.0})
        >>> len(fig.axes)
        4
    """
    source = _calibration_source(source)
    post = source if isinstance(source, Posterior) else None
    if post is None:
        if not getattr(source, "calibration", None):
            raise GPMSAError(
                "theta_pairs needs a Posterior, a study, or an Emulator from a joint fit"
            )
        post = calibration_posterior(source)
    if names is None:
        names = [n for n in post.names if _is_calibration_parameter(n, post.names)]
        if not names:
            raise GPMSAError(f"the posterior has no calibration parameter to plot: {post.names}")
    names = _name_list(names, list(post.names))
    unknown = [n for n in names if n not in post.names]
    if unknown:
        raise GPMSAError(f"unknown parameters {unknown}; the posterior has {post.names}")
    truth = _check_truth(truth, post.names)
    units = _units(source)
    k = len(names)
    bins = check_bins(bins, k, "plots.theta_pairs")
    fig = figure(2.4 * k + 0.6, 2.4 * k + 0.4)
    axes = fig.subplots(k, k, squeeze=False)
    draws = {n: np.asarray(post.samples[n], dtype=float) for n in names}
    for i, ni in enumerate(names):
        for j, nj in enumerate(names):
            ax = axes[i, j]
            if j > i:
                ax.set_axis_off()
                continue
            if i == j:
                ax.hist(draws[ni], bins=diagnostics.histogram_bins(draws[ni], bins), color="0.6",
                        density=True)  # fmt: skip
                if ni in truth:
                    ax.axvline(truth[ni], color="C3", lw=1.2)
                ax.set_yticks([])
            else:
                # rasterised: 1e5 draws as vector markers made SVGs of hundreds of MB
                ax.plot(draws[nj], draws[ni], ".", ms=2, alpha=0.3, color="C0", rasterized=True)
                if ni in truth and nj in truth:
                    ax.plot(truth[nj], truth[ni], "x", color="C3", ms=8, mew=2)
            if i == k - 1:
                ax.set_xlabel(axis_label(nj, units.get(nj, "")))
            if j == 0 and i > 0:
                ax.set_ylabel(axis_label(ni, units.get(ni, "")))
    return fig
