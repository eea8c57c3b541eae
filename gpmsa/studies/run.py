"""``calibrate_study`` (the emulators fixed) and ``fit_study`` (emulators and calibration
jointly): several models whose calibration parameters are shared or hierarchical."""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from dataclasses import replace
from datetime import datetime, timezone

import numpy as np

from gpmsa._fp_state import underflow_as_zero
from gpmsa._version import library_versions
from gpmsa.calibration.calibrate import (
    CALIBRATION_FIXED,
    burn_message,
    calibration_fixed,
    calibration_held_native,
    calibration_problem,
    held_discrepancy_names,
    observation_fit,
)
from gpmsa.calibration.observations import (
    check_emulator,
    far_value,
    reduce,
    warn_if_outside,
)
from gpmsa.errors import GPMSAError, ReductionWarning, user_stacklevel
from gpmsa.fitting.continuation import appended_record, resumes_copies, source_ladders
from gpmsa.fitting.emulator import EMULATOR_PARAMS, Emulator, check_metadata
from gpmsa.fitting.fit import (
    N_KEEP,
    check_keep,
    check_point,
    fit_held_native,
    hold_fixed,
    point_estimate,
    sampled_convergence,
    thinning,
)
from gpmsa.limits import check_memory
from gpmsa.mcmc import level_moves, tempering, tuning
from gpmsa.mcmc.bounds import warn_at_bound
from gpmsa.mcmc.diagnostics import summarize, warn_unconverged
from gpmsa.mcmc.starts import check_init
from gpmsa.model.basis import discrepancy_kind, is_basis_list
from gpmsa.model.data import ObsData, SimData, check_flag, run_seed
from gpmsa.model.discrepancy import kept_bases, scale_record
from gpmsa.model.discrepancy import record as discrepancy_record
from gpmsa.model.far_values import far_run, joint_far_value, warn_far, warn_far_run
from gpmsa.model.priors import Priors
from gpmsa.model.problem import ORDER, fixed_record, prepare
from gpmsa.studies import continuation as cont
from gpmsa.studies.continuation import STEPS, WIDTHS_BY_CHAIN
from gpmsa.studies.hot import continued_copies, hot_record
from gpmsa.studies.layout import (
    HyperPriors,
    build_layout,
    check_hyper,
    check_labels,
    check_study_names,
    model_theta_priors,
)
from gpmsa.studies.record import DISCREPANCIES, discrepancy_arrays
from gpmsa.studies.sampler import StudyChains, held_elements, sample_study
from gpmsa.studies.study import (
    HELD_THETA,
    OBS_DIGESTS,
    OBS_LAYOUTS,
    Study,
    layout_of,
    theta_domains,
)


def _sequence(value, what: str) -> list:
    if isinstance(value, (str, bytes, np.ndarray, Emulator, SimData, ObsData)) or not isinstance(
        value, Sequence
    ):
        raise GPMSAError(f"{what} must be a list with one entry per model, got "
                         f"{type(value).__name__}")  # fmt: skip
    return list(value)


def _same_count(**lists) -> int:
    counts = {k: len(v) for k, v in lists.items()}
    if len(set(counts.values())) != 1:
        raise GPMSAError(f"mismatched numbers of models: {counts}")
    n = next(iter(counts.values()))
    if n < 1:
        raise GPMSAError("a study needs at least one model")
    return n


def _refuse_no_observations(label: str, x, y) -> None:
    """GPMSAError where model ``label``'s x_obs or y_obs (arrays, lists, tables) has no rows:
    a model without observations (an ObsData holds at least one; checked before the shape
    checks, whose message would not say so)."""
    for what, value in (("x_obs", x), ("y_obs", y)):
        if value is None or isinstance(value, ObsData):
            continue
        try:
            shape = np.shape(value)
        except (TypeError, ValueError):  # ragged: a list of experiments, not empty
            continue
        if len(shape) >= 1 and shape[0] == 0:
            raise GPMSAError(
                f"model {label!r} has no observations (its {what} holds no experiments: shape "
                f"{shape}); give every model at least one experiment, or leave model {label!r} "
                "out of the study"
            )


def _check_run(n_iter, n_burn, n_chains, hyper, what: str = "n_samples") -> HyperPriors:
    for name, val, low in ((what, n_iter, 2), ("n_chains", n_chains, 1)):
        if isinstance(val, bool) or not (isinstance(val, (int, np.integer)) and val >= low):
            raise GPMSAError(f"{name} must be an integer >= {low}, got {val!r}")
    if isinstance(n_burn, bool) or not (isinstance(n_burn, (int, np.integer))
                                        and 0 <= n_burn < n_iter - 1):  # fmt: skip
        raise GPMSAError(burn_message(n_burn, n_iter, what, 1000 if what == "n_samples" else None))
    if hyper is None:
        return HyperPriors()
    if not isinstance(hyper, HyperPriors):
        raise GPMSAError(f"hyper must be a gpmsa.HyperPriors, got {type(hyper).__name__}")
    return hyper


def _check_memory(problems, n_iter: int, n_chains: int, what: str,
                  append_to: Study | None = None, thin: int = 1) -> None:  # fmt: skip
    """Refuse (before sampling) a study whose stored sweeps (every sweep of every chain, kept
    twice while stacked) exceed the memory limit; appending to ``append_to`` at its step
    ``thin``, also the pooled draws a chain (its and the continuation's), held 1.5 times more
    (the parts and the pooled arrays), as ``gpmsa.fit`` counts an appended fit's."""
    per_sweep = sum(sum(int(np.size(p.init[n])) for n in p.sampled) for p in problems) + 4
    nbytes = 8.0 * 2.0 * per_sweep * n_iter * n_chains
    if append_to is not None:
        pooled = int(append_to.draws["log_post"].shape[1]) + int(n_iter) // thin
        nbytes += 8.0 * 1.5 * per_sweep * pooled * n_chains
        what += f" appending to {pooled} draws a chain"
    check_memory(nbytes, what)


def _check_tempering(temperatures, swap_every, n_iter, source, what: str, adapt_ladder=False,
                     tune=True, n_chains: int = 1):  # fmt: skip
    """The ladder (``tempering.ladder``; None: off), ``swap_every`` (None: 1) and
    ``adapt_ladder`` (``tempering.check_adapt``, with ``tune`` the run's) of a study's parallel
    tempering, checked (n_iter, ``what``, already is). A continuation (``source`` the study
    ``init``; else None) of a tempered study runs on at its ladder (each chain's, an
    (n_chains, K) array, where its chains adapted theirs) and swap interval unless
    ``temperatures=`` or ``swap_every=`` is given (``source_ladders``); GPMSAError naming
    ``tune=False`` with a tempered continuation that does not resume its hot copies (every copy
    is tuned while it warms up; ``gpmsa.fitting.continuation.resumes_copies``)."""
    temps, ladders = tempering.ladder(temperatures), None
    if temperatures is None and source is not None:  # (temperatures=1: plain)
        ladders, every = source_ladders(source.settings or {}, n_chains, "init=study")
        if ladders is not None:
            temps = tuple(float(t) for t in np.atleast_2d(ladders)[0])
            swap_every = every if swap_every is None else swap_every
    every = 1 if swap_every is None else swap_every
    every = tempering.check_swap_every(every, temps, int(n_iter), what)
    adapt = tempering.check_adapt(adapt_ladder, temps, tune)
    if ladders is not None and ladders.ndim == 2:  # each chain at its own (adapted) ladder
        temps = ladders
    out = {} if temps is None else {"temperatures": temps, "swap_every": every,
                                    **({"adapt_ladder": True} if adapt else {})}  # fmt: skip
    if (
        temps is not None
        and source is not None
        and not tune
        and not resumes_copies(source.settings or {}, out, n_chains, "init=study")
    ):
        raise GPMSAError(
            "tune=False with a tempered continuation (temperatures=, or init=study a tempered "
            "study) that does not resume its hot copies (at the source's ladder, which records "
            "them, settings 'hot_states'): every copy is tuned at its temperature (from the "
            "T = 1 copy's widths) while the copies warm up from the chain's last state, before "
            "any draw is kept; leave tune out, or tune=True, or pass temperatures=1 to "
            "continue without tempering"
        )
    return out


