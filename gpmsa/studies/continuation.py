"""Continuing a study's chains (``calibrate_study(..., init=study)``, ``fit_study(...,
init=study)``): the checks that the study is this one's, each chain's start at its last kept
draw, its step widths and precision steps (SEPIA's second ``do_mcmc`` of its shared and
hierarchical models), and ``append=True``, which pools the source's kept draws with the
continuation's (as ``gpmsa.fit``'s, ``gpmsa.fitting.continuation``)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from gpmsa.errors import GPMSAError
from gpmsa.fitting.continuation import (
    PER_COMPONENT,
    append_step,
    appended_counts,
    component_order,
    continued_starts,
    discrepancy_moved,
    pool_chains,
    reordered,
    sweeps_run,
)
from gpmsa.fitting.continuation import check_append as check_fit_append
from gpmsa.fitting.emulator import EMULATOR_PARAMS
from gpmsa.model.data import as_float
from gpmsa.model.problem import Problem
from gpmsa.studies.layout import HyperPriors, Layout
from gpmsa.studies.record import discrepancy_arrays
from gpmsa.studies.sampler import StudyState, element_names
from gpmsa.studies.study import Study

WIDTHS_BY_CHAIN = "step_widths_by_chain"
"""The settings key of a study of several chains: sweep element name -> each chain's step width
(``settings["step_widths"]`` holds chain 0's); absent with one chain and in files written
before it."""
STEPS = "proportional_steps"
"""The settings key of a continued study: whether its chains stepped the precisions by GPM/SA's
proportional step (absent: ``not settings["tune"]``, the rule its sampler followed)."""


def check_source(source: Study, kind: str, layout: Layout, hyper: HyperPriors,
                 n_chains: int, **same) -> None:  # fmt: skip
    """GPMSAError naming what of ``source`` (``init=``) differs from this study: its kind, its
    number of chains, its labels, shared and hierarchical names, elements (ranges and theta
    priors), hyperpriors, and each ``same`` entry (name -> (the source's, this one's))."""
    what = "calibrate_study" if kind == "calibration" else "fit_study"
    if source.kind != kind:
        raise GPMSAError(f"init=study is a {source.kind} study; {what} continues a study of kind "
                         f"{kind!r} (made by {what})")  # fmt: skip
    n_prev = int(source.draws["log_post"].shape[0])
    if n_prev != n_chains:
        raise GPMSAError(f"init=study continues its {n_prev} chain(s): pass n_chains={n_prev}")
    old = source.layout
    checks = {
        "labels": (list(old.labels), list(layout.labels)),
        "shared": (list(old.shared), list(layout.shared)),
        "hierarchical": (list(old.groups), list(layout.groups)),
        "calibration parameters (names, ranges, theta priors)": _differing_elements(old, layout),
        # without a group the hyperpriors act on nothing (a study file before sd_prior
        # records SEPIA's, one since the default): they cannot make the studies differ
        **({"hyper": (source.hyper.to_dict(), hyper.to_dict())} if layout.groups else {}),
        **same,
    }  # fmt: skip
    differs = [name for name, (a, b) in checks.items() if a != b]
    if differs:
        detail = "; ".join(f"{n}: {_brief(checks[n][0])} there, {_brief(checks[n][1])} here"
                           for n in differs)  # fmt: skip
        raise GPMSAError(f"init=study was another study: its {', '.join(differs)} differ "
                         f"({detail}); continue it with the same models and settings, or start "
                         "afresh")  # fmt: skip


def _differing_elements(old: Layout, new: Layout) -> tuple[list, list]:
    """The study elements (name, theta prior, range) of the layouts ``old`` and ``new``: those
    that differ where both have as many (a model's own element names its model: "m[b]"), else
    all of them."""
    pairs = [[(e.name, e.prior, b) for e, b in zip(lay.elements, lay.bounds, strict=True)]
             for lay in (old, new)]  # fmt: skip
    if len(pairs[0]) != len(pairs[1]):
        return pairs[0], pairs[1]
    diff = [k for k, (a, b) in enumerate(zip(*pairs, strict=True)) if a != b]
    return [pairs[0][k] for k in diff], [pairs[1][k] for k in diff]


def _brief(value) -> str:
    text = repr(value)
    return text if len(text) <= 120 else text[:117] + "..."


def calibration_starts(source: Study, problems: list[Problem]) -> list[list[dict]]:
    """Per chain, each model's start for ``calibrate_study``: its lamOs (and discrepancy's betaV,
    lamVz) at the chain's last kept draw in ``source``, the rest (the emulator's parameters,
    held) its problem's."""
    out = []
    for c in range(source.draws["log_post"].shape[0]):
        chain = []
        for j, prob in enumerate(problems):
            beta, lam = discrepancy_arrays(j)
            drawn = {"lamOs": source.draws["lamOs"][:, :, j], "betaV": source.draws.get(beta),
                     "lamVz": source.draws.get(lam)}  # fmt: skip
            start = dict(prob.init)
            for name in ("lamOs", "betaV", "lamVz"):
                if name not in prob.init or not prob.init[name].size:
                    continue
                if drawn[name] is None:
                    raise GPMSAError(f"init=study has no {name} draws of model "
                                     f"{source.labels[j]!r} (another discrepancy?)")  # fmt: skip
                val = np.asarray(drawn[name][c, -1], dtype=np.float64)
                if val.size != prob.init[name].size:
                    raise GPMSAError(f"init=study's {name} of model {source.labels[j]!r} has "
                                     f"{val.size} elements, this one's {prob.init[name].size} "
                                     "(another discrepancy basis or groups?)")  # fmt: skip
                start[name] = val.reshape(prob.init[name].shape)
            chain.append(start)
        out.append(chain)
    return out


