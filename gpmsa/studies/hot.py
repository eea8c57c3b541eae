"""A tempered study's hot copies: their record in the study's settings (``HOT_RECORD``, as a
tempered fit's, ``gpmsa.fitting.validation``), its check on loading, and a continuation at the
same ladder resuming every copy where it stopped, untuned (docs/internals.md, "Tempered
continuation").

settings "hot_states": {"theta": (C, K - 1, G), "mu", "lam": (C, K - 1, H), "members": {label:
{name: (C, K - 1, *shape)}}} (unit scale; each model's sampled parameters) and
"hot_step_widths": {sweep element name: (C, K - 1)}; both or neither (absent in untempered
studies, in files written before the record and where it would hold more than
``MAX_HOT_VALUES`` numbers)."""

from __future__ import annotations

import math

import numpy as np

from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.fitting.continuation import reordered
from gpmsa.fitting.validation import HOT_RECORD, MAX_HOT_VALUES, file_floats, hot_record_given
from gpmsa.mcmc.sampler import none_as_nan
from gpmsa.model.data import as_float
from gpmsa.model.discrepancy import n_groups
from gpmsa.studies.sampler import StudyState

PARTS = ("theta", "mu", "lam", "members")
"""The keys of settings "hot_states"."""


def hot_record(info: dict, names, labels) -> dict:
    """The settings of a tempered run's hot copies (``sample_study``'s info "hot"; ``names``:
    the sweep's elements, ``labels``: the models'): ``HOT_RECORD``, or {} where they would hold
    more than ``MAX_HOT_VALUES`` numbers (its continuation then tunes its copies)."""
    hot = info.get("hot")
    if hot is None:
        return {}
    arrays = [hot["theta"], hot["mu"], hot["lam"], hot["widths"],
              *(v for m in hot["members"] for v in m.values())]  # fmt: skip
    if sum(np.size(a) for a in arrays) > MAX_HOT_VALUES:
        return {}
    states = {k: np.asarray(hot[k]).tolist() for k in ("theta", "mu", "lam")}
    states["members"] = {lab: {n: np.asarray(v).tolist() for n, v in m.items()}
                         for lab, m in zip(labels, hot["members"], strict=True)}  # fmt: skip
    widths = {n: hot["widths"][:, :, e].tolist() for e, n in enumerate(names)}
    return dict(zip(HOT_RECORD, (states, widths), strict=True))


def continued_copies(settings: dict, starts: list[tuple], problems, layout, hyper,
                     there: list[str], orders: list, n_temps: int) -> list:  # fmt: skip
    """Per chain, its K - 1 hot copies' (start, widths) from the source's ``settings``
    (``HOT_RECORD``): each start (models' starts, g, mu, lam) the chain's (``starts``, as
    ``continuation.chain_starts``) with the recorded values; widths in sweep order (``there``:
    each element's name in the source; ``orders``: per model, its per-component parameters'
    order among the source's). GPMSAError naming the record where it does not fit this study
    or a copy's state has no finite log posterior here (a damaged file)."""
    try:
        return _copies(settings, starts, problems, layout, hyper, there, orders, n_temps - 1)
    except (GPMSAError, KeyError, TypeError, ValueError, IndexError) as exc:
        raise GPMSAError(
            f"init=study: its recorded hot copies (settings['hot_states'], "
            f"settings['hot_step_widths']) do not fit this study ({exc}); pass tune=True (every "
            "copy tuned from the chain's last state) or temperatures= another ladder (1: none)"
        ) from None


def _copies(settings, starts, problems, layout, hyper, there, orders, n_hot):
    states, widths = (settings[k] for k in HOT_RECORD)
    n_chains = len(starts)

    def arr(value, shape, what):
        out = as_float(value, what, advice=False)
        if 0 in shape and out.size == 0:  # JSON keeps no empty shape
            out = np.zeros((n_chains, n_hot, *shape))
        if out.shape != (n_chains, n_hot, *shape):
            raise GPMSAError(f"{what} has shape {out.shape}, expected {(n_chains, n_hot, *shape)}")
        return out

    n_h = len(layout.groups)
    g = arr(states["theta"], (layout.n_elements,), "theta")
    mu, lam = arr(states["mu"], (n_h,), "mu"), arr(states["lam"], (n_h,), "lam")
    members = []
    for lab, prob, order in zip(layout.labels, problems, orders, strict=True):
        rec = states["members"][lab]
        if set(rec) != set(prob.sampled) - {"theta"}:
            raise GPMSAError(f"model {lab!r}: parameters {sorted(rec)}, this study samples "
                             f"{sorted(set(prob.sampled) - {'theta'})}")  # fmt: skip
        members.append({n: reordered(n, arr(v, prob.init[n].shape, f"{lab}.{n}"), order)
                        for n, v in rec.items()})  # fmt: skip
    if set(widths) != set(there):
        raise GPMSAError(f"widths name {sorted(widths)}, this study sweeps {sorted(there)}")
    w = np.stack([arr(widths[n], (), f"widths of {n!r}") for n in there], axis=-1)
    if not (np.all(np.isfinite(w)) and np.all(w > 0)):
        raise GPMSAError("widths must be finite numbers > 0")
    out = []
    for c, (models, *_) in enumerate(starts):
        chain = []
        for k in range(n_hot):
            start = ([{**m, **{n: v[c, k] for n, v in rec.items()}}
                      for m, rec in zip(models, members, strict=True)],
                     g[c, k].copy(), mu[c, k].copy(), lam[c, k].copy())  # fmt: skip
            state = StudyState(problems, layout, hyper, *start, np.random.default_rng(0))
            if not math.isfinite(state.log_post()):
                raise GPMSAError(f"chain {c}'s hot copy {k + 1} has no finite log posterior")
            chain.append((start, w[c, k]))
        out.append(chain)
    return out