def _settings(chains: StudyChains, n_burn: int, t0: float, labels, **extra) -> dict:
    rate = chains.accept_rate.mean(axis=0)
    info = {
        k: v for k, v in chains.info.items() if k not in ("level_offsets", "hot")
    }  # `_level_offsets`, `hot_record`
    for key in ("swap_rate", "adapted_temperatures"):  # parallel tempering: as fit's settings
        if key in info:
            info = {**info, key: np.asarray(info[key]).tolist()}
    return {**info, "n_burn": int(n_burn), **extra,
            "accept_rate": {n: float(r) for n, r in zip(chains.names, rate, strict=True)},
            "step_widths": {n: float(w) for n, w in zip(chains.names, chains.widths[0],
                                                        strict=True)},
            **({WIDTHS_BY_CHAIN: {n: [float(w) for w in col] for n, col in
                                  zip(chains.names, chains.widths.T, strict=True)}}
               if chains.widths.shape[0] > 1 else {}),
            **hot_record(chains.info, chains.names, labels),
            "seconds": time.perf_counter() - t0,
            "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
            "versions": library_versions("numpy")}  # fmt: skip


def _level_offsets(chains: StudyChains, layout, models) -> dict:
    """The joint level moves' record (``chains.info["level_offsets"]``, unit scale) in native
    units, as ``gpmsa.calibrate``'s ``info["level_offsets"]`` (``level_moves.native_record``)
    with study element names: per categorical study element, its "levels" (native codes, its
    first model's: ``models``, the emulators or SimData), the "shifted" continuous elements (of
    every model that uses it) and per chain their conditional "modes" at each level; {} where
    no element made the move."""
    record = chains.info.get("level_offsets") or {}
    names = [el.name for el in layout.elements]
    lo, hi = np.array(layout.bounds, dtype=np.float64).reshape(-1, 2).T
    out = {}
    for e, rec in record.items():
        i, k = layout.elements[e].uses[0]
        levels = {e: models[i].levels[len(models[i].x_names) + k]}
        out.update(level_moves.native_record({"shifted": rec["shifted"], "offsets": {e: rec[
            "offsets"]}}, names, lo, hi, levels))  # fmt: skip
    return out


def _tune_rule(tune, init) -> bool | None:
    """``tune`` checked (None: decided by ``_continue``, else True)."""
    if tune is None:
        return None if isinstance(init, Study) else True
    return check_flag(tune, "tune")


def _continue(source: Study, problems, layout, hyper, n_chains: int, tune: bool | None,
              models: list[list[dict]], append: bool, orders=None, tempered: dict | None = None
              ) -> tuple[bool, dict, dict, dict[str, str]]:  # fmt: skip
    """A continuation of ``source``'s chains from ``models`` (per chain, each model's start):
    (tune, ``sample_study``'s continuation arguments, the settings it adds, each sweep
    element's name -> its name in ``source``). Untuned (``tune`` None where ``source`` records
    its chains' widths, or False), each chain runs on with its recorded widths and precision
    steps (a per-component element's its source component's: ``orders``, per model,
    ``continuation.member_orders``); tuned, from GPM/SA's widths (refused where it
    ``append``s: `continuation.refuse_tuning`). ``tempered`` (parallel tempering,
    ``_check_tempering``'s): where ``source`` records its hot copies and this runs at its
    ladder (``gpmsa.fitting.continuation.resumes_copies``), ``tune`` None or False resumes
    every copy where it stopped, untuned; else ``tune`` None tunes every copy at its
    temperature from the recorded widths (the copies warm up before any draw; appending
    too)."""
    tempered = tempered or {}
    starts = cont.chain_starts(source, models)
    names, there = cont.sweep_names(problems, layout, hyper, starts[0], orders)
    widths = None if tune is True else cont.continued_widths(source, there, n_chains)
    resume = (tune is not True and widths is not None
              and resumes_copies(source.settings, tempered, n_chains, "init=study"))  # fmt: skip
    if tune is None:  # tempered: every copy tuned while it warms up, unless each resumes
        tune = widths is None or (bool(tempered) and not resume)
    if tune and append and not tempered:
        cont.refuse_tuning()
    steps = None if tune else cont.continued_steps(source)
    extra = {"continued_from": cont.source_digest(source)}
    if steps is not None:
        extra[STEPS] = steps
    resumed = {"chain_starts": starts, "widths": widths, "prop_mh": steps}
    if resume:  # every hot copy where it stopped, with its widths
        resumed["hot_copies"] = continued_copies(
            source.settings, starts, problems, layout, hyper, there,
            orders or [None] * len(problems), len(tempering.chain_ladders(
                tempered["temperatures"], n_chains)[0]))  # fmt: skip
    return tune, resumed, extra, dict(zip(names, there, strict=True))


def _study_draws(chains: StudyChains, keep: slice, discrepancy: bool = False
                 ) -> dict[str, np.ndarray]:  # fmt: skip
    """The study's kept draws; with ``discrepancy`` also each model's betaV (C, N, p, G) and
    lamVz (C, N, G) as "betaV_j", "lamVz_j" (j: the model's index), where it has them.
    ``chains.members`` holds the held parameters too (``_with_held``)."""
    lam_os = np.stack([m["lamOs"][:, keep, 0] for m in chains.members], axis=2)
    out = {"theta": chains.theta[:, keep], "mu": chains.mu[:, keep], "lam": chains.lam[:, keep],
           "lamOs": lam_os, "log_post": chains.log_post[:, keep]}  # fmt: skip
    for j, m in enumerate(chains.members):
        if discrepancy and "lamVz" in m:
            beta, lam = discrepancy_arrays(j)
            out[beta], out[lam] = m["betaV"][:, keep], m["lamVz"][:, keep]
    return out


def _with_held(chains: StudyChains, problems, names, fixes) -> StudyChains:
    """``chains`` with each model's parameters of ``names`` that its problem holds whole
    (``fixes``: the models' ``fixed=``) as draws (C, N, *shape) at their value, beside the
    sampled ones; ``chains`` itself without ``fixed=``."""
    if all(f is None for f in fixes):
        return chains
    members = []
    lead = chains.log_post.shape
    for m, prob in zip(chains.members, problems, strict=True):
        extra = {k: np.tile(prob.init[k], (*lead, *([1] * prob.init[k].ndim)))
                 for k in names if k in prob.fixed and k not in m and k != "theta"}  # fmt: skip
        members.append({**m, **extra})
    return replace(chains, members=tuple(members))


