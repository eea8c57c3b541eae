"""Continuing a calibration's chains (``gpmsa.calibrate(..., init=posterior)``): the checks that
the source is a calibration of this emulator, these observations and settings, each chain's start
at its last draw with the step widths it ended with, and ``append=True``, which pools the
source's chains with the continuation's (as ``gpmsa.fit``'s, ``gpmsa.fitting.continuation``, and
the studies' continuations)."""

from __future__ import annotations

import hashlib

import numpy as np

from gpmsa.calibration.observations import emulator_record
from gpmsa.calibration.posterior import Posterior
from gpmsa.errors import GPMSAError
from gpmsa.mcmc import tempering
from gpmsa.model.basis import discrepancy_kind
from gpmsa.model.categorical import snap_to_levels
from gpmsa.model.data import check_flag
from gpmsa.model.discrepancy import sample_names
from gpmsa.model.problem import Problem

SOURCE = "init=posterior"
"""How the messages name ``calibrate``'s ``init`` when it is a Posterior."""
MH_BACKENDS = ("numpy", "torch")
"""Backends whose recorded ``step_widths`` are GPM/SA's Metropolis widths (as ``gpmsa.fit``'s)."""


def checked_source(init, n_chains: int) -> Posterior:
    """``init`` checked as a Posterior that ``gpmsa.calibrate`` returned (MCMC, its chains, step
    widths and settings in ``info``) of ``n_chains`` chains; GPMSAError naming what it is
    otherwise (an Emulator: ``gpmsa.fit``'s; an ArviZ InferenceData, a grid posterior, a study's
    or a fit's posterior: no step widths or settings to continue from)."""
    if not isinstance(init, Posterior):
        kind = type(init).__name__
        hint = ""
        if kind == "Emulator":
            hint = " (a fit's chains continue in gpmsa.fit(..., init=emulator))"
        elif kind in ("InferenceData", "DataTree"):  # ArviZ 0.x, 1.x
            hint = (" (Posterior.to_arviz() keeps the draws, not the step widths and settings "
                    "a continuation needs: keep the Posterior itself, e.g. pickled)")  # fmt: skip
        raise GPMSAError(f"init must be a start rule or a Posterior that gpmsa.calibrate "
                         f"returned, got {kind}{hint}")  # fmt: skip
    info = init.info
    if info.get("method") != "mcmc" or info.get("engine") not in ("fast", "backend"):
        raise GPMSAError(
            f"{SOURCE} continues the chains of a Posterior that gpmsa.calibrate returned; this "
            f"one (method {info.get('method')!r}) records no chains' states and step widths (a "
            "Calibrator's grid, a fit's calibration_posterior or a study's member_posterior): "
            "calibrate afresh, or continue a fit or study with its own init="
        )
    if init.chains is None or "step_widths" not in info:
        raise GPMSAError(f"{SOURCE} holds no chains or step widths (info['step_widths']): "
                         "calibrate afresh")  # fmt: skip
    n_prev = int(np.atleast_2d(next(iter(init.chains.values()))).shape[0])
    if n_prev != n_chains:
        raise GPMSAError(f"{SOURCE} continues its {n_prev} chain(s): pass n_chains={n_prev}")
    return init


HINTS = {
    "emulator": "its model_sha256: another fit, or other calibration priors",
    "observations": "x_obs, y_obs or their precisions",
}
"""What a differing entry of `check_same` means, where its name does not say it."""


def check_same(source: Posterior, **same) -> None:
    """GPMSAError naming each ``same`` entry (name -> (the source's, this calibration's)) that
    differs, with both values (a digest by its first 12 characters)."""
    differs = [name for name, (a, b) in same.items() if a != b]
    if differs:
        detail = "; ".join(
            f"{n}: {_brief(same[n][0])} there, {_brief(same[n][1])} here"
            + (f" ({HINTS[n]})" if n in HINTS else "")
            for n in differs
        )
        raise GPMSAError(
            f"{SOURCE} was another calibration: other {', '.join(differs)} ({detail}); "
            "continue it with the same emulator, observations and settings, or start afresh"
        )


