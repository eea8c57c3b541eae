"""Why Sigma_W fails to factor in float64, and what to do: one message for every entry.

Sigma_W_j = R(zt; betaU_j) / lamUz_j + (1 / (lam_sim_j lamWOs) + 1 / lamWs_j) I. Its smallest
eigenvalue is at least the nugget 1 / (lam_sim_j lamWOs) + 1 / lamWs_j, but the correlation
matrix R of many runs with long correlation lengths (rho near 1), or of runs that nearly
coincide, is singular to rounding, so where the nugget falls to ~1e-14 of the GP variance
1 / lamUz_j the Cholesky factorisation fails. GPM/SA's priors bound lamWs and lamWOs by 1e5 (a
nugget of at least 1e-5 of the scale), where it never fails; wider bounds or held values far
beyond them can leave an emulator (its point estimate, a draw, a chain's start) that cannot be
factored. ``not_positive_definite`` names the component, the nugget against the variance and
the remedy.
"""

from __future__ import annotations

import numpy as np

from gpmsa.model.correlation import correlation
from gpmsa.model.data import array_text
from gpmsa.model.likelihood import lower_cholesky


def not_positive_definite(component: int, params: dict, lam_sim, m: int, where: str) -> str:
    """The refusal's text for Sigma_W of ``component`` not positive definite in float64 at
    ``params`` (betaU (p + q, p_u), lamUz (p_u,), lamWs (p_u,), lamWOs (1,); unit scale), over
    ``m`` runs whose projections have precisions ``lam_sim`` (p_u,); ``where`` says at which
    parameters (e.g. "at the emulator's parameters")."""
    j = component
    lam_uz = float(np.ravel(params["lamUz"])[j])
    lam_ws = float(np.ravel(params["lamWs"])[j])
    lam_wos = float(np.ravel(params["lamWOs"])[0])
    var = 1.0 / lam_uz
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        nug = float(1.0 / (float(np.ravel(lam_sim)[j]) * lam_wos) + 1.0 / lam_ws)
    beta = np.asarray(params["betaU"], dtype=float)[:, j]
    return (
        f"Sigma_W of basis component {j} is not positive definite in float64 {where}: its "
        f"nugget 1/lamWs + 1/(lam_sim lamWOs) = {nug:.3g} (lamWs {lam_ws:.3g}, lamWOs "
        f"{lam_wos:.3g}) is {nug / var:.2g} of the GP variance 1/lamUz = {var:.3g}, too little "
        f"to keep the correlation matrix of the {m} runs (betaU[:, {j}] = "
        f"{array_text(beta, precision=3, linewidth=200, threshold=8)}) positive "
        "definite to rounding (long correlation lengths against the runs' spacing, or runs "
        "that nearly coincide, make it near-singular). Keep lamWs and lamWOs within GPM/SA's "
        "bounds (their priors' upper bound 1e5, a nugget of at least 1e-5), or hold them at "
        "smaller values (fixed=)"
    )


def failing_component(
    zt: np.ndarray, params: dict, lam_sim, categorical=None, components=None
) -> int | None:
    """The first basis component (of ``components``; None: all) whose Sigma_W at ``params``
    (unit scale) over the runs ``zt`` (m, p + q) does not factor in float64 (as
    ``Emulator.predict`` factors it), or None."""
    m = zt.shape[0]
    lam_wos = float(np.ravel(params["lamWOs"])[0])
    if components is None:
        components = range(np.ravel(params["lamUz"]).size)
    for j in components:
        S = correlation(zt, None, params["betaU"][:, j], categorical) / params["lamUz"][j]
        S[np.diag_indices(m)] += 1.0 / (lam_sim[j] * lam_wos) + 1.0 / params["lamWs"][j]
        if not np.all(np.isfinite(S)) or lower_cholesky(S) is None:
            return j
    return None
