"""MCMC diagnostics: effective sample size, R-hat and acceptance (ArviZ, imported lazily)."""

from __future__ import annotations

import functools
import warnings

import numpy as np

from gpmsa.errors import GPMSAError


def _arviz():
    """Import arviz quietly (0.x emits a FutureWarning at import, 1.x warnings of its xarray
    accessors)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import arviz

    return arviz


@functools.cache
def arviz_major() -> int:
    """The installed ArviZ's major release. This module is the one place gpmsa calls ArviZ, and
    hides what 1.x (Python >= 3.12) changed: ``from_dict`` takes the groups as one dict and
    returns an xarray DataTree (0.x: keywords, an InferenceData; both have the groups
    ``posterior`` and ``sample_stats`` and ``to_netcdf``), ``hdi`` takes ``prob=`` (0.x:
    ``hdi_prob=``), and the array ``autocorr`` is ``arviz_stats.base.array_stats.autocorr`` (0.x:
    ``arviz.autocorr``); ``ess`` and ``rhat`` of an array are called alike and agree to the
    last digit. Read once (a process imports one ArviZ)."""
    return int(str(_arviz().__version__).split(".", 1)[0])


CF_TIME_UNITS = frozenset(
    ("days", "hours", "minutes", "seconds", "milliseconds", "microseconds", "nanoseconds")
)
"""Units that xarray's CF decoding reads as durations (timedelta64; by default in older xarray
releases, 2025.09 among them), as it reads any "units" holding "since" as dates (and refuses to
open a file whose reference date it cannot parse)."""


def is_cf_time_unit(unit: str) -> bool:
    """Whether xarray would decode a variable of this "units" attribute as times, not numbers
    (`CF_TIME_UNITS`, or one holding "since": "days since 2000-01-01", "s since start")."""
    return unit in CF_TIME_UNITS or "since" in unit


def to_inference_data(
    draws: dict[str, np.ndarray],
    log_post: np.ndarray | None = None,
    units: dict[str, str] | None = None,
):
    """ArviZ InferenceData (with ArviZ 1.x an xarray DataTree of the same groups, `arviz_major`)
    from draws name -> (n_chains, n_draws, *shape); ``units`` name -> unit, each kept as its
    variable's "units" attribute (a netCDF convention; none where
    missing or "", nor where xarray would read the draws back as times, `is_cf_time_unit`:
    dates or durations from ``to_netcdf``, or a file that does not open). GPMSAError for a
    name that is one of ArviZ's dimension names ("chain", "draw", "NAME_dim_K" of a draw with
    more axes): ArviZ would give that dimension's coordinate in its place, and its draws would
    be lost without a word; with ArviZ 1.x also for a name holding "/", which a DataTree
    refuses (0.x's InferenceData takes it; its ``to_netcdf`` refuses it)."""
    dims = {"chain", "draw"}
    for name, value in draws.items():
        dims.update(f"{name}_dim_{k}" for k in range(np.ndim(value) - 2))
    taken = [name for name in draws if name in dims]
    if taken:
        raise GPMSAError(
            f"to_arviz: parameter {taken[0]!r} is named as one of ArviZ's dimensions (chain, "
            "draw, NAME_dim_K), whose coordinate would replace its draws; rename the parameter "
            "(SimData's t_names, or a study's shared or hierarchical names), or build the "
            "InferenceData yourself under another name (arviz.from_dict)"
        )
    slashed = [name for name in draws if "/" in name]
    if slashed and arviz_major() >= 1:
        raise GPMSAError(
            f"to_arviz: parameter {slashed[0]!r} holds '/', which the xarray DataTree "
            "that ArviZ 1.x builds refuses in a variable's name (a path separator); rename the "
            "parameter (SimData's t_names, or a study's shared or hierarchical names), or build "
            "the DataTree yourself under another name (arviz.from_dict({'posterior': "
            "{name.replace('/', '_'): draws}}))"
        )
    az = _arviz()
    groups = {"posterior": dict(draws)}
    if log_post is not None:
        groups["sample_stats"] = {"lp": log_post}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idata = az.from_dict(groups) if arviz_major() >= 1 else az.from_dict(**groups)
    if tuple(idata.posterior.data_vars) != tuple(draws):  # 0.x with dm-tree sorts the names
        idata.posterior = idata.posterior[list(draws)]
    for name, unit in (units or {}).items():
        if unit and name in idata.posterior and not is_cf_time_unit(str(unit)):
            idata.posterior[name].attrs["units"] = str(unit)
    return idata


def bins_apart(lo: float, hi: float, bins: int, dtype=np.float64) -> bool:
    """Whether [lo, hi] holds ``bins`` equal bins whose edges, spaced in ``dtype`` as numpy
    spaces a histogram's (its draws' own float type), are all distinct (numpy refuses a range
    that does not: "Too many bins for data range")."""
    edges = np.linspace(lo, hi, bins + 1, dtype=dtype)
    return bool(np.all(edges[:-1] < edges[1:]))


def histogram_bins(draws: np.ndarray, bins: int) -> int | np.ndarray:
    """``bins`` (an int) for a histogram of the finite ``draws``, or, where their spread is too
    narrow for that many bins with distinct float64 edges (draws a few ulps apart, as rounding
    leaves a stuck chain's; numpy refuses them: "Too many bins for data range"), the distinct
    edges of those equal bins between the draws' extremes: fewer bins, still holding every draw.
    Equal draws keep ``bins`` (numpy widens them to +-0.5). numpy spaces the edges in the draws'
    own float type: float32 draws a few of their ulps apart are refused by it however far apart
    float64 tells them, and get float64 edges (`bins_apart`)."""
    raw = np.asarray(draws)
    arr = raw.astype(float).ravel()
    if arr.size == 0:
        return bins
    lo, hi = float(np.min(arr)), float(np.max(arr))
    if not lo < hi:  # one value (or NaN): numpy's own handling
        return bins
    apart = bins_apart(lo, hi, bins)
    if apart and np.issubdtype(raw.dtype, np.floating) and raw.dtype != np.float64:
        apart = bins_apart(raw.min(), raw.max(), bins, raw.dtype)  # (float32: its own spacing)
    return bins if apart else np.unique(np.linspace(lo, hi, bins + 1))


MIN_DRAWS_ESS = 4
"""Fewest draws per chain for which ArviZ computes an ESS (it logs a shape error below)."""
MIN_DRAWS_RHAT = 8
"""Fewest draws per chain for a split R-hat (each half needs 4)."""


def ess(x: np.ndarray) -> float:
    """Bulk effective sample size of x (n_chains, n_draws) (rank-normalised, as ArviZ); NaN for
    constant draws or fewer than MIN_DRAWS_ESS per chain."""
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    if np.ptp(x) == 0 or x.shape[1] < MIN_DRAWS_ESS:
        return float("nan")
    # ArviZ's own numerics (a 0 / 0 of chains stuck apart gives R-hat inf): quiet whatever the
    # caller's np.seterr, as its warnings are
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        return float(_arviz().ess(np.atleast_2d(x)))


def autocorrelation(x: np.ndarray) -> np.ndarray:
    """Autocorrelation of each chain of x (n_chains, n_draws) at lags 0 .. n_draws - 1 (ArviZ's
    FFT estimate); NaN rows for constant chains."""
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    out = np.full(x.shape, np.nan)
    varied = np.ptp(x, axis=1) > 0
    if np.any(varied):
        if arviz_major() >= 1:
            from arviz_stats.base import array_stats

            out[varied] = array_stats.autocorr(x[varied], axis=-1)
        else:
            out[varied] = _arviz().autocorr(x[varied], axis=-1)
    return out


def hdi(x: np.ndarray, level: float) -> tuple[float, float]:
    """Highest-density interval (ArviZ's: the shortest one) of 1-D draws x with probability
    ``level``."""
    prob = {"prob": level} if arviz_major() >= 1 else {"hdi_prob": level}
    lo, hi = _arviz().hdi(np.asarray(x, dtype=np.float64), **prob)
    return float(lo), float(hi)


def rhat(x: np.ndarray) -> float:
    """Rank-normalised split R-hat of x (n_chains, n_draws); one chain is split in two."""
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    if np.ptp(x) == 0 or x.shape[1] < MIN_DRAWS_RHAT:
        return float("nan")
    if x.shape[0] == 1:
        half = x.shape[1] // 2
        x = np.vstack([x[0, :half], x[0, half : 2 * half]])
    # ArviZ's own numerics (a 0 / 0 of chains stuck apart gives R-hat inf): quiet whatever the
    # caller's np.seterr, as its warnings are
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        return float(_arviz().rhat(np.atleast_2d(x)))


def summarize(
    draws: dict[str, np.ndarray], accept_rate: dict[str, np.ndarray] | None = None
) -> dict[str, dict[str, list[float]]]:
    """Per parameter and element (flattened, C order): mean, sd, ESS, R-hat, acceptance.

    ``draws``: name -> (n_chains, n_draws, *shape) after burn-in; ``accept_rate``: name ->
    (n_chains, *shape). JSON-able (lists of floats; NaN for constant chains, and an sd of NaN
    from a single draw).
    """
    out = {}
    for name, d in draws.items():
        flat = d.reshape(d.shape[0], d.shape[1], -1)
        n_total = flat.shape[0] * flat.shape[1]
        sd = flat.std(axis=(0, 1), ddof=1) if n_total > 1 else np.full(flat.shape[2], np.nan)
        entry = {
            "mean": [float(v) for v in flat.mean(axis=(0, 1))],
            "sd": [float(v) for v in sd],
            "ess": [ess(flat[:, :, i]) for i in range(flat.shape[2])],
            "rhat": [rhat(flat[:, :, i]) for i in range(flat.shape[2])],
        }
        if accept_rate is not None and name in accept_rate:
            entry["accept"] = [float(v) for v in accept_rate[name].reshape(d.shape[0], -1).mean(0)]
        out[name] = entry
    return out


RHAT_MAX = 1.01
"""Largest R-hat (rank-normalised, split) of a converged parameter (Vehtari et al. 2021)."""
ESS_MIN = 100.0
"""Smallest bulk effective sample size of a converged parameter (all chains together)."""
INFINITE_RHAT = "R-hat inf"
"""`convergence`'s reason (before any ", ESS ..." it adds) for an element whose R-hat is
infinite (each chain constant, the chains apart); a file's record stores that R-hat as null, as
it stores one not computable, and `gpmsa info` tells them apart by this reason."""


def says_infinite_rhat(why: object) -> bool:
    """Whether a convergence record's reason ``why`` (a flagged element's) calls its R-hat
    infinite: `INFINITE_RHAT` before any ", ..." the reason adds (`gpmsa info` and
    `read_back` read a file's record alike by this)."""
    return isinstance(why, str) and why.split(",")[0] == INFINITE_RHAT


RHAT_NOISE = 7.0
"""(R-hat - 1) x bulk ESS that one converged chain's split R-hat exceeds in about 1% of chains,
whatever its autocorrelation (measured on AR(1) chains, ESS 100-1,300: 99th percentiles 5.4-7.1,
medians 1.2-1.8). One chain's R-hat above RHAT_MAX but at most 1 + RHAT_NOISE / ESS is flagged
all the same (a drift of up to about one posterior sd over the chain reads so too: its ESS
stays above ESS_MIN), and its reason says it lies within that noise: a longer chain tells the
two apart."""
RHAT_APART = 1.1
"""R-hat above which the chains are not merely short but apart (Gelman and Rubin's old limit):
the convergence warning then says that longer chains may not join them."""


def beyond(value: float, limit: float, places: int) -> str:
    """``value``, which lies beyond ``limit`` (an R-hat above it, an ESS below), with ``places``
    decimals, or as many more as show it beyond: an R-hat of 1.0102 is "1.0102", not "1.010"
    beside a limit of 1.01, an ESS of 99.6 "99.6", not "100"."""
    txt = f"{value:.{places}f}"
    for more in range(places + 1, places + 9):
        if (float(txt) - limit) * (value - limit) > 0:
            break
        txt = f"{value:.{more}f}"
    return txt


def element_names(name: str, shape: tuple[int, ...]) -> list[str]:
    """Names of the elements of parameter ``name`` in C order: "lamUz[0]", "betaU[1,0]"; a
    scalar (shape ()) is its name."""
    if len(shape) == 0:
        return [name]
    if len(shape) == 1:
        return [f"{name}[{i}]" for i in range(int(np.prod(shape)))]
    return [f"{name}[{','.join(map(str, ix))}]" for ix in np.ndindex(*shape)]


def convergence(
    summary: dict[str, dict[str, list[float]]],
    shapes: dict[str, tuple[int, ...]],
    n_chains: int,
    n_draws: int,
    held: frozenset[str] | set[str] = frozenset(),
    levels: frozenset[str] | set[str] = frozenset(),
) -> dict:
    """The convergence record of sampled parameters from ``summarize`` output (JSON-able).

    ``shapes``: name -> element shape of every sampled parameter to judge; ``held``: names of
    elements held fixed within them ("lamVz[1]"), not judged; ``levels``: names of categorical
    elements (a level each draw), whose constant draws in one chain are not flagged: the
    posterior may hold one level, and one chain cannot tell that from a stuck chain (several
    chains at one level are flagged, as chains that may not have left their starts). Returns
    n_chains,
    n_draws (per chain), the limits, per parameter ``rhat`` and ``ess`` (bulk) lists (C order),
    the worst element of each kind (``max_rhat``, ``min_ess``: [element, value]; the value None
    where it is not finite, an infinite R-hat of chains stuck at different values; the element
    "" where no element has a value), and ``flagged``: element -> reason, for every element with
    R-hat > RHAT_MAX, ESS < ESS_MIN, no movement at all (constant draws: NaN R-hat and ESS), or
    too few draws to judge (fewer than MIN_DRAWS_RHAT a chain: no R-hat, and ArviZ's ESS of
    such short chains can exceed ESS_MIN even for chains stuck at different values).
    """
    rhat_of, ess_of, flagged = {}, {}, {}
    worst_r, worst_e = ("", -np.inf), ("", np.inf)
    for name, shape in shapes.items():
        rs, es = summary[name]["rhat"], summary[name]["ess"]
        rhat_of[name], ess_of[name] = list(rs), list(es)
        for el, r, e in zip(element_names(name, shape), rs, es, strict=True):
            if el in held:
                continue
            r = float("nan") if r is None else float(r)
            e = float("nan") if e is None else float(e)
            if n_draws < MIN_DRAWS_RHAT:
                flagged[el] = f"too few draws to judge ({n_draws} a chain)"
                continue
            if not (np.isfinite(r) or np.isfinite(e)):
                if el not in levels:
                    flagged[el] = "constant draws (no proposal accepted)"
                elif n_chains > 1:
                    flagged[el] = "constant draws (one level in every chain)"
                continue
            why = []
            if r > RHAT_MAX:
                why.append(INFINITE_RHAT if np.isinf(r) else f"R-hat {beyond(r, RHAT_MAX, 3)}")
                if n_chains == 1 and e >= ESS_MIN and r <= 1.0 + RHAT_NOISE / e:
                    why[-1] += f" (within one converged chain's noise at ESS {e:.0f})"
            if e < ESS_MIN:
                why.append(f"ESS {beyond(e, ESS_MIN, 0)}")
            if why:
                flagged[el] = ", ".join(why)
            if r > worst_r[1]:  # +inf too (chains stuck at different values); NaN never
                worst_r = (el, r)
            if np.isfinite(e) and e < worst_e[1]:
                worst_e = (el, e)
    return {
        "n_chains": int(n_chains),
        "n_draws": int(n_draws),
        "rhat_max": RHAT_MAX,
        "ess_min": ESS_MIN,
        "rhat": rhat_of,
        "ess": ess_of,
        "max_rhat": [worst_r[0], worst_r[1] if np.isfinite(worst_r[1]) else None],
        "min_ess": [worst_e[0], worst_e[1] if np.isfinite(worst_e[1]) else None],
        "flagged": flagged,
        "converged": not flagged,
    }


def read_back(summary: dict, shapes: dict[str, tuple[int, ...]], flagged: object = None
              ) -> dict:  # fmt: skip
    """``summarize``'s output as a file's JSON stores it (non-finite numbers as null) read
    back: a null inside a list as NaN (constant chains, one draw's sd, a rate not computed), or
    as inf for an R-hat whose element the convergence record's ``flagged`` calls infinite
    (`INFINITE_RHAT`: chains stuck apart). ``shapes``: name -> element shape (for the element
    names; a ``flagged`` that is no dict, which a file's checks let pass, names none). A field
    stored whole as null (no rates) stays None; anything else is kept as it is (the file's
    checks judged it). ``summary`` is not changed."""
    flagged = flagged if isinstance(flagged, dict) else {}
    return {
        name: {key: _nulls_read(v, name, shapes, flagged, rhat=key == "rhat")
               for key, v in entry.items()} if isinstance(entry, dict) else entry
        for name, entry in summary.items()
    }  # fmt: skip


def read_back_convergence(record, shapes: dict[str, tuple[int, ...]]):
    """A `convergence` record as a file stores it read back as `read_back` reads a summary:
    its "rhat" and "ess" lists' nulls as NaN, or inf where its "flagged" calls the R-hat
    infinite ("max_rhat" and "min_ess" keep None: `convergence` writes None there). ``record``
    is not changed; one that is no dict (None: none recorded) comes back as it is."""
    if not isinstance(record, dict):
        return record
    flagged = record.get("flagged")
    flagged = flagged if isinstance(flagged, dict) else {}
    out = dict(record)
    for key in ("rhat", "ess"):
        if isinstance(record.get(key), dict):
            out[key] = {name: _nulls_read(v, name, shapes, flagged, rhat=key == "rhat")
                        for name, v in record[key].items()}  # fmt: skip
    return out


def _nulls_read(values, name: str, shapes: dict, flagged: dict, rhat: bool):
    """``values`` with each None item as NaN (inf for a flagged infinite R-hat); ``values`` as
    it is where it is no list."""
    if not isinstance(values, list):
        return values
    names = None
    if rhat and name in shapes and int(np.prod(shapes[name])) == len(values):
        names = element_names(name, tuple(shapes[name]))
    out = []
    for i, v in enumerate(values):
        if v is None:
            why = flagged.get(names[i], "") if names is not None else ""
            v = np.inf if says_infinite_rhat(why) else np.nan
        out.append(v)
    return out


def warn_unconverged(record: dict, what: str, length: str = "n_iter",
                     more: str = "", names: dict[str, str] | None = None) -> None:  # fmt: skip
    """Warn (``gpmsa.ConvergenceWarning``) naming every flagged element of a convergence record
    and the caller's argument ``length`` that sets the chains' length (``more``: a further
    remedy, appended). Where the worst R-hat exceeds RHAT_APART (or is infinite) the warning
    adds that the chains lie apart, which longer chains may not mend (several modes). A record
    of one chain is worded for it: its split R-hat compares the chain's halves and cannot show
    whether independent chains agree, so it advises a longer chain or ``n_chains >= 2``.
    ``names``: element -> what it is for a person ("theta[0]" -> "k"), shown beside it. The
    warning points at the user's call (`user_stacklevel`)."""
    from gpmsa.errors import ConvergenceWarning, user_stacklevel

    flagged = record.get("flagged") or {}
    if not flagged:
        return
    names = names or {}

    def shown_as(el: str) -> str:
        return f"{el} ({names[el]})" if el in names else el

    items = "; ".join(f"{shown_as(el)}: {why}" for el, why in flagged.items())
    one = record["n_chains"] == 1
    apart = ""
    el, r = record.get("max_rhat") or ("", None)
    if el and (r is None or r > RHAT_APART):  # None with an element: an infinite R-hat
        shown = "inf" if r is None else beyond(r, RHAT_APART, 3)
        which = "the chain's halves lie" if one else "the chains lie"
        apart = (
            f" R-hat {shown} ({shown_as(el)}) says {which} apart, not merely that they "
            "are short: if longer chains do not bring them together, the posterior may have "
            "several modes that no chain crosses (compare the chains: to_arviz(), "
            "gpmsa.plots.traces; parallel tempering moves between modes: the numpy and "
            "torch samplers' temperatures= option of gpmsa.fit, calibrate(fast=False), "
            "calibrate_study and fit_study)."
        )
    if any(str(why).startswith("constant draws") for why in flagged.values()):
        apart += (
            " Constant draws in the chain: a categorical theta's chain that never leaves the "
            "level it started at reads so too, whether the posterior holds one level or the "
            "chain is stuck (run chains started at other levels, or let parallel tempering's "
            "temperatures= move between them: docs/models.md)."
            if one else
            " Constant draws in every chain: a categorical theta's chains that never leave the "
            "levels they started at read so too, whether the posterior holds one level or the "
            "chains are stuck (start chains at other levels, or let parallel tempering's "
            "temperatures= move between them: docs/models.md)."
        )  # fmt: skip
    noise = "within one converged chain's noise"
    if all(noise in str(why) for why in flagged.values()):  # one chain, ESS >= ESS_MIN each
        apart += (
            f" Each R-hat flagged lies within the noise of one converged chain at its ESS (up "
            f"to 1 + {RHAT_NOISE:g} / ESS in 1% of converged chains), as it does for a drift "
            f"of up to about one posterior sd over the chain: a longer chain ({length}) tells "
            "them apart."
        )
    chains, advice = f"{record['n_chains']} chains", f"Run longer chains ({length}) or more of them"
    if one:  # split R-hat: the chain's halves, not independent chains (PyMC's, Stan's practice)
        chains = "1 chain"
        advice = (
            "One chain's split R-hat compares the chain's halves and cannot show whether "
            f"independent chains agree: run a longer chain ({length}) or n_chains >= 2"
        )
    warnings.warn(
        f"{what}: {len(flagged)} parameter element(s) not converged over {chains} x "
        f"{record['n_draws']} draws (need R-hat <= {record['rhat_max']} and bulk ESS >= "
        f"{record['ess_min']:.0f}): {items}. {advice}{more}.{apart}",
        ConvergenceWarning, stacklevel=user_stacklevel(),
    )  # fmt: skip