def fit_starts(source: Study, problems: list[Problem], preps, obs, n_chains: int
               ) -> list[list[dict]]:  # fmt: skip
    """Per chain, each model's start for ``fit_study``: every parameter at the chain's last kept
    draw in its fitted member (``gpmsa.fitting.continuation.continued_starts``, which refuses
    other simulation runs, observations, priors, fixed parameters or discrepancy, naming the
    model; bases whose columns are the source's up to their signs and order are the same
    model, the per-component parameters following K's columns: ``member_orders``)."""
    per_model = []
    for lab, emu, prob, prep, o in zip(source.labels, source.members, problems, preps, obs,
                                       strict=True):  # fmt: skip
        try:
            per_model.append(continued_starts(emu, prob, prep.K, o, n_chains))
        except GPMSAError as exc:
            raise GPMSAError(f"model {lab!r}: {str(exc).replace('init=emulator', 'init=study')}"
                             ) from None  # fmt: skip
    return [[{k: v[c] for k, v in m.items()} for m in per_model] for c in range(n_chains)]


def member_orders(source: Study, problems: list[Problem]) -> list[list[int] | None]:
    """Per model, where its basis vectors (K's columns) are among its source member's
    (``component_order``; a model ``fit_starts`` took), for the per-component parameters'
    widths, draws and acceptance rates."""
    return [component_order(emu, prob) for emu, prob in zip(source.members, problems,
                                                            strict=True)]  # fmt: skip


def same_discrepancies(old: dict | None, new: dict | None, obs: dict) -> dict | None:
    """This calibration study's discrepancy record ``new`` (label -> its ``DISCREPANCIES``
    entry) with each model's entry that is the source's (``old``) up to its basis's columns'
    signs and order (``discrepancy_moved``, each column keeping its group; the same kind) as
    the source's: the same model, which ``check_source`` then finds equal. ``obs``: label ->
    the model's ObsProblem."""
    if not isinstance(old, dict) or not isinstance(new, dict):
        return new
    out = dict(new)
    for lab, entry in new.items():
        was = old.get(lab)
        if not isinstance(was, dict) or was == entry:
            continue
        kinds = [{k: v for k, v in d.items() if not k.startswith("discrepancy_")}
                 for d in (was, entry)]  # fmt: skip
        if kinds[0] == kinds[1] and discrepancy_moved(was, entry, obs.get(lab)):
            out[lab] = was
    return out


def chain_starts(source: Study, models: list[list[dict]]) -> list[tuple]:
    """Each chain's (models' starts, study elements g, groups' mu, lam) at its last kept draw."""
    return [(m, source.draws["theta"][c, -1].copy(), source.draws["mu"][c, -1].copy(),
             source.draws["lam"][c, -1].copy()) for c, m in enumerate(models)]  # fmt: skip