def _brief(value) -> str:
    """``value`` for a message: a digest (64 hex characters) by its first 12, a list or dict
    of them so, anything else its repr cut to 100 characters."""
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_brief(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {_brief(v)}" for k, v in value.items()) + "}"
    if isinstance(value, str) and len(value) == 64:
        return value[:12]
    text = repr(value)
    return text if len(text) <= 100 else text[:97] + "..."


def check_engine(source: Posterior, fast: bool, backend: str = "numpy") -> None:
    """GPMSAError where ``source`` ran on the other engine (the fast numpy sampler or a
    backend's) than the continuation would, on ``backend``: its states and widths are that
    engine's."""
    was = source.info["engine"] == "fast"
    if was != fast:
        how = "the fast numpy sampler" if was else f"backend {source.info.get('backend')!r}"
        hint = "pass fast=False (or its backend=)"
        if was:  # the fast sampler is numpy's: another backend is in the way, or fast=False
            hint = ("leave fast= out" if backend == "numpy" else
                    f"leave backend={backend!r} out (and fast=): the fast sampler is the numpy "
                    "backend's")  # fmt: skip
        raise GPMSAError(
            f"{SOURCE} ran on {how} (info['engine'] {source.info['engine']!r}); its "
            f"continuation runs there too: {hint}"
        )


def check_append(append, source: Posterior | None, n_burn) -> bool:
    """``append`` checked: a flag, True only with ``init`` a Posterior and ``n_burn`` None or 0
    (its chains start at the source's last draws, past burn-in)."""
    append = check_flag(append, "append")
    if append and source is None:
        raise GPMSAError("append=True appends a continuation's draws to those of the calibration "
                         "it continues: pass init=that posterior")  # fmt: skip
    if append and n_burn not in (None, 0):
        raise GPMSAError(
            "append=True pools every sweep of the continuation (its chains start at the "
            f"source's last draws, past burn-in): n_burn must be 0 or None, got {n_burn!r}"
        )
    return append


def proportional(source: Posterior) -> bool:
    """Whether ``source``'s chains stepped lamOs (and the discrepancy's precisions) by GPM/SA's
    proportional step (``info["proportional_steps"]`` of a continuation, else ``not
    info["tune"]``, the rule a fresh calibration follows), for its untuned continuation."""
    steps = source.info.get("proportional_steps", not source.info.get("tune", True))
    if not isinstance(steps, bool):
        raise GPMSAError(f"{SOURCE}: its info['proportional_steps'] must be true or false, got "
                         f"{steps!r}; pass tune=True")  # fmt: skip
    return steps


def _last(source: Posterior, name: str) -> np.ndarray:
    """Each chain's last draw of ``name`` (n_chains,); GPMSAError where the source lacks it."""
    if name not in source.chains:
        raise GPMSAError(f"{SOURCE} has no {name!r} draws (another model?): start afresh")
    return np.atleast_2d(source.chains[name])[:, -1].astype(np.float64)


def theta_unit(source: Posterior, emulator) -> np.ndarray:
    """Each chain's last theta (n_chains, q) on the unit scale, a categorical element exactly at
    its level (the draws hold the native codes)."""
    native = np.column_stack([_last(source, str(n)) for n in emulator.t_names])
    return emulator.standardizer.t_to_unit(native)


def theta_start(source: Posterior, emulator, constraint) -> list[float]:
    """Chain 0's last theta (native, (q,)): the run's ``theta_init``, so that the checks of a
    fresh chain's start (the constraint at GPM/SA's initial, held elements beside it) see where
    the chains start. GPMSAError naming each chain whose last draw ``constraint`` (a
    ``ThetaConstraint``, or None) refuses."""
    unit = theta_unit(source, emulator)
    for c, t in enumerate(unit if constraint is not None else ()):
        if not constraint(t):
            raise GPMSAError(f"{SOURCE}: chain {c}'s last draw "
                             f"({constraint.describe(constraint.native(t))}) lies outside this "
                             "theta constraint (another constraint?): start afresh")  # fmt: skip
    return [float(_last(source, str(n))[0]) for n in emulator.t_names]