def _held_names(problems, layout, fixes) -> list[str]:
    """The posterior names (``native_chains``') of what the models hold: the study elements
    and each model's lamOs, betaV and lamVz elements; [] without ``fixed=``."""
    if all(f is None for f in fixes):
        return []
    names = [layout.elements[e].name for e in sorted(held_elements(problems, layout))]
    for lab, prob in zip(layout.labels, problems, strict=True):
        masks = prob.held_masks(CALIBRATION_FIXED)
        if "lamOs" in masks:  # one element: held whole
            names.append(f"lamOs[{lab}]")
        names += [f"{k}[{lab}]" for k in held_discrepancy_names(prob, masks)]
    return names


def _per_model_fixed(fixed, labels: tuple[str, ...]) -> list:
    """Each model's ``fixed=`` from a study's ``fixed``: None (none), one dict (every model's)
    or a list or tuple with one entry (None or a dict) per model, as ``basis``; GPMSAError for
    a dict keyed by the study's ``labels`` (a per-model value by label, as ``priors`` takes
    one, would read as parameter names)."""
    n = len(labels)
    if isinstance(fixed, dict) and fixed and all(
        k in labels and k not in ORDER for k in fixed
    ):  # fmt: skip
        raise GPMSAError(
            f"fixed: a dict is every model's parameter -> value, and {list(fixed)} are the "
            "study's labels, not parameters; give a list with one entry (None or a dict) per "
            f"model, in the models' order {list(labels)}"
        )
    if fixed is None or isinstance(fixed, dict):
        return [fixed] * n
    if not isinstance(fixed, (list, tuple)):
        raise GPMSAError(
            "fixed must be None, a dict name -> value (every model's) or a list with one entry "
            f"(None or a dict) per model, got {type(fixed).__name__}"
        )
    if len(fixed) != n:
        raise GPMSAError(
            f"fixed has {len(fixed)} entries for {n} models: give one dict for every model, or "
            "a list with one entry (None or a dict) per model"
        )
    for k, f in enumerate(fixed):
        if f is not None and not isinstance(f, dict):
            raise GPMSAError(f"fixed[{k}] must be None or a dict name -> value, got "
                             f"{type(f).__name__}")  # fmt: skip
    return list(fixed)


def _per_model_basis(basis, n: int) -> list:
    """Each model's emulator basis from ``fit_study``'s ``basis``: None (every model's PCA), a
    numpy array (every model's), or a list or tuple with one entry (None or an array) per
    model."""
    if basis is None or isinstance(basis, np.ndarray):
        return [basis] * n
    if not isinstance(basis, (list, tuple)):
        raise GPMSAError(
            "basis must be None, a numpy array (every model's basis) or a list with one entry "
            f"(None or an array) per model, got {type(basis).__name__}"
        )
    if len(basis) != n:
        raise GPMSAError(
            f"basis has {len(basis)} entries for {n} models: give one numpy array for every "
            "model, or a list with one entry (None or an array) per model"
        )
    return list(basis)


def _per_model_value(value, labels: tuple[str, ...], what: str, single: bool) -> list:
    """Each model's value of a study's argument ``what``: ``value`` for every model where
    ``single``, else ``value`` a dict label -> entry naming every model once, or a list or
    tuple with one entry per model (in the models' order); GPMSAError naming ``what`` and the
    labels (an unknown or missing label, a wrong count)."""
    n = len(labels)
    if single:
        return [value] * n
    if isinstance(value, dict):
        unknown = [k for k in value if k not in labels]
        missing = [lab for lab in labels if lab not in value]
        if unknown or missing:
            wrong = f"names unknown model(s) {unknown}" if unknown else ""
            wrong += (" and " if unknown and missing else "") + (
                f"has no entry for model(s) {missing}" if missing else "")  # fmt: skip
            raise GPMSAError(
                f"{what} as a dict by label {wrong}: give one entry for each of the study's "
                f"labels {list(labels)} (None where a model takes the default)"
            )
        return [value[lab] for lab in labels]
    if len(value) != n:
        raise GPMSAError(
            f"{what} has {len(value)} entries for {n} models {list(labels)}: give one value "
            "for every model, a list with one entry per model (in the order of the models) "
            "or a dict label -> entry"
        )
    return list(value)


def _per_model_discrepancy(discrepancy, groups, labels: tuple[str, ...]) -> list[tuple]:
    """Each model's (basis, groups) from a study's ``discrepancy`` and ``discrepancy_groups``:
    one value for every model, or a list or tuple with one entry per model, or a dict by label
    (``_per_model_value``). A basis given as a list is read as the per-model list (one matrix
    for every model: a numpy array); groups as one list of integers are every model's."""
    n = len(labels)
    if not (discrepancy is None or isinstance(discrepancy, (str, np.ndarray, list, tuple, dict))):
        raise GPMSAError(
            "discrepancy must be None, 'constant', 'linear', a numpy array (every model's basis), "
            "a list with one of these per model or a dict of them by label, got "
            f"{type(discrepancy).__name__}"
        )
    if isinstance(discrepancy, (list, tuple)) and len(discrepancy) != n:
        raise GPMSAError(
            f"discrepancy has {len(discrepancy)} entries for {n} models {list(labels)}: give one "
            "value for every model, or a list with one entry (None, 'constant', 'linear' or an "
            "array) per model, or a dict by label"
            + (
                "; a model's per-experiment bases (a list) are its entry: [[D_0, D_1], ...]"
                if is_basis_list(discrepancy)
                else ""
            )  # fmt: skip
        )
    bases = _per_model_value(discrepancy, labels, "discrepancy",
                             not isinstance(discrepancy, (list, tuple, dict)))  # fmt: skip
    one = groups is None or isinstance(groups, np.ndarray) or (
        isinstance(groups, (list, tuple))
        and all(isinstance(g, int | np.integer) for g in groups)
    )  # fmt: skip
    if isinstance(groups, (list, tuple)) and not one and len(groups) != n:
        raise GPMSAError(
            f"discrepancy_groups has {len(groups)} entries for {n} models {list(labels)}: give "
            "one list of groups for every model, or a list with one entry (None or a list) per "
            "model, or a dict by label"
        )
    # anything else is every model's: check_groups names what is wrong with it
    per = _per_model_value(groups, labels, "discrepancy_groups",
                           one or not isinstance(groups, (list, tuple, dict)))  # fmt: skip
    return list(zip(bases, per, strict=True))