def sweep_names(problems, layout, hyper, start, orders=None) -> tuple[list[str], list[str]]:
    """The sweep's element names from chain 0's start (a ``StudyState``), and each one's name
    in the source: a per-component element (``PER_COMPONENT``) at its source component
    (``orders``: per model, ``member_orders``; None: as here). GPMSAError where the source's
    draws give no finite log posterior here."""
    state = StudyState(problems, layout, hyper, *start, np.random.default_rng(0))
    if not math.isfinite(state.log_post()):
        raise GPMSAError("init=study: its last kept draws have no finite log posterior in this "
                         "study (other data or priors?); start afresh")  # fmt: skip
    orders = [None] * len(state.states) if orders is None else orders
    there = [SimpleNamespace(els=_source_elements(s.problem, s.els, o))
             for s, o in zip(state.states, orders, strict=True)]  # fmt: skip
    return element_names(state.states, layout), element_names(there, layout)


def _source_elements(problem: Problem, els, order: list[int] | None) -> list[tuple]:
    """A model's sweep elements (name, index) with each per-component one's index at its
    source component (``reordered``: this model's component j is the source's ``order[j]``)."""
    out = []
    for name, idx in els:
        if name in PER_COMPONENT:
            shape = problem.init[name].shape
            flat = reordered(name, np.arange(math.prod(shape)).reshape(shape), order)[idx]
            idx = tuple(int(i) for i in np.unravel_index(int(flat), shape))
        out.append((name, idx))
    return out


def continued_widths(source: Study, names: list[str], n_chains: int) -> list[np.ndarray] | None:
    """Each chain's step widths in sweep order (``names``) as ``source`` recorded them (its
    ``WIDTHS_BY_CHAIN``, else ``settings["step_widths"]`` for every chain: one chain, or
    untuned ones, which run on GPM/SA's widths); None where it records none. GPMSAError where
    the record does not fit this study's sweep."""
    settings = source.settings
    record = settings.get(WIDTHS_BY_CHAIN)
    if record is None:
        one = settings.get("step_widths")
        if one is None:
            return None
        if n_chains > 1 and settings.get("tune") is not False:
            return None  # tuned chains' own widths not recorded: tune again
        record = {k: [v] * n_chains for k, v in one.items()} if isinstance(one, dict) else one
    if not isinstance(record, dict) or sorted(record) != sorted(names):
        raise GPMSAError("init=study: its recorded step widths do not name this study's sweep "
                         "elements (another model?); pass tune=True")  # fmt: skip
    try:  # text, bools, null or a number beyond float64: a damaged record
        w = as_float([record[n] for n in names], "the step widths", advice=False).T
    except GPMSAError:
        w = np.empty(0)
    if w.shape != (n_chains, len(names)) or not (np.all(np.isfinite(w)) and np.all(w > 0)):
        raise GPMSAError(f"init=study: its recorded step widths are not finite positive widths "
                         f"for {n_chains} chain(s); pass tune=True")  # fmt: skip
    return list(w)


def continued_steps(source: Study) -> bool:
    """Whether ``source``'s chains stepped the precisions proportionally (``STEPS``, else
    ``not settings["tune"]``), for its untuned continuation."""
    steps = source.settings.get(STEPS, not source.settings.get("tune", True))
    if not isinstance(steps, bool):
        raise GPMSAError(f"init=study: its settings[{STEPS!r}] must be true or false, got "
                         f"{steps!r}; pass tune=True")  # fmt: skip
    return steps


def source_digest(source: Study) -> str | None:
    """The source's study file digest (``content_sha256``) where it was saved or loaded."""
    return getattr(source, "sha256", None)


def check_append(append, init, n_burn) -> bool:
    """A study function's ``append`` checked (`gpmsa.fitting.continuation.check_append`): a
    flag, True only with ``init`` a Study and ``n_burn`` None or 0."""
    return check_fit_append(append, init, n_burn, Study, "study", "study")


def appended_thin(source: Study, n_iter: int, n_chains: int, n_keep=None) -> int:
    """The thinning step of an appended study: the source's (``settings["thin"]``; a
    calibration study keeps every sweep: 1), checked as an appended fit's
    (`gpmsa.fitting.continuation.append_step`)."""
    return append_step(source.settings.get("thin", 1), n_iter, n_chains, n_keep, "init=study")


