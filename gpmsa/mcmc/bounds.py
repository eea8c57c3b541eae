"""A calibration posterior piled up against a bound of the emulator's theta domain.

The prior of theta stops at the domain (the design's range, or ``SimData``'s ``t_range``), so
where the data point beyond it the posterior piles up at the bound, with a small sd that reads
as a confident estimate. ``gpmsa.calibrate``, a joint ``gpmsa.fit(data, obs)`` and the
studies (``calibrate_study``, ``fit_study``) flag it (``AtBoundWarning``;
``Posterior.info["at_bound"]``), and ``gpmsa calibrate`` prints it (from its grid
posterior's exact marginals where it has them); the online ``Calibrator`` does not.

The rule: at least ``BOUND_SHARE`` (half) of the draws lie within ``BOUND_BAND`` (1 %) of the
domain's width of a bound, i.e. the posterior median lies there. On synthetic calibrations
(``docs/calibration.md``) it never fired with the truth inside at 0.5 of the width, fired
in 1 % of runs with the truth at 0.97 or 0.03 of it (posteriors that approach the edge), and
in every run with the truth 30 % of the width outside whose posterior was tight (sd under
1 % of the width); a broad posterior (the data say little) that merely leans on the bound is
not flagged.
"""

from __future__ import annotations

import warnings

import numpy as np

from gpmsa.errors import AtBoundWarning, numbers_text, user_stacklevel

BOUND_BAND = 0.01
"""The band at each end of a theta element's domain, a fraction of the domain's width."""

BOUND_SHARE = 0.5
"""The share of the draws inside a band that marks the posterior piled up there."""


def _shares(values, lo: float, hi: float) -> tuple[float, float]:
    """The posterior's share within `BOUND_BAND` of the width of [``lo``, ``hi``]'s lower and
    upper bound: of draws (an array), or of a grid posterior's marginal (anything with a
    ``cdf``, a ``GridMarginal``: its exact mass there, no draws)."""
    band = BOUND_BAND * (hi - lo)
    if callable(getattr(values, "cdf", None)):
        return float(values.cdf(lo + band)), 1.0 - float(values.cdf(hi - band))
    d = np.asarray(values)
    return float(np.mean(d <= lo + band)), float(np.mean(d >= hi - band))


def at_bound(draws: dict, names, t_min, t_max, skip=()) -> dict[str, str]:
    """name -> "lower" or "upper" for each theta element whose draws (native units, ``draws``
    by name; or a grid posterior's marginal, `_shares`) pile up against that bound of its
    domain [``t_min``, ``t_max``] (`BOUND_SHARE` of them within `BOUND_BAND` of the width);
    ``skip``: names not judged (categorical or held elements)."""
    out = {}
    for k, name in enumerate(names):
        lo, hi = float(t_min[k]), float(t_max[k])
        if name in skip or not BOUND_BAND * (hi - lo) > 0.0:
            continue
        lower, upper = _shares(draws[name], lo, hi)
        if upper >= BOUND_SHARE:
            out[name] = "upper"
        elif lower >= BOUND_SHARE:
            out[name] = "lower"
    return out


def bound_text(side: str, values, lo: float, hi: float) -> str:
    """A parameter flagged at ``side`` of [``lo``, ``hi``] in words: "its upper bound 600
    (domain [200, 600]; 97% of the draws within 1% of its width of it; mean 598.5, sd 1.3)"
    (``values``: its draws, or a grid posterior's marginal: "of the posterior")."""
    shares = _shares(values, lo, hi)
    if callable(getattr(values, "cdf", None)):
        what, mean, sd = "posterior", values.mean(), values.sd()
    else:
        what, mean, sd = "draws", np.mean(values), np.std(values)
    mean, sd, lo_text, hi_text = numbers_text(mean, sd, lo, hi, digits=4)
    return (
        f"its {side} bound {hi_text if side == 'upper' else lo_text} (domain [{lo_text}, "
        f"{hi_text}]; {shares[side == 'upper']:.0%} of the {what} within {BOUND_BAND:.0%} of "
        f"its width of it; mean {mean}, sd {sd})"
    )


def warn_at_bound(found: dict[str, str], draws: dict, names, t_min, t_max, where: str,
                  record: str) -> None:  # fmt: skip
    """One ``AtBoundWarning`` naming each element of ``found`` (`at_bound`'s), its bound, the
    share of its draws there, what it may mean and what to do; ``where``: the call,
    ``record``: where the user reads ``found`` again."""
    if not found:
        return
    parts = [
        f"{name} at {bound_text(found[name], draws[name], float(t_min[k]), float(t_max[k]))}"
        for k, name in enumerate(names)
        if name in found
    ]
    warnings.warn(
        f"{where}: the posterior piles up against a bound of the emulator's domain: "
        f"{'; '.join(parts)}. The data may point beyond the simulation design (the truth "
        "outside it), or the model misses something that theta absorbs (a discrepancy "
        "missing, a wrong emulator or units): the sd is then the prior's edge, not the "
        "data's precision. Widen the design (simulation runs beyond that bound) and refit, "
        f"or check the emulator and add a discrepancy; {record} records it",
        AtBoundWarning,
        stacklevel=user_stacklevel(),
    )
