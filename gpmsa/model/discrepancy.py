"""Discrepancy precision groups (GPM/SA's ``lamVzGroup``) and the discrepancy parameters' names.

Each discrepancy basis vector k has its weight process v_k ~ GP(0, R(x; betaV[:, g]) / lamVz[g])
with g = groups[k]: the vectors of one group share a correlation (betaV column) and a
precision (lamVz element). One group (the default) is GPM/SA's default model.

Posterior names: with one group "betaV" (one known input) or "betaV[k]" (k = 0 .. p-1) and
"lamVz", as before groups existed; with G > 1 groups "betaV[k,g]" and "lamVz[g]".
"""

from __future__ import annotations

import math
import re

import numpy as np

from gpmsa.errors import GPMSAError
from gpmsa.model.basis import SCALE_TOL, basis_digest, basis_scale, given_bases, is_basis_list

NAME_PATTERN = re.compile(r"(betaV|lamVz)(\[\d+(,\d+)?\])?")
"""The discrepancy parameters' posterior names."""


def check_groups(groups, p_v: int) -> tuple[int, ...] | None:
    """The group (0 .. G-1) of each of the ``p_v`` discrepancy basis vectors, or None for one
    group; GPMSAError naming what is wrong. Every group from 0 to G-1 must hold a vector."""
    if groups is None:
        return None
    if p_v == 0:
        raise GPMSAError(
            "discrepancy_groups needs a discrepancy basis (discrepancy='constant', 'linear' or "
            "an array)"
        )
    count = f"{p_v} integer{'s' if p_v != 1 else ''}"
    try:  # the elements as given: np.asarray would turn [0, True] into [0, 1]
        items = groups.tolist() if isinstance(groups, np.ndarray) else list(groups)
    except TypeError:
        items = None
    if isinstance(groups, (str, bytes, dict, set)) or not isinstance(items, list):
        raise GPMSAError(f"discrepancy_groups must be a sequence of {count}, got {groups!r:.80}")
    if len(items) != p_v:
        raise GPMSAError(
            f"discrepancy_groups must give one group per discrepancy basis vector: {count}, "
            f"got {len(items)} entries"
        )
    if not all(isinstance(g, int | np.integer) and not isinstance(g, bool) for g in items):
        raise GPMSAError(
            f"discrepancy_groups must be integers (not floats or bools), got {items!r:.80}"
        )
    used = sorted({int(g) for g in items})
    if used[0] < 0:
        raise GPMSAError(f"discrepancy_groups must be >= 0, got {items}")
    if used != list(range(len(used))):
        hint = ("GPM/SA's lamVzGroup counts from 1: subtract 1"
                if used == list(range(1, len(used) + 1))
                else f"{len(used)} groups numbered up to {used[-1]}")  # fmt: skip
        raise GPMSAError(
            f"discrepancy_groups must number the groups 0 .. G-1, each used at least once; got "
            f"{items} ({hint})"
        )
    return None if len(used) == 1 else tuple(int(g) for g in items)


def n_groups(groups: tuple[int, ...] | None) -> int:
    """Number of discrepancy precision groups (1 for None)."""
    return 1 if groups is None else max(groups) + 1


def sample_names(p: int, n_grp: int) -> tuple[list[str], list[str]]:
    """The posterior names of betaV's elements (input-major: betaV[k,g] for k, then g) and of
    lamVz's, for ``p`` known inputs and ``n_grp`` groups."""
    if n_grp == 1:
        return (["betaV"] if p == 1 else [f"betaV[{k}]" for k in range(p)]), ["lamVz"]
    beta = [f"betaV[{k},{g}]" for g in range(n_grp) for k in range(p)]
    return beta, [f"lamVz[{g}]" for g in range(n_grp)]


def to_samples(beta_v: np.ndarray, lam_vz: np.ndarray) -> dict[str, np.ndarray]:
    """Posterior samples from draws betaV (*lead, p, G) and lamVz (*lead, G)."""
    p, n_grp = beta_v.shape[-2:]
    bnames, lnames = sample_names(p, n_grp)
    out = {}
    for i, name in enumerate(bnames):
        k, g = i % p, i // p
        out[name] = np.array(beta_v[..., k, g], dtype=np.float64)
    for g, name in enumerate(lnames):
        out[name] = np.array(lam_vz[..., g], dtype=np.float64)
    return out