def refuse_tuning() -> None:
    """The GPMSAError of an appended study whose continuation would tune."""
    raise GPMSAError(
        "append=True pools the chains' draws evenly spaced in sweeps; tuning (tune=True, or "
        "tune=None where init=study records no step widths for its chains) would run its "
        "sweeps between the source's and the continuation's: pass tune=False"
    )


def _pool(old: np.ndarray, new: np.ndarray, what: str) -> np.ndarray:
    """(C, a, *shape) and (C, b, *shape) chains pooled as (C, a + b, *shape): each chain's
    ``old`` draws, then its ``new`` (``pool_chains``)."""
    old, new = np.asarray(old, dtype=np.float64), np.asarray(new, dtype=np.float64)
    if old.ndim != new.ndim or old.shape[0] != new.shape[0] or old.shape[2:] != new.shape[2:]:
        raise GPMSAError(f"append=True: init=study has no {what} draws of shape "
                         f"{new.shape[2:]} for {new.shape[0]} chain(s) to append to (another "
                         "model?)")  # fmt: skip
    c, a, b = new.shape[0], old.shape[1], new.shape[1]
    both = pool_chains(old.reshape(c * a, *old.shape[2:]), new.reshape(c * b, *new.shape[2:]), c)
    return both.reshape(c, a + b, *new.shape[2:])


def pool_study_draws(source: Study, draws: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """``source``'s draws (theta, mu, lam, lamOs, log_post, a calibration's betaV_j, lamVz_j;
    each (C, N, ...)), each chain followed by a continuation's ``draws``."""
    if set(source.draws) != set(draws):
        raise GPMSAError(f"append=True: init=study's draws {sorted(source.draws)} are not this "
                         f"study's {sorted(draws)}")  # fmt: skip
    return {k: _pool(source.draws[k], v, k) for k, v in draws.items()}


def pool_member(member, post: dict[str, np.ndarray], order: list[int] | None = None
                ) -> dict[str, np.ndarray]:  # fmt: skip
    """A fitted member's retained draws (its ``draws`` and ``calibration``, flat chain-major),
    each chain followed by the continuation's ``post`` (name -> (C, N, ...)); ``order``: this
    model's components among the member's (``member_orders``): the per-component draws are
    taken in this model's order (``reordered``)."""
    cal = dict(member.calibration or {})
    out = {}
    for k, v in post.items():
        old = member.draws.get(k) if k in EMULATOR_PARAMS else cal.get(k)
        old = None if old is None else reordered(k, old, order)
        c = v.shape[0]
        if old is None or np.shape(old)[0] % c:
            raise GPMSAError(f"append=True: init=study's member has no {k} draws to append to "
                             "(another model?)")  # fmt: skip
        old = np.asarray(old).reshape(c, np.shape(old)[0] // c, *np.shape(old)[1:])
        out[k] = _pool(old, v, k)
    return out


def appended_settings(source: Study, n_iter: int, accept_rate: dict | None,
                      renamed: dict[str, str] | None = None) -> dict:  # fmt: skip
    """The settings an appended study adds: appended_to (the source's study file digest, None
    for a study never saved), appended_after (its draws per chain), pooled_sweeps and
    sweeps_run (per chain; as ``gpmsa.fit``'s), and accept_rate: each element's rate of both
    parts weighted by their sweeps (the source's ``settings["accept_rate"]`` over its sweeps
    run, ``accept_rate`` over ``n_iter``); none where the source records no rate or sweeps.
    ``renamed``: a sweep element's name -> its name in the source (``sweep_names``)."""
    settings = source.settings
    renamed = renamed or {}
    out = appended_counts(settings, source_digest(source),
                          int(source.draws["log_post"].shape[1]), n_iter)  # fmt: skip
    old, run = settings.get("accept_rate"), sweeps_run(settings)
    ok = (
        isinstance(old, dict)
        and accept_rate is not None
        and run is not None
        and set(old) == set(accept_rate)
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in old.values())
    )
    out["accept_rate"] = None if not ok else {
        k: float((old[renamed.get(k, k)] * run + r * n_iter) / (run + n_iter))
        for k, r in accept_rate.items()
    }  # fmt: skip
    return out