@underflow_as_zero
def calibrate_study(
    emulators, x_obs, y_obs=None, *, labels=None, shared=(), hierarchical=(),
    hyper: HyperPriors | None = None, n_samples: int = 5000, n_burn: int | None = None,
    tune: bool | None = None, seed=None, n_chains: int = 1, init: str | Study = "auto",
    tune_rounds: int = tuning.N_BURN, tune_levels: int = tuning.N_LEVELS,
    extrapolate: bool = False, progress: bool = False, n_jobs: int | None = None,
    executor=None, metadata: dict | None = None, discrepancy=None, discrepancy_groups=None,
    fixed=None, append: bool = False, temperatures=None, swap_every: int | None = None,
    adapt_ladder: bool = False,
) -> Study:  # fmt: skip
    """Calibrate several fitted emulators at once, their emulator parameters fixed (as
    ``gpmsa.calibrate`` does for one), with shared and/or hierarchical calibration parameters.

    Args:
        emulators: one ``gpmsa.Emulator`` per model; x_obs, y_obs: per model, its observations
            as ``gpmsa.calibrate`` takes them; or x_obs one ``gpmsa.ObsData`` per model and
            y_obs None (or a None entry for a model given an ObsData).
        labels: the models' labels (default model0, model1, ...), a list or tuple in the
            models' order.
        shared: parameter names (emulator t_names) that take one value in every model that has
            them (a list or tuple, as ``hierarchical``: a set, whose order changes between
            processes, or a dict, whose values would have no effect, is a GPMSAError).
            hierarchical: names whose per-model values are draws of
            Normal(mu, 1/lam) truncated to the parameter's range, mu and lam sampled too
            (``hyper``: their priors, ``gpmsa.HyperPriors()``: a uniform group sd; SEPIA's:
            ``HyperPriors.sepia()``; given without a hierarchical name, with a uniform sd
            prior's sd_max below 1e-3, or with sd_prior="gamma" and an sd_max, which only the
            uniform prior reads, a GPMSAError). Every other parameter is its model's.
            A categorical parameter (``t_categorical``) may be shared (the same levels in
            every model) or a model's own, not hierarchical; its level moves with the
            continuous parameters (``gpmsa.studies.sampler``, docs/models.md), and
            ``settings["level_offsets"]`` records the move as ``gpmsa.calibrate``'s
            ``info["level_offsets"]`` does, by study element names (`_level_offsets`).
        n_samples, n_burn, tune, seed, n_chains, init, tune_rounds, tune_levels, extrapolate,
            progress, n_jobs, executor: as ``gpmsa.calibrate`` (the generic numpy sweep);
            seed None (or a numpy Generator) draws one from fresh entropy (from the
            Generator), and the integer the study ran with is ``study.settings["seed"]``
            (``seed=that`` reruns it). n_burn None: 1000 (0 for a continuation); tune None:
            True (for a continuation: False where the study records its chains' widths).
        init: a start rule ("auto", ...), or a calibration ``Study`` of the same models, labels,
            shared and hierarchical names, observations, hyperpriors, fixed values,
            discrepancies (a basis whose columns are the source's up to their signs and order,
            each keeping its group, is the same) and number of chains (GPMSAError naming what
            differs), whose chains continue from their last kept draws with the step widths
            they ran with (``docs/models.md``, "Continuing a study"); settings
            "continued_from": its ``sha256``.
        append: with ``init`` a study, return its kept draws followed, chain by chain, by this
            continuation's every sweep (a calibration study keeps every sweep after burn-in),
            as ``gpmsa.fit``'s ``append``: diagnostics, convergence and posterior over the
            pooled chains; settings n_burn 0, "appended_to" (the source's ``sha256``),
            "appended_after" (its draws per chain), "pooled_sweeps", "sweeps_run" and
            "accept_rate" weighted by the parts' sweeps. Refused (naming the argument):
            ``init`` not a study, n_burn > 0, tuning (pass tune=False).
        metadata: a JSON-able dict saved with the study.
        discrepancy, discrepancy_groups: each model's discrepancy basis and its precision
            groups, as ``gpmsa.calibrate``'s (None, "constant", "linear" or an array; groups
            None or one integer per basis vector): one value for every model, or a list with
            one entry per model (``["constant", None]``), or a dict label -> entry naming every
            model once. A list is read as the per-model list:
            give one matrix for every model as a numpy array, and a model's per-experiment
            bases (``gpmsa.calibrate``'s list) as its entry (``[[D_0, D_1], None]``). The
            priors are each emulator's own (theta, lamOs, lamVz, betaV's: set per model with
            ``Emulator.with_calibration_priors``; the emulator's are its fit's, held).
        fixed: parameters held at known values, as ``gpmsa.calibrate``'s ``fixed=`` (theta
            elements by t_name or position, native units; lamOs; with a discrepancy betaV and
            lamVz, whole or by element): one dict for every model, or a list with one entry
            (None or a dict) per model (a dict by label is a GPMSAError naming the list form).
            A shared parameter held must be held at one value by
            every model that has it (one dict for all does so); a held hierarchical element
            stays in its group at its value. ``settings["fixed"]`` records each model's (as
            ``calibrate``'s ``info["fixed"]``).
        temperatures, swap_every: parallel tempering, as ``gpmsa.fit``'s (off by default, and
            then the draws are the plain sampler's, bit for bit): each chain runs a copy of the
            whole study per temperature (the models' likelihoods raised to 1/T, every prior and
            the hierarchy's untempered), each tuned at its temperature; neighbours propose to
            swap their states every ``swap_every`` (1, at most n_samples) sweeps, and only the
            T = 1 copy's draws are kept (about n times the time). ``settings`` record
            "temperatures", "swap_every", "swap_rate" (per chain, per neighbour pair) and
            each hot copy's last state and widths ("hot_states", "hot_step_widths").
            A continuation (``init`` a study) of a tempered study runs on at its ladder (each
            chain's where they adapted theirs) and ``swap_every`` unless given; at that
            ladder, without ``tune=True`` or ``adapt_ladder``, every copy resumes where it
            stopped, untuned; otherwise (no such record, another ladder) every copy starts
            from its chain's last kept state, tuned at its temperature before any draw
            (``tune=False`` refused; docs/models.md, "Parallel tempering").
        adapt_ladder: with ``temperatures`` (at least 3) and tuning, each chain adapts its
            ladder's temperatures between 1 and the hottest during tuning towards equal swap
            rates, then freezes it before the widths' tuning and the draws (an exact MCMC;
            ``gpmsa.mcmc.tempering.adapt_ladder``); ``settings["adapted_temperatures"]``
            (per chain) records it, "temperatures" the ladder it started from.

    Returns a ``Study``; ``study.posterior`` names each shared parameter by its name, every
    other by "NAME[LABEL]", each model's "lamOs[LABEL]" (and with a discrepancy its
    "betaV[LABEL]" and "lamVz[LABEL]", NAME as ``gpmsa.calibrate`` names it: "betaV[0][LABEL]"
    for several inputs, "lamVz[1][LABEL]" for several groups) and each hierarchical group's
    "NAME.mu", "NAME.sd" (native units) and "NAME.lam" (unit-scale precision).
    ``study.posterior.info["at_bound"]`` names each study element and group mean whose
    posterior piles up against a bound of its domain (``gpmsa.calibrate``'s rule,
    ``gpmsa.mcmc.bounds``; categorical and held ones not judged), and one
    ``gpmsa.AtBoundWarning`` names them (``fit_study`` likewise). GPMSAError
    names a bad input: mismatched numbers of models (or discrepancy entries), an unknown
    shared name, a shared or hierarchical parameter whose range differs between the models.

    >>> import numpy as np, gpmsa
    >>> t = np.linspace(0.1, 0.9, 12)[:, None]; x = np.tile([[0.0], [1.0]], (6, 1))
    >>> sim = gpmsa.SimData(x=x, t=t, y=(x + 2 * t), t_names=["E"])
    >>> prm = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
    >>> emu = gpmsa.Emulator.from_params(sim, prm)
    >>> study = gpmsa.calibrate_study([emu, emu], [[[0.5]], [[0.2]]], [[1.5], [1.2]],
    ...                               shared=["E"], n_samples=400, n_burn=100, seed=1)
    >>> study.posterior.names[:3]
    ('E', 'lamOs[model0]', 'lamOs[model1]')
    >>> 0.3 < study.posterior.mean("E") < 0.7
    True
    """
    emulators = _sequence(emulators, "emulators")
    x_obs = _sequence(x_obs, "x_obs")
    if y_obs is None:
        y_obs = [None] * len(x_obs)
        arrays = [k for k, x in enumerate(x_obs) if not isinstance(x, ObsData)]
        if arrays:
            raise GPMSAError(
                f"y_obs is required unless every x_obs entry is a gpmsa.ObsData; entry "
                f"{arrays[0]} is a {type(x_obs[arrays[0]]).__name__}"
            )
    y_obs = _sequence(y_obs, "y_obs")
    n = _same_count(emulators=emulators, x_obs=x_obs, y_obs=y_obs)
    labels = check_labels(labels, n)
    for lab, e, x, y in zip(labels, emulators, x_obs, y_obs, strict=True):  # errors name it
        _per_model(lab, check_emulator, e, categorical_theta=True)  # its level moves
        _refuse_no_observations(lab, x, y)
    continuing = isinstance(init, Study)
    append = cont.check_append(append, init, n_burn)
    n_burn = (0 if continuing else 1000) if n_burn is None else n_burn
    given_hyper = hyper is not None
    hyper = _check_run(n_samples, n_burn, n_chains, hyper)
    source = init if continuing else None  # a tempered one's ladder: the default
    tempered = _check_tempering(temperatures, swap_every, n_samples, source, "n_samples",
                                adapt_ladder, tune is not False, int(n_chains))  # fmt: skip
    if not continuing:
        check_init(init, int(n_chains), "gpmsa.load_study")
    seed = run_seed(seed)
    metadata = check_metadata(metadata)
    tune, progress = _tune_rule(tune, init), check_flag(progress, "progress")
    extrapolate = check_flag(extrapolate, "extrapolate")
    bases = _per_model_discrepancy(discrepancy, discrepancy_groups, labels)
    fixes = _per_model_fixed(fixed, labels)
    held = [_per_model(lab, calibration_fixed, e, f, b)
            for lab, e, f, (b, _) in zip(labels, emulators, fixes, bases, strict=True)]  # fmt: skip
    layout = layout_of(emulators, labels, shared, hierarchical)
    check_study_names(layout)
    check_hyper(hyper, given_hyper, layout, fresh=not continuing)
    t0 = time.perf_counter()
    models = list(zip(labels, emulators, x_obs, y_obs, strict=True))
    reduced, fits = [], []
    for (lab, e, x, y), (basis, _) in zip(models, bases, strict=True):
        with warnings.catch_warnings():
            if basis is not None:  # the reduction with its basis warns (as gpmsa.calibrate)
                warnings.simplefilter("ignore", ReductionWarning)
            reduced.append(_per_model(lab, reduce, e, x, y, extrapolate))
        fits.append(observation_fit(e, reduced[-1], [e.params]))  # as gpmsa.calibrate warns
        warn_if_outside(fits[-1], discrepancy=basis is not None, model=lab,
                        far=far_value(e, reduced[-1], fits[-1]))  # fmt: skip
    problems = [_per_model(lab, calibration_problem, e, x, y, extrapolate=extrapolate,
                           reduced=None if basis is not None else r, discrepancy=basis,
                           discrepancy_groups=groups, fixed=h,
                           fit=None if basis is not None else f)
                for (lab, e, x, y), r, f, (basis, groups), h in zip(
                    models, reduced, fits, bases, held, strict=True)]  # fmt: skip
    problems = [
        p if p.theta_levels is None else p.with_init({"theta": p.snap_theta(p.init["theta"])})
        for p in problems
    ]  # a categorical theta: at a level
    natives = [calibration_held_native(e, f) for e, f in zip(emulators, fixes, strict=True)]
    record: dict = {}  # what the study records of its models, before any sampling
    _record_fixed(record, labels, problems, layout, fixes, natives)
    record[OBS_DIGESTS] = {lab: r.values_sha256 for lab, r in zip(labels, reduced, strict=True)}
    record[OBS_LAYOUTS] = {lab: r.layout_sha256 for lab, r in zip(labels, reduced, strict=True)}
    recorded = {lab: {"discrepancy": discrepancy_kind(basis), **discrepancy_record(prob.obs)}
                for lab, (basis, _), prob in zip(labels, bases, problems, strict=True)
                if basis is not None}  # fmt: skip
    if recorded:  # full_prediction(posterior=member_posterior(LABEL)) refuses another basis
        record[DISCREPANCIES] = recorded
    resumed, extra, thin, renamed = {}, {}, 1, {}  # thin: an appended study's step (all: 1)
    if continuing:
        old = init.settings
        obs_of = {lab: prob.obs for lab, prob in zip(labels, problems, strict=True)}
        cont.check_source(
            init, "calibration", layout, hyper, int(n_chains),
            emulators=([e.model_sha256 for e in init.members],
                       [e.model_sha256 for e in emulators]),
            # a file from before these records (6947c74) says nothing of its observations:
            # not compared, as fit(init=emulator) takes a file without obs_sha256
            observations=([old.get(k, record[k]) for k in (OBS_DIGESTS, OBS_LAYOUTS)],
                          [record[OBS_DIGESTS], record[OBS_LAYOUTS]]),
            **{"fixed values": ([old.get(k) for k in ("fixed", HELD_THETA)],
                                [record.get(k) for k in ("fixed", HELD_THETA)]),
               "discrepancy": (old.get(DISCREPANCIES), cont.same_discrepancies(
                   old.get(DISCREPANCIES), record.get(DISCREPANCIES), obs_of))},
        )  # fmt: skip
        thin = cont.appended_thin(init, int(n_samples), int(n_chains)) if append else 1
        starts = cont.calibration_starts(init, problems)
        tune, resumed, extra, renamed = _continue(init, problems, layout, hyper, int(n_chains),
                                                  tune, starts, append,
                                                  tempered=tempered)  # fmt: skip
    _check_memory(problems, n_samples, n_chains, f"calibrate_study(n_samples={n_samples}, "
                  f"n_chains={n_chains})", init if append else None, thin)  # fmt: skip
    chains = sample_study(
        problems, layout, hyper, n_iter=int(n_samples), n_chains=int(n_chains), tune=tune,
        seed=seed, init="auto" if continuing else init, tune_rounds=tune_rounds,
        tune_levels=tune_levels, progress=progress, n_jobs=n_jobs, executor=executor, **resumed,
        **tempered,
    )  # fmt: skip
    chains = _with_held(chains, problems, ("lamOs", "betaV", "lamVz"), fixes)
    settings = _settings(chains, n_burn, t0, labels, n_samples=int(n_samples), **extra)
    settings = tempering.recorded_ladders(settings, init.settings if continuing else {})
    settings.update(record)
    moves = _level_offsets(chains, layout, emulators)
    if moves:  # a categorical parameter's joint level move (other studies as before)
        settings["level_offsets"] = moves
    keep = slice(thin - 1, None, thin) if append else slice(int(n_burn), None)
    draws = _study_draws(chains, keep, discrepancy=True)
    if append:  # the source's draws, then every sweep at its step (1)
        draws = cont.pool_study_draws(init, draws)
        settings.update(cont.appended_settings(init, int(n_samples), settings["accept_rate"],
                                               renamed))  # fmt: skip
    study = Study("calibration", emulators, layout, hyper, draws, settings, metadata)
    warn_unconverged(study.convergence, "gpmsa.calibrate_study", length="n_samples")
    _warn_at_bound(study, "gpmsa.calibrate_study")
    return study