def check_hot_record(settings: dict, study) -> None:
    """A study file's hot copies (settings ``HOT_RECORD``; absent: none), against ``study``
    built from the file: both or neither, "hot_states" with theta (C, K - 1, G), mu and lam
    (C, K - 1, H) and members {label: {name: (C, K - 1, *shape)}}, each name a parameter of
    that model (``member_shapes``) of its shape, finite numbers (precisions > 0),
    "hot_step_widths" {sweep element: (C, K - 1)} finite numbers > 0; C the draws' chains, K
    the length of settings.temperatures. EmulatorFileError naming the field otherwise."""
    if not hot_record_given(settings, "study"):
        return
    temps = settings.get("temperatures")
    if not isinstance(temps, list) or len(temps) < 2:
        raise _fail("settings.hot_states", f"needs settings.temperatures, a ladder of 2 or more "
                                           f"(got {temps!r:.60})")  # fmt: skip
    lead = (int(study.draws["log_post"].shape[0]), len(temps) - 1)
    states, widths = (settings[k] for k in HOT_RECORD)
    for key, value in ((HOT_RECORD[0], states), (HOT_RECORD[1], widths)):
        if not isinstance(value, dict):
            raise _fail(f"settings.{key}", f"must be an object, got {value!r:.60}")
    if set(states) != set(PARTS):
        raise _fail("settings.hot_states", f"must hold exactly {list(PARTS)}, got "
                                           f"{sorted(states)!r:.120}")  # fmt: skip
    n_h = len(study.layout.groups)
    want = {"theta": (study.layout.n_elements,), "mu": (n_h,), "lam": (n_h,)}
    for part, shape in want.items():
        _values(states[part], (*lead, *shape), f"settings.hot_states.{part}", part == "lam")
    members = states["members"]
    if not isinstance(members, dict) or set(members) != set(study.labels):
        raise _fail("settings.hot_states.members", f"must be an object naming the models "
                                                   f"{list(study.labels)}")  # fmt: skip
    for lab, rec in members.items():
        if not isinstance(rec, dict):
            raise _fail(f"settings.hot_states.members.{lab}", "must be an object name -> values")
        own = member_shapes(study, study.labels.index(lab))
        for name, value in rec.items():
            field = f"settings.hot_states.members.{lab}.{name:.40}"
            if name not in own:
                raise _fail(field, f"names no parameter of model {lab!r} (its own: "
                                   f"{sorted(own)}; theta is the study's, settings.hot_states."
                                   "theta)")  # fmt: skip
            want = (*lead, *own[name])
            arr = _values(value, None, field, name.startswith("lam"))
            if arr.shape != want and not (arr.size == 0 and 0 in want):  # JSON: no empty shape
                raise _fail(field, f"has shape {list(arr.shape)}, expected {list(want)}: "
                                   f"(chains, hot copies) + {name}'s shape {list(own[name])} "
                                   f"in model {lab!r}")  # fmt: skip
    rates = settings.get("accept_rate")
    if isinstance(rates, dict) and set(widths) != set(rates):
        raise _fail("settings.hot_step_widths", "must name the sweep's elements (those of "
                                                "settings.accept_rate)")  # fmt: skip
    for name, value in widths.items():
        _values(value, lead, f"settings.hot_step_widths[{name!r:.40}]", True)


def member_shapes(study, i: int) -> dict[str, tuple[int, ...]]:
    """Model ``i``'s own parameters and their shapes, as its calibration problem or joint fit
    has them (theta aside: the study's): the emulator's (``Emulator.params``; held in a
    calibration), lamOs (1,) and, with a discrepancy of G precision groups, betaV (p, G) and
    lamVz (G,)."""
    emu = study.members[i]
    own = {k: tuple(np.shape(v)) for k, v in emu.params.items()}
    own["lamOs"] = (1,)
    rec = study.discrepancy(i)
    if rec is not None:
        n_grp = n_groups(rec["discrepancy_groups"])
        own.update(betaV=(emu.p, n_grp), lamVz=(n_grp,))
    return own


def _values(value, shape, field: str, positive: bool) -> np.ndarray:
    """``value`` as finite float64 (> 0 where ``positive``) of ``shape`` (None: any): numbers
    in nested lists, null among them read as NaN (refused as not finite)."""
    arr = file_floats(none_as_nan(value) if isinstance(value, list) else value, field)
    if shape is not None and arr.shape != shape and not (arr.size == 0 and 0 in shape):
        raise _fail(field, f"has shape {list(arr.shape)}, expected {list(shape)} (chains, hot "
                           "copies: one per rung of settings.temperatures above T = 1, "
                           "...)")  # fmt: skip
    bad = ~np.isfinite(arr) | ((arr <= 0) if positive else False)
    if np.any(bad):  # the values refused, not the array's first
        need = "finite numbers > 0" if positive else "finite numbers"
        raise _fail(field, f"must be {need}, got {arr[bad][:4].tolist()!r:.60}")
    return arr


def _fail(field: str, problem: str) -> EmulatorFileError:
    return EmulatorFileError(f"{field}: {problem}")
