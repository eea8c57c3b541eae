"""What the draw-based predictions share: input checks, parameter sets, the GP of the weights.

Everything here works on GPM/SA's scales (unit inputs, standardised outputs); the public modules
(``emulator_draws``, ``full``, ``sobol``, ``crossval``) convert at their edges.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.linalg import cho_solve, solve_triangular

from gpmsa.errors import FewDrawsWarning, GPMSAError, user_stacklevel
from gpmsa.fitting.emulator import NO_DRAWS, Emulator
from gpmsa.model import kronecker
from gpmsa.model.categorical import check_levels
from gpmsa.model.correlation import correlation
from gpmsa.model.data import (
    as_float,
    as_matrix,
    by_column_names,
    check_count,
    check_probabilities,
    check_seed,
    evenly_spaced,
)
from gpmsa.model.likelihood import lower_cholesky
from gpmsa.model.mean_basis import KINDS as MEAN_BASIS_KINDS
from gpmsa.model.nugget import not_positive_definite
from gpmsa.model.transforms import check_extrapolation, snap_to_unit

EMULATOR_PARAMS = ("betaU", "lamUz", "lamWs", "lamWOs")


def realization_interval(samples: np.ndarray, level: float, fix: str) -> tuple[np.ndarray, ...]:
    """Central interval of probability ``level`` (checked by the caller) from the quantiles of
    the realizations along axis 0. Fewer than 2 / (1 - level) realizations cannot resolve its
    tails (one draw gives an interval of width 0): then a warning that it is too narrow, saying
    how to draw more (``fix``)."""
    n, need = samples.shape[0], int(np.ceil(2.0 / (1.0 - level) - 1e-9))
    if n < need:
        warnings.warn(
            f"a central {level:g} interval from {n} realization(s) is too narrow: its tails need "
            f"at least {need}; draw more ({fix})",
            FewDrawsWarning,
            stacklevel=user_stacklevel(),
        )
    lo, hi = realization_quantile(samples, [(1 - level) / 2, (1 + level) / 2])
    return lo, hi


def realization_quantile(samples: np.ndarray, q) -> np.ndarray:
    """The realizations' quantiles along axis 0 at probabilities ``q`` in [0, 1] (a number or
    an array of them, checked: GPMSAError naming q), numpy's default (linear) rule: shape
    ``np.shape(q) + samples.shape[1:]``; `realization_interval`'s ends are these at
    (1 -+ level) / 2."""
    return np.quantile(samples, check_probabilities(q, "q"), axis=0)


def rng_of(seed) -> np.random.Generator:
    """A Generator from an integer in [0, 2**128), a Generator or None (``check_seed``)."""
    seed = check_seed(seed, generator=True)
    return seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)


def unit_inputs(
    values, names, lo, hi, what: str, levels=None, extrapolate: bool | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Native rows (N, d) -> (native, unit scale), with the library's extrapolation rule.

    A 1-D array is one column when d = 1 and one row otherwise; a number one point when d = 1
    (as ``gpmsa.calibrate`` takes x_obs). Inside the design range: silent;
    up to ``EXTRAPOLATION_MARGIN`` of the range outside it: a warning; beyond: GPMSAError naming
    ``what``, the input, the values and the domain (``check_extrapolation``; ``extrapolate``:
    the caller's option of that name, None where it has none; False: the message points at it;
    True: the warning at any distance, as ``gpmsa.calibrate(extrapolate=True)`` takes x_obs).
    With no inputs (d = 0, an emulator without known inputs) None, or an (N, 0) array, is one
    row of no columns (broadcast against t's rows).
    ``levels``: per column the training levels of a categorical input, None for a continuous
    one (``gpmsa.model.categorical``): a level never seen in training is refused first, as
    ``Emulator.predict`` does.
    """
    d = len(names)
    if d == 0 and values is None:
        values = np.empty((1, 0))
    values = by_column_names(values, names, what)
    try:
        ndim = np.ndim(values)
    except ValueError:  # a ragged list: as_matrix refuses it by name, with its lengths
        ndim = -1
    if (d > 1 and ndim == 1 and np.size(values) == d) or (d == 1 and ndim == 0):
        values = as_float(values, what).reshape(1, -1)  # a dict is refused by its own name
    native = as_matrix(values, what, ncols=d, no_columns=d == 0)
    if levels is not None and any(lv is not None for lv in levels):
        check_levels(native, levels, names, what)
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    unit = snap_to_unit((native - lo) / (hi - lo))
    check_extrapolation(native, unit, names, lo, hi, what, extrapolate)  # the user's line
    return native, unit


