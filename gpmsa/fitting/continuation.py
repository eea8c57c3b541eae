"""Continuing a fit's chains (``gpmsa.fit(..., init=emulator)``): where each chain starts, its
step widths and precision steps, the checks that the model is the same, and ``append=True``,
which pools the source's retained draws with the continuation's (SEPIA's second ``do_mcmc``)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from gpmsa.errors import GPMSAError, numbers_text
from gpmsa.fitting.emulator import EMULATOR_PARAMS, Emulator
from gpmsa.fitting.validation import HOT_RECORD
from gpmsa.mcmc import tempering
from gpmsa.mcmc.sampler import check_hot_copies, check_step_widths
from gpmsa.model.basis import reordered_basis
from gpmsa.model.data import ObsData, check_flag
from gpmsa.model.discrepancy import record as discrepancy_record
from gpmsa.model.priors import Priors
from gpmsa.model.problem import Problem, fixed_record


def continued_starts(
    emulator: Emulator, problem: Problem, K: np.ndarray, obs: ObsData | None, n_chains: int
) -> dict[str, np.ndarray]:
    """Each chain's start at its last kept draw in ``emulator`` (a fit of the same data, and
    observations for a joint fit, with ``n_chains`` chains): name -> (n_chains, *shape), for a
    backend's ``init``. Its chains continue where they stopped being recorded (a draw of each
    chain, not a fresh dispersed start): a fit that warned of R-hat or ESS runs on without
    starting over. A basis K or discrepancy basis D whose columns are the source's up to their
    signs and order is the same model (``component_order``, ``reordered_basis``): the starts
    of the per-component parameters (betaU's columns, lamUz, lamWs) follow K's columns.
    GPMSAError naming what differs."""
    _has_draws(emulator)
    _chains_of(emulator, n_chains)
    settings = emulator.settings or {}
    same = (emulator.x_unit.shape == problem.x_sim.shape and emulator.K.shape == K.shape
            and np.array_equal(emulator.x_unit, problem.x_sim)
            and np.array_equal(emulator.t_unit, problem.t_sim))  # fmt: skip
    order = component_order(emulator, problem) if same else None
    if order is None:
        raise GPMSAError(
            "init=emulator was fitted to other simulation runs (or another n_pc or basis)"
        )
    cal = emulator.calibration or {}
    if (obs is None) != (not cal):
        raise GPMSAError(
            "init=emulator is a joint fit: pass its observations (obs=)" if cal else
            "init=emulator is a simulator-only fit; a joint fit (obs=) starts its own chains"
        )  # fmt: skip
    if obs is not None and settings.get("obs_sha256") not in (None, obs.digest()):
        raise GPMSAError("init=emulator was fitted jointly with other observations")
    differs, detail = _model_differences(emulator, problem, order)
    if differs:
        raise GPMSAError(
            f"init=emulator was another model: its {', '.join(differs)} differ from this "
            f"fit's{detail}; continue it with the same settings, or start afresh"
        )
    per = emulator.log_post.size // n_chains
    last = np.arange(1, n_chains + 1) * per - 1  # kept draws are stored chain after chain
    out = {}
    for name, init in problem.init.items():
        source = emulator.draws if name in EMULATOR_PARAMS else cal
        if name not in source or np.shape(source[name])[1:] != init.shape:
            raise GPMSAError(
                f"init=emulator has no {name} of shape {init.shape} (another discrepancy basis, "
                "groups or model?)"
            )
        out[name] = np.array(reordered(name, source[name], order)[last], dtype=np.float64)
    if "theta" in out:
        _at_levels(problem, out["theta"])
    return out


def _at_levels(problem: Problem, theta) -> None:
    """Each categorical element of the unit ``theta`` (..., q) that a float32 fit (torch
    ``dtype="float32"``) held at a level rounded to float32 put back on that level, in place
    (the prior has mass at the levels alone); other values left for the checks to name."""
    for k, lv in enumerate(problem.theta_levels or ()):
        for level in () if lv is None else np.asarray(lv, dtype=np.float64):
            col = theta[..., k]
            col[np.float32(col) == np.float32(level)] = level


def check_same_scales(emulator: Emulator, data, standardizer) -> None:
    """GPMSAError naming each input whose unit domain, or the output scale, differs between
    ``emulator``'s fit and this one (``SimData(x_range=, t_range=, y_scale=, y_mean=,
    y_sd=)``) where the runs are the same (their outputs equal): they then sit at other unit
    values, so the chains cannot continue. Other runs are left to `continued_starts` to name."""
    y = np.asarray(data.y, dtype=float)
    if emulator.y.shape != y.shape or not np.array_equal(emulator.y, y):
        return
    old, new = emulator.standardizer, standardizer
    names = (*emulator.x_names, *emulator.t_names)
    ends = [np.concatenate([s.x_min, s.t_min, s.x_max, s.t_max]) for s in (old, new)]
    d = len(names)
    differs = [
        "{}: [{}, {}] in init=emulator's fit, [{}, {}] here".format(
            n, *numbers_text(ends[0][k], ends[0][d + k], ends[1][k], ends[1][d + k]))
        for k, n in enumerate(names)
        if ends[0][k] != ends[1][k] or ends[0][d + k] != ends[1][d + k]
    ]  # fmt: skip
    scale = {True: "'columnwise'", False: "'scalar'"}
    given = set(old.y_given) | set(new.y_given)  # else both the runs' own: the same
    if "y_mean" in given and not np.array_equal(old.y_mean, new.y_mean):
        was, now = _given(old, new, "y_mean")
        differs.append(f"y_mean: {was} in init=emulator's fit, {now} here")
    if "y_sd" in given:
        if not np.array_equal(old.y_sd, new.y_sd):
            was, now = _given(old, new, "y_sd")
            differs.append(f"y_sd: {was} in init=emulator's fit, {now} here")
    elif old.columnwise != new.columnwise:
        differs.append(f"y_scale: {scale[old.columnwise]} in init=emulator's fit, "
                       f"{scale[new.columnwise]} here")  # fmt: skip
    if differs:
        raise GPMSAError(
            "init=emulator mapped the same runs onto other unit values (SimData's x_range, "
            f"t_range, y_scale, y_mean or y_sd): {'; '.join(differs)}; give its fit's, or start "
            "afresh"
        )


def _given(old, new, name: str) -> tuple[str, str]:
    """Two Standardizers' ``name`` ("y_mean" or "y_sd") for a message: each one's value(s)
    (the first three; ``numbers_text``: as many digits as tell the two apart), and whether the
    user gave it or it is the runs' own."""
    values = [np.ravel(getattr(std, name)) for std in (old, new)]
    texts = numbers_text(*values[0][:3], *values[1][:3])
    cut = min(values[0].size, 3)
    out = []
    for std, v, cells in zip((old, new), values, (texts[:cut], texts[cut:]), strict=True):
        text = cells[0] if v.size == 1 else f"[{', '.join(cells)}{', ...' if v.size > 3 else ''}]"
        who = "given" if name in std.y_given else "the runs' own"
        out.append(f"{text} ({who})")
    return out[0], out[1]