def fast_starts(source: Posterior, emulator, levels, positions) -> list[tuple]:
    """Each chain's start (unit theta, lamOs, emulator-set index) for the fast sampler's
    ``run(start=)``; ``levels``: the sampler's per-element levels (unit scale), ``positions``:
    the emulator draws its sets are (None: the point estimate, one set)."""
    theta = theta_unit(source, emulator)
    lam = _last(source, "lamOs")
    sets = np.zeros(theta.shape[0], dtype=np.int64)
    if positions is not None:
        kept = np.asarray(source.info.get("emulator_draws", ()), dtype=np.int64)
        last = kept.reshape(theta.shape[0], -1)[:, -1] if kept.size else kept
        where = {int(p): i for i, p in enumerate(positions)}
        if last.size != theta.shape[0] or any(int(p) not in where for p in last):
            raise GPMSAError(f"{SOURCE}: its chains' last emulator draws "
                             "(info['emulator_draws']) are not among this calibration's "
                             "(another n_emulator_draws?)")  # fmt: skip
        sets = np.array([where[int(p)] for p in last])
    return [(snap_to_levels(t, levels).tolist(), float(v), int(k))
            for t, v, k in zip(theta, lam, sets, strict=True)]  # fmt: skip


def fast_widths(source: Posterior, q: int, n_chains: int) -> list[np.ndarray]:
    """Each chain's step widths (q + 1,) as ``source`` recorded them (``info["step_widths"]``;
    a held element's NaN, which its sweep never reads); GPMSAError where they do not fit."""
    try:
        w = np.array(source.info["step_widths"], dtype=np.float64)
    except (TypeError, ValueError):
        w = np.empty(0)
    if w.shape != (n_chains, q + 1) or not np.all(np.isnan(w) | (w > 0)) or np.isinf(w).any():
        raise GPMSAError(f"{SOURCE}: its recorded step widths (info['step_widths']) are not "
                         f"positive widths of {q + 1} elements for {n_chains} chain(s); pass "
                         "tune=True")  # fmt: skip
    return list(w)