def posterior_theta(emulator, theta: np.ndarray) -> np.ndarray:
    """Unit-scale theta (k, q) of native posterior draws (k, q), under the rule of
    ``Emulator.predict``: outside the emulator's t domain a warning, beyond it by more than
    ``EXTRAPOLATION_MARGIN`` a GPMSAError naming the parameter; a categorical one off its
    training levels: GPMSAError."""
    s, levels = emulator.standardizer, tuple(getattr(emulator, "levels", ()))[emulator.p :]
    return unit_inputs(theta, emulator.t_names, s.t_min, s.t_max, "posterior theta", levels)[1]


def lacks_text(missing: list[str], names) -> str:
    """The message for a posterior without the draws ``missing`` (it has ``names``); where it
    holds them per model ("t[model]", a study's pooled posterior), it points to
    ``study.member_posterior``."""
    text = f"posterior lacks {missing}; it has {tuple(names)}"
    if any(str(n).startswith(f"{k}[") for k in missing for n in names):
        text += (" (a study's pooled posterior names each model's parameters 'name[model]': "
                 "pass study.member_posterior(model))")  # fmt: skip
    return text


def posterior_lamos(posterior, idx: np.ndarray | None = None) -> np.ndarray:
    """The posterior's lamOs draws (those at ``idx``; None: all); GPMSAError when it has none
    or one is not a finite precision > 0 (1/lamOs is the observation-error variance)."""
    if "lamOs" not in posterior.names:
        raise GPMSAError(f"the posterior lacks lamOs (the observation precision); it has "
                         f"{posterior.names}")  # fmt: skip
    lam = np.asarray(posterior.samples["lamOs"], dtype=np.float64).reshape(-1)
    lam = lam if idx is None else lam[idx]
    bad = np.flatnonzero(~(np.isfinite(lam) & (lam > 0)))
    if bad.size:
        raise GPMSAError(f"the posterior's lamOs draws must be finite and > 0 (a precision), got "
                         f"{float(lam[bad[0]])!r}")  # fmt: skip
    return lam


def check_posterior_emulator(emulator, posterior) -> None:
    """GPMSAError when ``posterior`` recorded the emulator it was drawn with (info
    "emulator_sha256": that emulator's ``Emulator.model_sha256``, as ``gpmsa.calibrate``,
    ``Calibrator.update``, ``calibration_posterior`` and ``Study.member_posterior`` record it)
    and ``emulator`` is another one: its draws would be mixed with another emulator's
    predictive; or is no gpmsa.Emulator (it has no ``model_sha256``). A posterior without the
    record (made by hand, by older code, or from an object with only the attributes
    calibration checks for) is taken."""
    info = getattr(posterior, "info", None) or {}
    recorded = info.get("emulator_sha256")
    own = getattr(emulator, "model_sha256", None)
    if not isinstance(recorded, str) or recorded == own:
        return
    if not isinstance(own, str):  # not a gpmsa.Emulator: no fingerprint to compare
        raise GPMSAError(
            "posterior= records the gpmsa.Emulator it was drawn with (info 'emulator_sha256'); "
            f"emulator must be that gpmsa.Emulator, got {type(emulator).__name__}"
        )
    model = info.get("model")
    whose = f" (study model {model!r})" if isinstance(model, str) else ""
    raise GPMSAError(
        f"posterior= was drawn with another emulator{whose} (model_sha256 {recorded[:12]}..., "
        f"this emulator's {own[:12]}...): pass the emulator it was calibrated with"
    )