def _warn_at_bound(study: Study, where: str) -> None:
    """One ``AtBoundWarning`` naming the study's parameters that its posterior's
    ``info["at_bound"]`` flags (``Study``: each element, each hierarchical group's mean; held
    and categorical ones not judged), as ``gpmsa.calibrate`` warns; none where none is."""
    post = study.posterior
    warn_at_bound(post.info["at_bound"], post.samples, *theta_domains(study.layout), where,
                  "study.posterior.info['at_bound']")  # fmt: skip


def _record_fixed(settings: dict, labels, problems, layout, fixes, natives,
                  emulator=False) -> None:  # fmt: skip
    """With ``fixed=``: ``settings["fixed"]`` label -> the model's held parameters (as
    ``calibrate``'s ``info["fixed"]``; ``emulator``: the emulator's parameters too, as
    ``fit``'s ``settings["fixed"]``), ``settings["held"]`` the posterior names held (not
    judged for convergence) and, where theta elements are held, ``settings[HELD_THETA]``
    each one's native value as given (``natives``: per model, position -> value; a shared
    element its first model's), which the posterior reports exactly (``Study``)."""
    if all(f is None for f in fixes):
        return
    out = {}
    for lab, prob, f in zip(labels, problems, fixes, strict=True):
        if f is None:
            continue
        # a calibration holds every emulator parameter: record only those the user named
        named = {k for k in prob.held_masks() if k not in EMULATOR_PARAMS or (emulator and k in f)}
        out[lab] = fixed_record(prob, named)
    settings["fixed"] = out
    settings["held"] = _held_names(problems, layout, fixes)
    theta = {}
    for i, values in enumerate(natives):
        for k, v in values.items():
            theta.setdefault(layout.elements[layout.index[i][k]].name, v)
    if theta:
        settings[HELD_THETA] = theta