PER_COMPONENT = ("betaU", "lamUz", "lamWs")
"""The emulator parameters with one entry per basis vector of K (their last axis)."""


def component_order(emulator: Emulator, problem: Problem) -> list[int] | None:
    """Where each of ``problem``'s basis vectors (K's columns) is among ``emulator``'s (a fit of
    the same runs): its component j is the emulator's ``order[j]``, up to its sign (the weights
    w agree to 1e-12, a sign flipped or not); None where they are not the same vectors. Their
    model is the same (each component's weights have a zero-mean GP prior of their own), its
    per-component parameters ``PER_COMPONENT`` in another order."""
    old, new = np.asarray(emulator.w), np.asarray(problem.w)
    if old.shape != new.shape:
        return None
    order = []
    for j in range(new.shape[1]):
        hits = [i for i in range(old.shape[1]) if i not in order
                and _same_up_to_sign(old[:, i], new[:, j])]  # fmt: skip
        if not hits:
            return None
        order.append(hits[0])
    return order


def _same_up_to_sign(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether weights ``a`` and ``b`` (m,) agree to 1e-12, one's sign flipped or not."""
    return any(np.allclose(s * a, b, rtol=0.0, atol=1e-12) for s in (1.0, -1.0))


def reordered(name: str, values, order: list[int] | None):
    """A source's draws (or widths, rates) of parameter ``name``, (..., p_u) for a per-component
    one (``PER_COMPONENT``), in the order of this fit's components (``component_order``);
    other parameters, or ``order`` None, as given."""
    if order is None or name not in PER_COMPONENT or order == sorted(order):
        return values
    return np.asarray(values)[..., order]


MH_BACKENDS = ("numpy", "torch")
"""Backends whose recorded ``step_widths`` are GPM/SA's Metropolis widths (a continuation runs
on with them)."""


def continued_widths(emulator: Emulator, problem: Problem, n_chains: int,
                     order: list[int] | None = None) -> dict | None:  # fmt: skip
    """The step widths ``emulator``'s chains ran with (``settings["step_widths"]``, per chain),
    for its continuation; None where it recorded none or its backend's are not Metropolis widths
    (``MH_BACKENDS``; pyro records its NUTS step size there). GPMSAError where the record does
    not fit ``problem``'s chains and parameters (a damaged file). ``order``: this fit's
    components among the source's (``component_order``)."""
    settings = emulator.settings or {}
    record = settings.get("step_widths")
    if not record or settings.get("backend") not in MH_BACKENDS:
        return None
    if isinstance(record, dict):
        record = {k: _reordered_list(k, v, order) for k, v in record.items()}
    try:
        check_step_widths(record, problem, n_chains)
    except GPMSAError as exc:
        raise GPMSAError(
            f"init=emulator: its recorded step widths (settings['step_widths']) do not fit "
            f"this fit ({exc}); pass step_widths= or tune=True"
        ) from None
    return record


def continued_ladder(emulator: Emulator, options: dict, n_chains: int, given):
    """The ladder of ``fit(..., init=emulator)`` (a continuation; ``options`` its backend's,
    ``given`` their "temperatures" checked by ``tempering.ladder``): ``given`` where the option
    is there (None given: a continuation without tempering), else the source's where it was
    tempered (`source_ladders`), set in ``options`` with its "swap_every" unless given. Where
    the source records its hot copies (`resumes_copies`) each resumes where it stopped; else
    every copy of a chain starts at the chain's last kept state and is tuned at its temperature
    before any draw (``fit``; a hot copy is auxiliary, any start is valid once warmed up).
    Returns chain 0's ladder (K,), or None."""
    if "temperatures" in options:
        return given
    ladders, every = source_ladders(emulator.settings or {}, n_chains)
    if ladders is None:
        return None
    if options.get("swap_every") is None:
        options["swap_every"] = every
    options["temperatures"] = ladders.tolist() if ladders.ndim == 1 else ladders
    return tuple(float(t) for t in np.atleast_2d(ladders)[0])


def resumes_copies(settings: dict, options: dict, n_chains: int,
                   source: str = "init=emulator") -> bool:  # fmt: skip
    """Whether a continuation of a fit's or a study's ``settings`` (``options``: its tempering,
    "temperatures" set by `continued_ladder`, and "adapt_ladder") resumes every hot copy where
    the source's stopped: the source records them (``HOT_RECORD``) and the continuation runs at
    its ladder (each chain's), without adapting it again (``source``: the argument that gave
    it, for `source_ladders`' errors). The caller also leaves ``tune`` out (or False). A
    damaged ladder record resumes none (the continuation's ladder is given: its copies are
    tuned); a source of other chains is named."""
    if any(settings.get(k) is None for k in HOT_RECORD) or options.get("adapt_ladder"):
        return False
    mine = tempering.chain_ladders(options.get("temperatures"), n_chains)
    if mine is None:
        return False
    try:
        ladders, _ = source_ladders(settings, n_chains, source)
    except GPMSAError:
        n_prev = settings.get("n_chains")
        if type(n_prev) is int and n_prev != n_chains:
            raise
        return False
    if ladders is None:
        return False
    theirs = np.atleast_2d(ladders)
    return theirs.shape[1] == len(mine[0]) and np.array_equal(
        np.broadcast_to(theirs, (n_chains, theirs.shape[1])), np.array(mine)
    )


def continued_copies(emulator: Emulator, problem: Problem, n_chains: int, ladders,
                     order: list[int] | None = None) -> dict:  # fmt: skip
    """The numpy sampler's ``hot_copies`` of a continuation resuming ``emulator``'s hot copies
    (its settings ``HOT_RECORD``) at ``ladders`` (``options["temperatures"]``), per-component
    parameters in this fit's order (``order``: ``component_order``). GPMSAError naming the
    record where it does not fit this fit's chains, copies and parameters (a damaged file)."""
    settings = emulator.settings or {}
    record = {}
    for part, key in zip(("starts", "widths"), HOT_RECORD, strict=True):
        value = settings[key]
        if isinstance(value, dict):
            value = {k: _reordered_list(k, v, order) for k, v in value.items()}
        record[part] = value
    theta = record["starts"].get("theta") if isinstance(record["starts"], dict) else None
    if theta is not None and problem.theta_levels:  # a float32 fit's levels, as its draws'
        try:
            theta = np.array(theta, dtype=np.float64)
        except (TypeError, ValueError, OverflowError):  # a damaged record: the check names it
            theta = None
        if theta is not None and theta.shape[-1:] == (len(problem.theta_levels),):
            _at_levels(problem, theta)
            record["starts"]["theta"] = theta
    try:
        check_hot_copies(record, problem, tempering.chain_ladders(ladders, n_chains), n_chains)
    except GPMSAError as exc:
        raise GPMSAError(
            f"init=emulator: its recorded hot copies (settings['hot_states'], "
            f"settings['hot_step_widths']) do not fit this fit ({exc}); pass tune=True (every "
            "copy tuned from the chain's last state) or temperatures= another ladder (1: none)"
        ) from None
    return record


def source_ladders(settings: dict, n_chains: int, source: str = "init=emulator"):
    """A tempered source's ladder and swap interval from its ``settings`` (a fit's or a
    study's): (the ladder (K,) of settings "temperatures", or each chain's (n_chains, K) where
    its chains adapted theirs, "adapted_temperatures"; its "swap_every", 1 where not recorded);
    (None, None) where it was not tempered. GPMSAError naming a damaged record (``source``: the
    argument that gave it; one naming n_chains where the source ran other chains)."""
    if settings.get("temperatures") is None:
        return None, None
    n_prev = settings.get("n_chains")
    if type(n_prev) is int and n_prev != n_chains:  # before its per-chain ladders' shape
        raise GPMSAError(f"{source} continues its {n_prev} chain(s): pass n_chains={n_prev}")
    try:
        recorded = settings["temperatures"]
        if np.ndim(recorded) != 1:  # a fit records a list, never a count
            raise GPMSAError(f"temperatures is a {type(recorded).__name__}, not a list")
        start = tempering.ladder(recorded)
        ladders = [start] * n_chains
        if settings.get("adapted_temperatures") is not None:
            adapted = np.asarray(settings["adapted_temperatures"], dtype=float)
            if adapted.shape != (n_chains, len(start)):
                raise GPMSAError(f"adapted_temperatures of shape {adapted.shape}, not "
                                 f"({n_chains}, {len(start)})")  # fmt: skip
            ladders = tempering.chain_ladders(adapted, n_chains)
        every = tempering.check_swap_every(settings.get("swap_every", 1), start)
    except (GPMSAError, TypeError, ValueError) as exc:
        raise GPMSAError(
            f"{source}: its tempering record (settings 'temperatures', 'adapted_temperatures', "
            f"'swap_every') is damaged ({exc}); pass temperatures="
        ) from None
    same = ladders.count(ladders[0]) == n_chains
    return np.array(ladders[0] if same else ladders), every


def continued_steps(emulator: Emulator) -> bool | None:
    """Whether ``emulator``'s chains stepped the precisions by GPM/SA's proportional step (its
    ``settings["proportional_steps"]``; a file written before that was recorded: ``not
    settings["tune"]``, the rule its sampler followed), for its untuned continuation; None where
    its backend is not a Metropolis one (``MH_BACKENDS``). GPMSAError naming a damaged record."""
    settings = emulator.settings or {}
    if settings.get("backend") not in MH_BACKENDS:
        return None
    steps = settings.get("proportional_steps")
    if steps is None and isinstance(settings.get("tune"), bool):
        steps = not settings["tune"]
    if steps is not None and not isinstance(steps, bool):
        raise GPMSAError(
            f"init=emulator: its settings['proportional_steps'] must be true, false or null, got "
            f"{steps!r}; pass proportional_steps= or tune=True"
        )
    return steps


def check_append(append, init, n_burn, kind: type = Emulator, source: str = "emulator",
                 of: str = "fit") -> bool:  # fmt: skip
    """``append`` checked (``fit``'s; a study function's with ``kind`` Study): a flag, True only
    with ``init`` a ``kind`` (its ``source``, whose draws it appends to) and ``n_burn`` None or
    0 (the source's burn-in is already removed); GPMSAError naming the argument otherwise."""
    append = check_flag(append, "append")
    if append and not isinstance(init, kind):
        got = repr(init) if init is None or isinstance(init, str) else type(init).__name__
        raise GPMSAError(
            f"append=True appends a continuation's draws to those of the {of} it continues: "
            f"pass init=that {source} (got init={got})"
        )
    if append and n_burn not in (None, 0):
        raise GPMSAError(
            f"append=True pools every kept sweep of the continuation (its chains start at the "
            f"source's last kept draws, past burn-in): n_burn must be 0 or None, got {n_burn!r}"
        )
    return append


def _has_draws(emulator: Emulator) -> None:
    """GPMSAError unless ``emulator`` (``fit``'s ``init``) holds retained draws."""
    if not emulator.draws or not emulator.log_post.size:
        raise GPMSAError("init=emulator continues a fit's chains; this emulator has no draws "
                         "(Emulator.from_params?)")  # fmt: skip


def _chains_of(emulator: Emulator, n_chains: int) -> None:
    """GPMSAError unless ``emulator`` was fitted with ``n_chains`` chains."""
    n_prev = int((emulator.settings or {}).get("n_chains", 1) or 1)
    if n_prev != n_chains:
        raise GPMSAError(f"init=emulator continues its {n_prev} chain(s): pass n_chains={n_prev}")


def appended_thin(source: Emulator, n_iter: int, n_chains: int, n_keep) -> int:
    """The thinning step of ``fit(..., init=source, append=True)``: the source's
    (``settings["thin"]``), whose continuation keeps n_chains x (n_iter // thin) draws.
    GPMSAError where the source has no draws, other chains or no step, where ``n_iter`` keeps
    no draw at it, or where ``n_keep`` (None: the step's) is not that count (naming it)."""
    _has_draws(source)
    _chains_of(source, n_chains)
    return append_step((source.settings or {}).get("thin"), n_iter, n_chains, n_keep)


def append_step(thin, n_iter: int, n_chains: int, n_keep, source: str = "init=emulator") -> int:
    """``thin``, the step its ``source`` (``init=``) recorded (settings["thin"]), checked for
    an append: an integer >= 1 at which ``n_iter`` sweeps keep a draw, and ``n_keep`` (None:
    the step's) the n_chains x (n_iter // thin) draws it keeps; GPMSAError naming each."""
    if isinstance(thin, bool) or not isinstance(thin, int) or thin < 1:
        raise GPMSAError(
            f"append=True thins the continuation by its source's step, and {source} "
            f"records none (settings['thin'] = {thin!r}): continue it without append"
        )
    new = n_chains * (n_iter // thin)
    if not new:
        raise GPMSAError(
            f"append=True keeps one sweep in {thin} ({source}'s step, settings['thin']): "
            f"n_iter={n_iter} keeps none; pass n_iter >= {thin}"
        )
    if n_keep is not None and n_keep != new:
        raise GPMSAError(
            f"append=True thins by {source}'s step {thin} (settings['thin']), which keeps "
            f"{new} draws of {n_chains} chain(s) x {n_iter} sweeps: pass n_keep={new}, or leave "
            f"n_keep out (got n_keep={n_keep!r})"
        )
    return thin


def _reordered_list(name: str, values, order: list[int] | None):
    """A recorded nested list (of numbers and None) of ``name``, its last axis in the order of
    this fit's components (``reordered``); as given where nothing moves or that fails (a damaged
    record, which its check then names)."""
    try:
        given = np.asarray(values, dtype=object)
        moved = reordered(name, given, order)
    except (IndexError, ValueError):
        return values
    return values if moved is given else moved.tolist()


def pool_chains(first: np.ndarray, second: np.ndarray, n_chains: int) -> np.ndarray:
    """Chain-major draws (n_chains a, *shape) and (n_chains b, *shape) pooled as
    (n_chains (a + b), *shape): each chain's ``first`` draws, then its ``second``."""
    first, second = np.asarray(first, dtype=float), np.asarray(second, dtype=float)
    a, b = first.shape[0] // n_chains, second.shape[0] // n_chains
    both = np.concatenate([first.reshape(n_chains, a, *first.shape[1:]),
                           second.reshape(n_chains, b, *second.shape[1:])], axis=1)  # fmt: skip
    return both.reshape(n_chains * (a + b), *first.shape[1:])


def pool_draws(source: Emulator, retained: dict, log_post: np.ndarray, calibration, n_chains,
               order: list[int] | None = None):  # fmt: skip
    """``source``'s retained draws (emulator and calibration ones), log posteriors and
    calibration draws, each chain followed by a continuation's (``retained``, ``log_post``,
    ``calibration``, chain-major as ``fit`` keeps them). GPMSAError where the source lacks a
    parameter the continuation sampled or its shape differs. ``order``: this fit's components
    among the source's (``component_order``): the pooled draws are in this fit's."""
    cal = dict(source.calibration or {})
    pooled = {}
    for k, v in retained.items():
        old = source.draws.get(k) if k in EMULATOR_PARAMS else cal.get(k)
        old = None if old is None else reordered(k, old, order)
        if old is None or np.shape(old)[1:] != v.shape[1:]:
            raise GPMSAError(f"append=True: init=emulator has no {k} draws of shape "
                             f"{v.shape[1:]} to append to (another model?)")  # fmt: skip
        pooled[k] = pool_chains(old, v, n_chains)
    if calibration is not None:
        if set(cal) != set(calibration):
            raise GPMSAError(f"append=True: init=emulator's calibration draws {sorted(cal)} are "
                             f"not this fit's {sorted(calibration)}")  # fmt: skip
        calibration = {k: pool_chains(cal[k], v, n_chains) for k, v in calibration.items()}
    return pooled, pool_chains(source.log_post, log_post, n_chains), calibration


def _sweeps(settings: dict) -> tuple[int | None, int | None]:
    """A fit's sweeps per chain (after burn-in, and in all) from its ``settings``: an appended
    fit's "pooled_sweeps" and "sweeps_run", else n_iter - n_burn and n_iter; None where not
    recorded as integers."""

    def whole(v):
        return v if isinstance(v, int) and not isinstance(v, bool) and v >= 0 else None

    if "appended_to" in settings:
        return whole(settings.get("pooled_sweeps")), whole(settings.get("sweeps_run"))
    n_iter, n_burn = whole(settings.get("n_iter")), whole(settings.get("n_burn"))
    return (None if n_iter is None or n_burn is None else n_iter - n_burn), n_iter


def appended_record(source: Emulator, n_iter: int, n_chains: int) -> dict:
    """The settings of ``fit(..., init=source, n_iter=n_iter, append=True)``: appended_to (the
    source's ``model_sha256``), appended_after (its retained draws per chain: the pooled chain
    c's first ones), pooled_sweeps and sweeps_run (per chain: after burn-in, and in all, tuning
    aside; None where the source does not record its own)."""
    return appended_counts(source.settings or {}, source.model_sha256,
                           int(source.n_draws // n_chains), n_iter)  # fmt: skip


def appended_counts(settings: dict, digest: str | None, per_chain: int, n_iter: int) -> dict:
    """The appended settings (``appended_record``'s) of a source whose ``settings``, digest and
    retained draws per chain are given, continued by ``n_iter`` sweeps a chain."""
    pooled, run = _sweeps(settings)
    return {
        "appended_to": digest,
        "appended_after": int(per_chain),
        "pooled_sweeps": None if pooled is None else pooled + n_iter,
        "sweeps_run": None if run is None else run + n_iter,
    }


def sweeps_run(settings: dict) -> int | None:
    """A fit's (or study's) sweeps per chain in all, tuning aside, from its ``settings`` (an
    appended one's "sweeps_run"); None where not recorded."""
    return _sweeps(settings)[1]


def pool_accept(summary: dict, source: Emulator, accept_rate: dict, n_iter: int, backend: str,
                order: list[int] | None = None) -> None:  # fmt: skip
    """Each entry of ``summary`` (``summarize`` of pooled draws) given the acceptance rate of
    both parts, weighted by their sweeps (the source's "accept" in its diagnostics over its
    sweeps run, ``accept_rate`` (n_chains, *shape) over ``n_iter``); none where the source
    records no rate or sweeps, or where one part is Metropolis (``MH_BACKENDS``) and the other
    NUTS (pyro's rate is another figure). ``order``: this fit's components among the source's
    (``component_order``)."""
    settings = source.settings or {}
    run = _sweeps(settings)[1]
    if (settings.get("backend") in MH_BACKENDS) != (backend in MH_BACKENDS):
        return
    for name, entry in summary.items():
        old = (source.diagnostics or {}).get(name, {}).get("accept")
        if run is None or old is None or name not in accept_rate:
            continue
        new = accept_rate[name].reshape(accept_rate[name].shape[0], -1).mean(0)
        old = np.array([np.nan if v is None else v for v in old], dtype=float)
        if old.shape != new.shape:
            continue
        shape = accept_rate[name].shape[1:]
        old = np.asarray(reordered(name, old.reshape(shape), order)).reshape(-1)
        both = (old * run + new * n_iter) / (run + n_iter)
        entry["accept"] = [float(v) for v in both]


def _model_differences(emulator: Emulator, problem: Problem, order: list[int] | None = None
                       ) -> tuple[list[str], str]:  # fmt: skip
    """What of the model ``emulator`` was fitted with differs from ``problem``'s: its priors,
    mean basis, fixed parameters, theta constraint and discrepancy basis and groups. A
    discrepancy basis whose columns are the source's up to their signs and order (each with
    its group: ``reordered_basis``) is the same; priors that agree to 1e-12 are the same (the
    data correction's sums run in another order where K or that basis is reordered, or in a
    file of an older version), and a per-component parameter held (fixed) with K in another
    order (``order``, from ``component_order``) is another model. Returns (the names of what
    differs, `_prior_fields`' detail where the priors do, else "")."""
    settings = emulator.settings or {}
    mb = problem.mean_basis
    disc = {} if problem.obs is None or problem.obs.D is None else discrepancy_record(problem.obs)
    n_grp = problem.obs.n_groups if problem.obs is not None and problem.obs.p_v else 0
    keys = ("discrepancy_sha256", "discrepancy_groups")
    old_disc, new_disc = {k: settings.get(k) for k in keys}, {k: disc.get(k) for k in keys}
    k_moved = order is not None and order != sorted(order)
    d_moved = discrepancy_moved(old_disc, new_disc, problem.obs)
    fixed = (settings.get("fixed", {}), fixed_record(problem))
    priors = tuple(_prior_record(p, n_grp, problem.q) for p in (emulator.priors, problem.priors))
    differs = {
        "priors": not _close(*priors),
        "mean_basis": settings.get("mean_basis") != (None if mb is None else mb.kind),
        "fixed parameters": fixed[0] != fixed[1]
        or (k_moved and any(k in f for f in fixed for k in PER_COMPONENT)),
        "theta constraint": bool(settings.get("constraint", False))
        != (problem.constraint is not None),
        "discrepancy": old_disc != new_disc and not d_moved,
    }
    names = [name for name, differ in differs.items() if differ]
    return names, _prior_fields(*priors) if differs["priors"] else ""


CORRECTED = frozenset({"lamWOs", "lamOs", "corrected"})
"""Prior fields that fitting corrects for the data (GPM/SA's data corrections): they differ
with the data or the discrepancy, not as the user set them, so `_prior_fields` leaves them out."""


def _prior_fields(source: dict, this: dict) -> str:
    """ " (priors: ...)": the fields in which the prior records ``source`` and ``this``
    (`_prior_record`) differ with their values (the source's, then this fit's), and the remedy
    (an Emulator's ``priors`` are data-corrected: ``fit`` takes the priors as set before
    fitting)."""
    fields = [k for k in sorted((set(source) | set(this)) - CORRECTED)
              if source.get(k) != this.get(k)]  # fmt: skip
    if not fields:  # only the data's corrections differ (other data, another discrepancy)
        return ""
    shown = "; ".join(f"{k}: {_short(source.get(k))} there, {_short(this.get(k))} here"
                      for k in fields[:3])  # fmt: skip
    more = f"; and {len(fields) - 3} more" if len(fields) > 3 else ""
    return f" (priors: {shown}{more}: give priors= as the source was fitted with)"


def _short(value, width: int = 60) -> str:
    """``repr(value)``, cut to ``width`` characters with "..." where longer."""
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def discrepancy_moved(old: dict, new: dict, obs) -> bool:
    """Whether discrepancy records ``old`` and ``new`` (``discrepancy.record``'s
    discrepancy_sha256 and discrepancy_groups) differ, ``obs``'s bases (an ObsProblem, or None)
    being ``old``'s up to their columns' signs and order, each column keeping its group
    (``reordered_basis``): the same model."""
    if old == new or obs is None:
        return False
    digest, groups = old.get("discrepancy_sha256"), old.get("discrepancy_groups")
    return reordered_basis(digest, groups, obs.D, obs.v_groups)


def _close(a, b) -> bool:
    """Whether two prior records (``_prior_record``) are equal but for floats within 1e-12."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float):
        return a == b or math.isclose(a, b, rel_tol=1e-12, abs_tol=0.0)
    return a == b


def _prior_record(priors: Priors, n_grp: int, q: int) -> dict:
    """``priors.to_dict()`` with theta_mean, theta_sd as the lists of the ``q`` calibration
    parameters' theta priors, lamVz as the list of the ``n_grp`` groups' priors and rhoV_a,
    rhoV_b as the lists of the groups' betaV Beta parameters (a shared prior, equal per-element
    or per-group ones and, for betaV, none (betaU's) are one model); as written without a
    discrepancy, or where the per-element or per-group priors do not fit the model."""
    out = priors.to_dict()
    if priors.theta_count in (None, q):
        pairs = [priors.theta_prior(k) for k in range(q)]
        out["theta_mean"], out["theta_sd"] = [m for m, _ in pairs], [s for _, s in pairs]
    if n_grp and (not priors.per_group or len(priors.lamVz) == n_grp):
        one = replace(priors, lamVz=priors.lamvz_priors(n_grp)).to_dict()
        out["lamVz"] = one["lamVz"]
    if n_grp and (not priors.rhov_per_group or len(priors.rhoV_a) == n_grp):
        pairs = priors.rhov_priors(n_grp)
        out["rhoV_a"], out["rhoV_b"] = [a for a, _ in pairs], [b for _, b in pairs]
    return out