def backend_starts(source: Posterior, problem: Problem, emulator) -> dict[str, np.ndarray]:
    """Each chain's start of every sampled parameter (name -> (n_chains, *shape)) at its last
    draw, for a backend's ``init`` (theta on the unit scale, a categorical element at its level;
    betaV and lamVz from their posterior names, ``sample_names``)."""
    theta = np.array([problem.snap_theta(t) for t in theta_unit(source, emulator)])
    out = {"theta": theta, "lamOs": _last(source, "lamOs")[:, None]}
    if "lamVz" in problem.init:
        p, n_grp = problem.init["betaV"].shape
        bnames, lnames = sample_names(p, n_grp)
        n = theta.shape[0]
        beta = np.zeros((n, p, n_grp))
        for i, name in enumerate(bnames):
            beta[:, i % p, i // p] = _last(source, name)
        out["betaV"] = beta
        out["lamVz"] = np.column_stack([_last(source, name) for name in lnames])
    return {k: v for k, v in out.items() if k in problem.sampled}


def backend_widths(source: Posterior, backend: str) -> dict | None:
    """The step widths ``source``'s chains ran with (``info["step_widths"]``, name -> per
    chain) for a continuation on ``backend``; None where either is not a Metropolis backend
    (pyro records its NUTS step size there, and adapts its own)."""
    if source.info.get("backend") not in MH_BACKENDS or backend not in MH_BACKENDS:
        return None
    return dict(source.info["step_widths"])


def continued_ladder(source: Posterior, options: dict, n_chains: int):
    """The ladder of a continuation (``options``: the backend's, where "temperatures" given
    wins, None or 1 meaning untempered): else the source's (each chain's adapted one where its
    chains adapted theirs), set in ``options`` with its "swap_every" unless given. Returns the
    ladder (``tempering.ladder``'s, chain 0's), or None."""
    if "temperatures" in options:
        return tempering.ladder(options["temperatures"])
    info = source.info
    if info.get("temperatures") is None:
        return None
    try:
        first = tempering.ladder(info["temperatures"])  # the ladder the chains started from
        ladders = first
        if info.get("adapted_temperatures") is not None:
            ladders = np.asarray(info["adapted_temperatures"], dtype=float)
            tempering.chain_ladders(ladders, n_chains)
        every = tempering.check_swap_every(info.get("swap_every", 1), first)
    except (GPMSAError, TypeError, ValueError) as exc:
        raise GPMSAError(f"{SOURCE}: its tempering record (info 'temperatures', "
                         f"'adapted_temperatures', 'swap_every') is damaged ({exc}); pass "
                         "temperatures=") from None  # fmt: skip
    options["temperatures"] = ladders if isinstance(ladders, np.ndarray) else list(ladders)
    options.setdefault("swap_every", every)
    return first


def chains_sha256(post: Posterior) -> str:
    """A digest of ``post``'s chains (names, shapes and float64 values): what a continuation
    records as "continued_from" and "appended_to" (a Posterior has no file digest)."""
    h = hashlib.sha256()
    for name in sorted(post.chains):
        arr = np.ascontiguousarray(post.chains[name], dtype=np.float64)
        h.update(f"{name}{arr.shape}".encode())
        h.update(arr.tobytes())
    return h.hexdigest()


def pool(source: Posterior, chains: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Each chain of ``source`` followed by the continuation's (name -> (n_chains, n))."""
    if set(source.chains) != set(chains):
        raise GPMSAError(f"append=True: {SOURCE}'s draws {sorted(source.chains)} are not this "
                         f"calibration's {sorted(chains)}")  # fmt: skip
    return {k: np.concatenate([np.atleast_2d(source.chains[k]), v], axis=1)
            for k, v in chains.items()}  # fmt: skip


def pool_flat(old, new, n_chains: int) -> np.ndarray:
    """Chain-major flat records (``info["emulator_draws"]``) pooled as ``pool`` pools chains."""
    old, new = np.asarray(old), np.asarray(new)
    return np.concatenate([old.reshape(n_chains, -1), new.reshape(n_chains, -1)], 1).reshape(-1)


def _sweeps(info: dict) -> tuple[int, int]:
    """A calibration's kept and run sweeps per chain (tuning aside): an appended one's
    "pooled_sweeps" and "sweeps_run", else n_samples - n_burn and n_samples."""
    if "appended_to" in info:
        return int(info["pooled_sweeps"]), int(info["sweeps_run"])
    return int(info["n_samples"]) - int(info["n_burn"]), int(info["n_samples"])


def appended_info(source: Posterior, n_samples: int, accept_rate, backend: str):
    """The info an appended calibration adds: appended_to (``chains_sha256`` of the source),
    appended_after (its draws per chain), pooled_sweeps and sweeps_run (per chain, tuning
    aside), and accept_rate: both parts' rates weighted by their sweeps (as ``accept_rate``,
    a list per chain or a dict name -> per chain; the continuation's own where they do not
    match, or where one part ran Metropolis (``MH_BACKENDS``) and the continuation on
    ``backend`` NUTS or the reverse: pyro's rate is another figure)."""
    kept, run = _sweeps(source.info)
    out = {
        "appended_to": chains_sha256(source),
        "appended_after": int(np.atleast_2d(next(iter(source.chains.values()))).shape[1]),
        "pooled_sweeps": kept + int(n_samples),
        "sweeps_run": run + int(n_samples),
    }
    old = source.info.get("accept_rate")
    mixed = (source.info.get("backend") in MH_BACKENDS) != (backend in MH_BACKENDS)
    if mixed or isinstance(old, dict) != isinstance(accept_rate, dict):
        return {**out, "accept_rate": accept_rate}  # not comparable: the continuation's own

    def weighted(a, b):
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        if a.shape != b.shape:
            return np.asarray(b).tolist()
        return ((a * run + b * n_samples) / (run + n_samples)).tolist()

    if isinstance(accept_rate, dict):
        out["accept_rate"] = {k: weighted(old.get(k, v), v) for k, v in accept_rate.items()}
    else:
        out["accept_rate"] = weighted(old, accept_rate)
    return out


def check_source(source, emulator, fast: bool, emulator_params: str, n_emulator_draws: int,
                  constraint, log_prior, discrepancy, theta_init,
                  backend: str = "numpy") -> None:  # fmt: skip
    """GPMSAError where ``calibrate``'s ``init`` (a Posterior, ``source``) is a calibration of
    another emulator (its ``model_sha256``: another fit, or other calibration priors), another
    emulator_params, constraint, log_prior or discrepancy, or ran on another engine than
    ``fast`` on ``backend`` runs (`check_engine`); and where ``theta_init`` is given (the
    chains start at their last draws)."""
    info = source.info
    same = {
        "emulator": (info.get("emulator_sha256"),
                     emulator_record(emulator).get("emulator_sha256")),
        "emulator_params": (info.get("emulator_params"), emulator_params),
        "theta constraint": (bool(info.get("constraint", False)), constraint is not None),
        "log_prior": (bool(info.get("log_prior", False)), log_prior is not None),
        "discrepancy": (info.get("discrepancy"), discrepancy_kind(discrepancy)),
    }  # fmt: skip
    if emulator_params == "draws":
        same["n_emulator_draws"] = (info.get("n_emulator_draws"), n_emulator_draws)
    check_same(source, **same)
    check_engine(source, fast, backend)
    if theta_init is not None:
        raise GPMSAError(f"theta_init= sets a fresh chain's start; {SOURCE}'s chains "
                         "continue from their last draws: leave theta_init out")  # fmt: skip


def continued_run(source, tune, fast: bool, backend: str, temps, append: bool,
                   options: dict) -> tuple[bool, dict]:  # fmt: skip
    """A continuation's tuning and what its run takes ({"source", "widths": run on the recorded
    step widths (the fast sampler: True; a backend: name -> per chain; None: GPM/SA's),
    "proportional": the precisions' steps (None: ``not tune``)}), by ``gpmsa.fit``'s rules:
    ``tune`` None runs untuned on the recorded widths (tuned where none are recorded, and
    every copy of a tempered one tuned at its temperature from them: ``tune=False`` refused
    there); True tunes again from GPM/SA's widths; ``append`` refuses tuning (untempered)."""
    widths = None
    if tune is not True and "step_widths" not in options:
        widths = True if fast else backend_widths(source, backend)
    if tune is None:
        tune = widths is None or temps is not None
    if temps is not None and not tune:
        raise GPMSAError(
            f"tune=False with a tempered continuation (temperatures=, or {SOURCE} a "
            "tempered calibration): calibrate records no hot copies' states, so every copy is "
            "tuned at its temperature (from the T = 1 copy's widths) while the copies warm up "
            "from the chain's last state, before any draw is kept; leave tune out (or "
            "tune=True: from GPM/SA's widths), or pass temperatures=None to continue without "
            "tempering"
        )
    if append and tune and (fast or backend in MH_BACKENDS) and temps is None:
        raise GPMSAError(
            "append=True pools the chains' draws one sweep apart; tuning (tune=True, or "
            f"tune=None where {SOURCE} records no Metropolis step widths) would run its "
            "sweeps between the source's and the continuation's: pass tune=False"
        )
    steps = None  # the precisions' steps as the chains it continues (SEPIA: once tuned, always)
    metropolis = fast or (backend in MH_BACKENDS
                          and source.info.get("backend") in MH_BACKENDS)  # fmt: skip
    if not tune and metropolis and "proportional_steps" not in options:
        steps = proportional(source)
    return tune, {"source": source, "widths": widths, "proportional": steps}


def settings_record(constraint, log_prior, emulator_params: str, n_emulator_draws: int) -> dict:
    """What ``info`` records of the settings a continuation must share and the draws do not
    show: "constraint" and "log_prior" (True where given), "n_emulator_draws" (its draws mode)."""
    out = {k: True for k, v in (("constraint", constraint), ("log_prior", log_prior))
           if v is not None}  # fmt: skip
    if emulator_params == "draws":
        out["n_emulator_draws"] = int(n_emulator_draws)
    return out