def _check_priors(priors, q: int) -> None:
    """GPMSAError naming ``priors`` where a model's (with ``q`` calibration parameters) is not
    a ``gpmsa.Priors`` (or None), or gives per-element theta priors for another q."""
    if priors is None:
        return
    if not isinstance(priors, Priors):
        raise GPMSAError(f"priors must be a gpmsa.Priors or None, got {priors!r:.80}")
    try:
        priors.theta_moments(q)
    except GPMSAError as exc:
        raise GPMSAError(f"priors: {exc}") from None


def _refuse_group_priors(layout) -> None:
    """GPMSAError where ``fit_study``'s ``priors`` give a hierarchical parameter of a model a
    theta prior other than ``Priors``' default: its elements take their group's truncated
    normal instead, so it would have no effect (the layout records each element's model
    prior)."""
    default = tuple(float(v) for v in Priors().theta_prior(0))
    for el in layout.elements:
        mean, sd = (float(v) for v in el.prior)
        if el.group < 0 or (mean, sd) == default:
            continue
        raise GPMSAError(
            f"model {layout.labels[el.uses[0][0]]!r}: priors gives hierarchical parameter "
            f"{el.param!r} the theta prior (mean {mean:g}, sd {sd:g}), which would have no "
            f"effect: each model's {el.param} takes its group's prior Normal(mu, 1/lam) instead "
            "(mu's prior: hyper=gpmsa.HyperPriors(mu_mean=, mu_sd=)); leave it at the default "
            f"({default[0]:g}, {default[1]:g}) (per element: Priors(theta_mean=[...], "
            f"theta_sd=[...]) with {default[0]:g} and {default[1]:g} at {el.param}'s position), "
            f"or make {el.param!r} shared or each model's own"
        )


def _per_model(label: str, make, *args, **kwargs):
    """``make(*args, **kwargs)`` for the model ``label``; its GPMSAError and its warnings name
    that model (so that two models' alike warnings both show, and say which)."""
    caught: list[warnings.WarningMessage] = []
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            return make(*args, **kwargs)
    except GPMSAError as exc:
        try:
            named = type(exc)(f"model {label!r}: {exc}")  # the same class, where it can be
        except TypeError:
            named = GPMSAError(f"model {label!r}: {exc}")
        raise named from exc
    finally:
        for w in caught:  # the caller's filters apply to them here
            warnings.warn(f"model {label!r}: {w.message}", w.category,
                          stacklevel=user_stacklevel())  # fmt: skip


def _member_convergence(problem, summary: dict, counts: tuple[int, int]):
    """A ``fit_study`` model's convergence records over its kept draws (``counts``: chains,
    draws a chain): (every parameter it sampled, as ``gpmsa.fit`` records it; those but theta
    and lamOs, which the study's own record judges under the study's names); one chain by its
    split R-hat, as ``gpmsa.fit``."""
    return (sampled_convergence(problem, summary, *counts),
            sampled_convergence(problem, summary, *counts, skip=("theta", "lamOs")))  # fmt: skip