def paired_draws(emulator, posterior, what: str) -> np.ndarray:
    """(n,) per posterior sample, the position in ``emulator.draws`` of the emulator parameters
    drawn jointly with it: ``info["emulator_draws"]`` (``gpmsa.calibrate(...,
    emulator_params="draws")``, a ``Calibrator(..., emulator_params="draws")`` update's), or
    draw i for sample i where the posterior's theta draws are the emulator's own joint-fit
    draws (``calibration_posterior``, a ``fit_study`` member's). GPMSAError where the emulator
    kept no draws or the posterior holds none jointly with theta (one calibrated at the point
    estimate, ``calibrate_study``'s: the message says which)."""
    kept = emulator.n_draws if getattr(emulator, "draws", None) else 0
    if kept == 0:
        raise GPMSAError(f"{what} with draws=True needs the emulator's retained draws, but this "
                         f"emulator kept none {NO_DRAWS}; pass draws=False")  # fmt: skip
    names = tuple(emulator.t_names)
    n = np.size(posterior.samples[names[0]])
    recorded = posterior.info.get("emulator_draws")
    if recorded is not None:
        pos = np.asarray(recorded)
        if (pos.shape != (n,) or pos.dtype.kind not in "iu" or (n and not (
                0 <= pos.min() and pos.max() < kept))):  # fmt: skip
            raise GPMSAError(
                f"posterior info['emulator_draws'] must hold one position in the emulator's "
                f"{kept} retained draws per sample ({n}), got shape {pos.shape}, dtype {pos.dtype}"
            )
        return pos
    cal = getattr(emulator, "calibration", None)
    if cal and n == kept:
        theta = np.asarray(cal["theta_native"], dtype=float)
        own = all(np.array_equal(np.asarray(posterior.samples[k], dtype=float), theta[:, j])
                  for j, k in enumerate(names))  # fmt: skip
        if own:
            return np.arange(n)
    why = ("its theta draws are not this emulator's joint-fit draws" if cal else
           "this emulator was fitted without observations, so it has no theta draws")  # fmt: skip
    same = "every theta draw with the same emulator parameters, so there is no draw to pair"
    use = ("gpmsa.calibration_posterior(emu) of a joint fit (gpmsa.fit(data, obs)), a posterior "
           "of gpmsa.calibrate(..., emulator_params='draws') or of gpmsa.Calibrator(emu, "
           "emulator_params='draws').update(...), or draws=False")  # fmt: skip
    if posterior.info.get("method") == "study calibration":
        source = f": gpmsa.calibrate_study calibrates at each model's point estimate, {same}"
        use = "study.member_posterior(...) of gpmsa.fit_study (joint fits, paired), " + use
    elif posterior.info.get("emulator_params") == "point":
        source = ": it was calibrated at the emulator's point estimate (emulator_params='point'), "
        source += same
    else:
        source = ""
    raise GPMSAError(
        f"{what} with draws=True pairs each theta draw with the emulator-parameter draw drawn "
        f"with it, but this posterior records none (info['emulator_draws']){source}; and {why}: "
        f"pass {use}"
    )


def gpmsa_model_only(emulator, what: str, *, callable_basis: bool = True) -> None:
    """GPMSAError when ``emulator`` is not a gpmsa.Emulator, or, where ``what`` integrates the
    mean over the inputs (``callable_basis`` False: only the named mean bases,
    ``MEAN_BASIS_KINDS``, have closed-form integrals), has a callable mean basis."""
    if not isinstance(emulator, Emulator):
        raise GPMSAError(f"{what} needs a gpmsa.Emulator, got {type(emulator).__name__}")
    basis = getattr(emulator, "mean_basis", None)
    if not callable_basis and basis is not None and basis.kind not in MEAN_BASIS_KINDS:
        raise GPMSAError(
            f"{what} supports the mean bases {MEAN_BASIS_KINDS}, not a callable one (its "
            "integrals over the inputs have no closed form); use Emulator.predict_mean"
        )


def draws_text(draw_index) -> str:
    """For a result's repr: "point estimate" for ``param_sets``'s index [-1], else "S draws"."""
    if list(np.ravel(draw_index)) == [-1]:
        return "point estimate"
    return f"{np.size(draw_index)} draws"


def param_sets(emulator, draws: bool, n_draws: int | None, what: str):
    """(indices, list of parameter dicts) the prediction averages over.

    ``draws=False``: the point estimate only (index -1). ``draws=True``: the retained posterior
    draws, or ``n_draws`` of them evenly spaced (``evenly_spaced``); GPMSAError when the
    emulator kept none.
    """
    if n_draws is not None:  # checked also where draws=False leaves it unused
        n_draws = check_count(n_draws, "n_draws")
    if not draws:
        return np.array([-1]), [emulator.params]
    n = emulator.n_draws if emulator.draws else 0
    if n == 0:
        raise GPMSAError(
            f"{what} with draws=True needs the emulator's retained posterior draws, but this "
            f"emulator kept none {NO_DRAWS}; pass draws=False to use its point estimate"
        )
    idx = evenly_spaced(n, n_draws)
    sets = [{k: np.asarray(emulator.draws[k][i]) for k in EMULATOR_PARAMS} for i in idx]
    return idx, sets