def has_draws(names) -> bool:
    """Whether posterior ``names`` include discrepancy precisions ("lamVz" or "lamVz[g]")."""
    return any(re.fullmatch(r"lamVz(\[\d+\])?", name) for name in names)


def groups_of(samples, p: int) -> int:
    """Number of groups whose discrepancy names ``samples`` (a name -> draws mapping) holds
    in full for ``p`` known inputs; 0 when it holds none; GPMSAError when it holds some."""
    present = [k for k in samples if NAME_PATTERN.fullmatch(k)]
    if not present:
        return 0
    n_grp = 1 if "lamVz" in samples else sum(1 for k in samples if re.fullmatch(r"lamVz\[\d+\]", k))
    if n_grp:
        bnames, lnames = sample_names(p, n_grp)
        if sorted(present) == sorted(bnames + lnames):
            return n_grp
    raise GPMSAError(
        f"the posterior's discrepancy draws {sorted(present)} are not those of a discrepancy "
        f"with {p} known input(s): betaV or betaV[k] and lamVz for one precision group, "
        "betaV[k,g] and lamVz[g] for several"
    )


def params_at(samples, p: int, n_grp: int, i: int) -> tuple[np.ndarray, np.ndarray]:
    """Draw ``i`` of ``samples`` as betaV (p, G) and lamVz (G,)."""
    bnames, lnames = sample_names(p, n_grp)
    beta = np.array([float(samples[k][i]) for k in bnames]).reshape(n_grp, p).T
    return beta, np.array([float(samples[k][i]) for k in lnames])


def record(obs) -> dict:
    """What a fit or calibration records of its discrepancy (``obs``: an ObsProblem with a
    basis): the bases' and groups' digest, and the groups where there are several, so that
    ``gpmsa.full_prediction`` refuses another basis or grouping and finds the groups."""
    out = {"discrepancy_sha256": basis_digest(obs.D, obs.v_groups)}
    if obs.v_groups is not None:
        out["discrepancy_groups"] = list(obs.v_groups)
    return out


def scale_record(kind, source: dict | None = None) -> dict:
    """What a joint fit records of a discrepancy basis given as an array or a list (``kind``,
    as given to the fit; the reduction checked it): "discrepancy_scale", the number its
    normalisation divided it by (`gpmsa.model.basis.basis_scale`), with which
    ``gpmsa.full_prediction(grid_discrepancy=)`` normalises the same basis functions on
    another grid, the kept (normalised) bases given; {} for the other kinds. A continuation
    (``source``: its source's settings, whose basis it has up to scale, signs and order) keeps
    the source's where that records one (the kept bases, or a multiple, may be given to it);
    where it records none (a file written before the record), a basis given normalised (its
    scale 1), perhaps the source's kept bases, records none: the scale is not known."""
    if kind is None or isinstance(kind, str):
        return {}
    if source is not None and source.get("discrepancy_scale") is not None:
        return {"discrepancy_scale": source["discrepancy_scale"]}
    scale = basis_scale(given_bases(kind))
    if source is not None and math.isclose(scale, 1.0, rel_tol=SCALE_TOL):
        return {}
    return {"discrepancy_scale": scale}


def kept_bases(obs, kind) -> tuple[np.ndarray, ...] | None:
    """The normalised per-experiment bases (``obs.D``, ``obs`` an ObsProblem or None) that a
    fit keeps with its emulator and file: those of a ``kind`` given as a list of per-experiment
    bases (`gpmsa.model.basis.discrepancy_bases`), which ``gpmsa.full_prediction`` then uses;
    None for the other kinds, which it rebuilds (a named kind) or is given again (an array)."""
    if obs is None or obs.D is None or not is_basis_list(kind):
        return None
    return tuple(obs.D)