@underflow_as_zero
def fit_study(
    sims, obs, *, labels=None, shared=(), hierarchical=(), hyper: HyperPriors | None = None,
    n_iter: int = 30_000, n_burn: int | None = None, n_keep: int | None = None,
    point: str = "mean",
    tune: bool | None = None, seed=None, n_chains: int = 1, init: str | Study = "auto",
    priors: Priors | Sequence | dict | None = None,
    n_pc: int | float | Sequence | dict | None = None, basis=None, discrepancy=None,
    discrepancy_groups=None, tune_rounds: int = tuning.N_BURN, tune_levels: int = tuning.N_LEVELS,
    progress: bool = False, n_jobs: int | None = None, executor=None,
    metadata: dict | None = None, fixed=None, append: bool = False, temperatures=None,
    swap_every: int | None = None, adapt_ladder: bool = False,
) -> Study:  # fmt: skip
    """Fit several GPM/SA models jointly (each its emulator and observations, as ``gpmsa.fit``
    with ``obs``) whose calibration parameters are shared and/or hierarchical (SEPIA's shared
    and hierarchical theta models). Each model's own parameters are updated within it; a study
    theta element is accepted on the sum of its models' log posteriors.

    Args:
        sims, obs: per model, its ``gpmsa.SimData`` and ``gpmsa.ObsData``.
        labels, shared, hierarchical, hyper: as ``calibrate_study``.
        n_iter, n_burn, n_keep, point, tune, seed, n_chains, init, tune_rounds, tune_levels,
            progress, n_jobs, executor: as ``gpmsa.fit``; the seed
            the study ran with is ``study.settings["seed"]`` and each model's
            ``settings["seed"]``. n_burn None: n_iter // 5 (0 for a continuation); tune None:
            True (for a continuation: False where the study records its chains' widths);
            n_keep None: 1,000 (an appended study's: the draws its step keeps).
            init: a start rule, or a fit ``Study`` to continue, as ``calibrate_study``'s (each
            model's emulator parameters too; its models' checks are ``gpmsa.fit``'s for
            ``init=emulator``, naming the model).
        append: with ``init`` a study, as ``calibrate_study``'s: the study's draws and each
            member's retained and calibration draws are the source's followed, chain by chain,
            by the continuation's sweeps thin, 2 thin, ... (``thin`` the source's
            ``settings["thin"]``, as ``gpmsa.fit``'s ``append``); each member's settings
            record its own source member (``gpmsa.fit``'s appended settings). Also refused: an
            n_keep other than the n_chains x (n_iter // thin) draws that step keeps.
        priors, n_pc, discrepancy, discrepancy_groups: as ``gpmsa.fit``'s, each one value for
            every model, or per model (SEPIA builds each model with its own): a list or tuple
            with one entry per model (in the order of ``sims``) or a dict label -> entry naming
            every model once. A per-model ``priors`` entry (None: ``gpmsa.Priors()``) may give
            per-element theta priors for its own q (in its t_names' order); a shared parameter's
            prior must agree between its models (by name, wherever it sits in each model's
            theta), and a hierarchical one's is the default (its group's prior replaces it: any
            other would have no effect, a GPMSAError). ``discrepancy`` and its groups are read
            as ``calibrate_study``'s (a list is the per-model list; a model's per-experiment
            bases are its entry). One ``n_pc`` sizes
            the PCA of the models without a ``basis``; a per-model one is each model's (None
            with a basis). Each member records its own (its ``priors``, settings "n_pc",
            "discrepancy"); a continuation (``init``) with other ones is refused naming the
            model. GPMSAError names the argument (and the model): a wrong number of entries, an
            unknown or missing label, an entry of another type or for another q.
        basis: as ``gpmsa.fit``'s, a numpy array for every model or a list with one entry
            (None: the model's PCA, as ``n_pc`` says) per model.
        metadata: a JSON-able dict saved with the study.
        fixed: parameters held at known values, as ``gpmsa.fit``'s ``fixed=`` (the emulator's
            too; theta by t_name or position, native units), whole or by element: one dict for
            every model, or a list with one entry (None or a dict) per model. A shared
            parameter held must be held at one value by every model that has it; each model's
            ``settings["fixed"]`` records its own (as ``fit``'s), ``study.settings["fixed"]``
            all of them.
        temperatures, swap_every: parallel tempering, as ``calibrate_study``'s (each copy a
            whole study, its emulators' parameters too; at most n_iter between swap rounds);
            each member's settings record them too, with the study's swap rates.
        adapt_ladder: the adaptive ladder, as ``calibrate_study``'s (each member's settings
            record the study's "adapted_temperatures").

    A categorical parameter's joint level move is recorded as ``calibrate_study`` records it
    (``settings["level_offsets"]``), and in each member's settings under its own t_name (as
    ``gpmsa.fit``'s; the shifted elements named as the study names them).

    Returns a ``Study`` of kind "fit": ``study.members`` are the models' fitted emulators (their
    ``calibration`` holds the model's theta draws), ``study.posterior`` as ``calibrate_study``.
    With several chains each member's ``convergence`` judges every parameter its model sampled
    over its retained draws (thinned to n_keep, as the study's record;
    ``gpmsa.fit``'s judges every sweep after burn-in), and a ``gpmsa.ConvergenceWarning`` naming
    the model lists its flagged emulator (and discrepancy) elements; theta and lamOs are judged
    by the study's record and warning, under the study's names.

    >>> import numpy as np, gpmsa
    >>> t = np.linspace(0.1, 0.9, 12)[:, None]; x = np.tile([[0.0], [1.0]], (6, 1))
    >>> sim = gpmsa.SimData(x=x, t=t, y=(x + 2 * t), t_names=["E"])
    >>> obs = [gpmsa.ObsData(x=[[0.5]], y=[[1.5]]), gpmsa.ObsData(x=[[0.2]], y=[[1.2]])]
    >>> study = gpmsa.fit_study([sim, sim], obs, shared=["E"], n_iter=300, seed=2,
    ...                         tune_rounds=5)
    >>> [e.calibration["theta"].shape for e in study.members]
    [(240, 1), (240, 1)]
    """
    sims, obs = _sequence(sims, "sims"), _sequence(obs, "obs")
    n = _same_count(sims=sims, obs=obs)
    for k, s in enumerate(sims):
        if not isinstance(s, SimData):
            raise GPMSAError(f"sims must hold one gpmsa.SimData per model, got "
                             f"{type(s).__name__} (model {k})")  # fmt: skip
    for o in obs:
        if not isinstance(o, ObsData):
            raise GPMSAError(f"obs must hold one gpmsa.ObsData per model, got {type(o).__name__}")
    continuing = isinstance(init, Study)
    append = cont.check_append(append, init, n_burn)
    if n_burn is None and isinstance(n_iter, int | np.integer):
        n_burn = 0 if continuing else n_iter // 5
    given_hyper = hyper is not None
    hyper = _check_run(n_iter, n_burn, n_chains, hyper, "n_iter")
    source = init if continuing else None  # a tempered one's ladder: the default
    tempered = _check_tempering(temperatures, swap_every, n_iter, source, "n_iter", adapt_ladder,
                                tune is not False, int(n_chains))  # fmt: skip
    if not continuing:
        check_init(init, int(n_chains), "gpmsa.load_study")
    seed = run_seed(seed)
    check_point(point)
    given_keep = n_keep
    n_keep = check_keep(N_KEEP if n_keep is None else n_keep, n_chains)
    metadata = check_metadata(metadata)
    tune, progress = _tune_rule(tune, init), check_flag(progress, "progress")
    labels = check_labels(labels, n)
    bases = _per_model_basis(basis, n)
    fixes = _per_model_fixed(fixed, labels)
    per_pc = isinstance(n_pc, (list, tuple, dict))
    pcs = _per_model_value(n_pc, labels, "n_pc", not per_pc)
    if not per_pc:  # one n_pc: the PCA's of the models without a basis
        pcs = [n_pc if k is None or all(b is not None for b in bases) else None for k in bases]
    pris = _per_model_value(priors, labels, "priors", not isinstance(priors, (list, tuple, dict)))
    discs = _per_model_discrepancy(discrepancy, discrepancy_groups, labels)
    for lab, pri, s in zip(labels, pris, sims, strict=True):  # before the models' PCA
        _per_model(lab, _check_priors, pri, len(s.t_names))
    preps = [_per_model(lab, prepare, s, o, priors=pri, n_pc=pc, discrepancy=d,
                        discrepancy_groups=g, basis=k)
             for lab, s, o, k, pc, pri, (d, g) in zip(labels, sims, obs, bases, pcs, pris, discs,
                                                      strict=True)]  # fmt: skip
    layout = build_layout(
        labels, [tuple(s.t_names) for s in sims],
        [(p.standardizer.t_min, p.standardizer.t_max) for p in preps],
        [model_theta_priors(p.problem.priors, p.problem.q) for p in preps],
        shared, hierarchical,
    )  # fmt: skip
    check_study_names(layout)
    check_hyper(hyper, given_hyper, layout, fresh=not continuing)
    if not continuing:  # a continuation takes its source's priors as they are
        _refuse_group_priors(layout)
    problems = [p.problem if f is None else _per_model(lab, hold_fixed, p.problem, f,
                                                       p.standardizer, s.t_names)
                for lab, p, s, f in zip(labels, preps, sims, fixes, strict=True)]  # fmt: skip
    t0 = time.perf_counter()
    natives = [fit_held_native(p, f, s.t_names)
               for p, f, s in zip(problems, fixes, sims, strict=True)]  # fmt: skip
    record: dict = {}
    _record_fixed(record, labels, problems, layout, fixes, natives, emulator=True)
    resumed, extra, renamed, orders = {}, {}, {}, [None] * n
    if continuing:
        cont.check_source(
            init, "fit", layout, hyper, int(n_chains),
            **{"fixed values": ([init.settings.get(k) for k in ("fixed", HELD_THETA)],
                                [record.get(k) for k in ("fixed", HELD_THETA)])},
        )  # fmt: skip
        if append:
            thin = cont.appended_thin(init, int(n_iter), int(n_chains), given_keep)
        models = cont.fit_starts(init, problems, preps, obs, int(n_chains))
        orders = cont.member_orders(init, problems)  # K's columns among each member's
        tune, resumed, extra, renamed = _continue(init, problems, layout, hyper, int(n_chains),
                                                  tune, models, append, orders,
                                                  tempered=tempered)  # fmt: skip
    _check_memory(problems, n_iter, n_chains, f"fit_study(n_iter={n_iter}, n_chains={n_chains})",
                  init if append else None, thin if append else 1)  # fmt: skip
    for lab, sim, ob, prep, (d, _) in zip(labels, sims, obs, preps, discs, strict=True):
        outlier = far_run(sim, prep.standardizer.grid)  # before the sampling
        if outlier is not None:
            warn_far_run(outlier, user_stacklevel(), model=lab)
        far = joint_far_value(sim, ob, prep.standardizer)
        if far is not None:
            warn_far(far, user_stacklevel(), model=lab, discrepancy=d is not None)
    chains = sample_study(
        problems, layout, hyper, n_iter=int(n_iter), n_chains=int(n_chains), tune=tune,
        seed=seed, init="auto" if continuing else init, tune_rounds=tune_rounds,
        tune_levels=tune_levels, progress=progress, n_jobs=n_jobs, executor=executor, **resumed,
        **tempered,
    )  # fmt: skip
    chains = _with_held(chains, problems, ORDER, fixes)
    if not append:
        thin = thinning(int(n_chains), int(n_iter - n_burn), n_keep)
    keep = slice(thin - 1, None, thin) if append else slice(int(n_burn), None, thin)
    settings = _settings(
        chains, n_burn, t0, labels, n_iter=int(n_iter), thin=thin, point=point, **extra
    )
    settings = tempering.recorded_ladders(settings, init.settings if continuing else {})
    settings.update(record)
    moves = _level_offsets(chains, layout, sims)
    if moves:  # a categorical parameter's joint level move (other studies as before)
        settings["level_offsets"] = moves
    draws = _study_draws(chains, keep)
    if append:  # the source's draws, then the continuation's at its step
        draws = cont.pool_study_draws(init, draws)
        settings.update(cont.appended_settings(init, int(n_iter), settings["accept_rate"],
                                               renamed))  # fmt: skip
    lp = draws["log_post"].reshape(-1)
    members = []
    for i, (sim, prep) in enumerate(zip(sims, preps, strict=True)):
        post = {k: v[:, keep] for k, v in chains.members[i].items()}
        if append:
            post = cont.pool_member(init.members[i], post, orders[i])
        flat = {k: v.reshape(v.shape[0] * v.shape[1], *v.shape[2:]) for k, v in post.items()}
        theta = draws["theta"][:, :, list(layout.index[i])]
        flat["theta"] = theta.reshape(-1, theta.shape[2])
        params = point_estimate(flat, lp, point)
        cal = {k: v for k, v in flat.items() if k not in EMULATOR_PARAMS}
        cal["theta_native"] = prep.standardizer.t_from_unit(cal["theta"])
        for k, lv in enumerate(problems[i].theta_levels or ()):
            if lv is not None:  # categorical draws: exactly the level codes (as gpmsa.fit)
                cal["theta_native"][:, k] = np.round(cal["theta_native"][:, k])
        for k, v in natives[i].items():
            cal["theta_native"][:, k] = v  # exactly the value given (as gpmsa.fit)
        emu_settings = {"n_iter": int(n_iter), "n_burn": int(n_burn), "thin": thin,
                        "n_chains": int(n_chains), "tune": bool(tune), "backend": "numpy",
                        "seed": seed, "point": point, "n_pc": int(prep.K.shape[1]),
                        "basis": "pca" if bases[i] is None else "given",
                        "joint_obs": True, "discrepancy": discrepancy_kind(discs[i][0]),
                        "obs_lengths": [int(e.size) for e in obs[i].experiments],
                        "obs_sha256": obs[i].digest(),
                        "study": {"label": labels[i], "shared": list(layout.shared),
                                  "hierarchical": list(layout.groups)},  # as read, once
                        "versions": settings["versions"]}  # fmt: skip
        if discs[i][0] is not None:  # full_prediction refuses another basis
            source = (init.members[i].settings or {}) if continuing else None  # its scale
            emu_settings.update(discrepancy_record(prep.problem.obs),
                                **scale_record(discs[i][0], source))  # fmt: skip
        if fixes[i] is not None:  # as gpmsa.fit records it (continuations compare it)
            emu_settings["fixed"] = fixed_record(problems[i])
        own = {t: moves[layout.elements[layout.index[i][k]].name]
               for k, t in enumerate(sim.t_names)
               if layout.elements[layout.index[i][k]].name in moves}  # fmt: skip
        if own:  # as gpmsa.fit records it, by its t_name (the shifted: study elements)
            emu_settings["level_offsets"] = own
        if tempered:  # as gpmsa.fit(..., temperatures=) records it (the study's swaps)
            emu_settings.update({k: settings[k] for k in ("temperatures", "swap_every",
                                                          "swap_rate", "adapt_ladder",
                                                          "adapted_temperatures")
                                 if k in settings})  # fmt: skip
        if continuing:  # as gpmsa.fit(..., init=the source member) records it
            emu_settings["continued_from"] = init.members[i].model_sha256
        if append:  # as gpmsa.fit(..., init=the source member, append=True) records it
            emu_settings.update(appended_record(init.members[i], int(n_iter), int(n_chains)))
        summary = summarize({**post, "theta": theta})
        records = _member_convergence(problems[i], summary, theta.shape[:2])
        members.append(Emulator._from_prepared(
            sim, prep, params, draws={k: flat[k] for k in EMULATOR_PARAMS}, log_post=lp,
            settings=emu_settings, diagnostics=summary, calibration=cal,
            convergence=records[0], discrepancy_bases=kept_bases(prep.problem.obs, discs[i][0]),
        ))  # fmt: skip
        # its emulator's (and discrepancy's) elements
        warn_unconverged(records[1], f"gpmsa.fit_study (model {labels[i]!r})")
    study = Study("fit", members, layout, hyper, draws, settings, metadata)
    warn_unconverged(study.convergence, "gpmsa.fit_study")
    _warn_at_bound(study, "gpmsa.fit_study")
    return study