def factors(emulator, prm: dict) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per basis component j: (lower Cholesky factor of Sigma_W_j, Sigma_W_j^-1 w_j).

    Sigma_W_j = R(zt; betaU_j) / lamUz_j + (1 / (lam_sim_j lamWOs) + 1 / lamWs_j) I.
    """
    kronecker.check_dense(emulator, "this prediction (cross-validation, full or joint)")
    zt = emulator.zt
    out = []
    for j in range(emulator.p_u):
        S = correlation(zt, None, prm["betaU"][:, j]) / prm["lamUz"][j]
        S[np.diag_indices(emulator.m)] += (
            1.0 / (emulator.lam_sim[j] * prm["lamWOs"][0]) + 1.0 / prm["lamWs"][j]
        )
        L = lower_cholesky(S)
        if L is None:
            raise GPMSAError(
                not_positive_definite(
                    j, prm, emulator.lam_sim, emulator.m, "at these emulator parameters"
                )
            )
        L = np.tril(L)
        out.append((L, cho_solve((L, True), emulator.w[:, j])))
    return out


def extended(emulator) -> bool:
    """Whether ``emulator`` has categorical inputs or a mean basis (GPM/SA's model extended)."""
    basis = getattr(emulator, "mean_basis", None)
    return basis is not None or any(lv is not None for lv in getattr(emulator, "levels", ()))


def gp_factors(emulator, prm: dict) -> list[tuple]:
    """Per basis component j: (L, alpha, gls). An extended emulator (`extended`): its own
    ``Emulator._factor`` (the categorical kernel; with a mean basis alpha = Sigma_W_j^-1 (w_j -
    H c_j) and the ``GLS`` fit c_j, else gls None), as ``Emulator.predict``; otherwise
    `factors`' (L, Sigma_W_j^-1 w_j) with gls None."""
    if extended(emulator):
        return emulator._factor(prm)
    return [(L, alpha, None) for L, alpha in factors(emulator, prm)]


def w_conditional(emulator, prm: dict, fac, z: np.ndarray, joint: bool):
    """The smooth GP of the weights at unit-scale points z (N, p + q), given the runs' w.

    ``fac``: `gp_factors`' (L, alpha, gls) per component. Returns mean (N, p_u) and, per
    component, the variance (N, p_u) or (joint) the covariance (p_u, N, N); no nugget 1/lamWs
    and no residual 1/lamWOs. With a mean basis (gls not None) the GLS mean h(z) c_j joins the
    mean and the coefficients' covariance g^T (H^T Sigma^-1 H)^-1 g, g = h(z)^T - H^T
    Sigma^-1 r, the (co)variance, as ``Emulator.predict``; categorical inputs take their kernel.
    """
    N, p_u = z.shape[0], emulator.p_u
    mean = np.empty((N, p_u))
    spread = np.empty((p_u, N, N)) if joint else np.empty((N, p_u))
    cat = emulator.categorical_mask if extended(emulator) else None
    basis = getattr(emulator, "mean_basis", None)
    h = None if basis is None else basis.matrix(z)
    for j, (L, alpha, gls) in enumerate(fac):
        lam = prm["lamUz"][j]
        r = correlation(z, emulator.zt, prm["betaU"][:, j], cat) / lam
        mean[:, j] = r @ alpha
        B = solve_triangular(L, r.T, lower=True)
        if gls is not None:
            mean[:, j] += h @ gls.coef
        if joint:
            spread[j] = correlation(z, None, prm["betaU"][:, j], cat) / lam - B.T @ B
            if gls is not None:
                g = h.T - gls.A.T @ B
                spread[j] += g.T @ cho_solve(gls.Q, g)
        elif gls is None:
            spread[:, j] = np.maximum(1.0 / lam - np.sum(B * B, axis=0), 0.0)
        else:
            spread[:, j] = np.maximum(1.0 / lam - np.sum(B * B, axis=0) + gls.variance(h, B), 0.0)
    return mean, spread


def mvn_factor(cov: np.ndarray) -> np.ndarray:
    """A matrix A with A A^T = cov (Cholesky with a tiny jitter; eigenvalues clipped at 0)."""
    scale = max(float(np.mean(np.diag(cov))), 1e-300)
    for jitter in (1e-12, 1e-10, 1e-8):
        try:
            return np.linalg.cholesky(cov + jitter * scale * np.eye(cov.shape[0]))
        except np.linalg.LinAlgError:
            continue
    vals, vecs = np.linalg.eigh(0.5 * (cov + cov.T))
    return vecs * np.sqrt(np.clip(vals, 0.0, None))
