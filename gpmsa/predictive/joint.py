"""A joint fit's calibration draws as a ``gpmsa.Posterior`` (no wrapping by hand)."""

from __future__ import annotations

import numpy as np

from gpmsa._fp_state import underflow_as_zero
from gpmsa.calibration.observations import emulator_record, theta_levels_native
from gpmsa.calibration.posterior import Posterior
from gpmsa.errors import GPMSAError
from gpmsa.mcmc.bounds import at_bound
from gpmsa.model.discrepancy import to_samples


@underflow_as_zero
def calibration_posterior(emulator) -> Posterior:
    """The calibration draws of a joint fit (``gpmsa.fit(data, obs, ...)``) as a Posterior.

    Samples (native units): each calibration parameter under its name in ``emulator.t_names``,
    ``lamOs``, and with a discrepancy ``lamVz`` and ``betaV`` (``betaV[k]`` per known input when
    p > 1; with several precision groups ``lamVz[g]`` and ``betaV[k,g]``,
    `gpmsa.model.discrepancy`). ``chains`` splits the retained draws into the fit's chains, so
    ``to_arviz()``, ``summary()`` (with ESS) and ``plot()`` work as for ``gpmsa.calibrate``.
    ``info`` carries the fit's discrepancy record ("discrepancy", "discrepancy_sha256",
    "discrepancy_groups" where there are several groups, "discrepancy_scale" for an array or
    a list) and its record of its observations
    ("obs_lengths", "obs_sha256"), so that ``gpmsa.full_prediction(..., posterior=)`` refuses
    other ones, as it does without it, and the emulator's ``model_sha256`` ("emulator_sha256"),
    so that it refuses another emulator; a fit with ``fixed=`` of calibration parameters,
    "held": the names held (``summary()``'s "held", as ``gpmsa.calibrate`` records them);
    "at_bound": the calibration parameters piled against a bound of the emulator's domain,
    as ``gpmsa.calibrate`` records them (``gpmsa.fit`` warned of them).

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
        >>> data = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["x"], t_names=["t"])
        >>> obs = gpmsa.ObsData(x=[[0.2], [0.8]], y=[[0.5], [1.1]])
        >>> emu = gpmsa.fit(data, obs, n_iter=50, tune=False, seed=0)
        >>> post = gpmsa.calibration_posterior(emu)
        >>> post.names
        ('t', 'lamOs')
        >>> 0.0 <= post.mean("t") <= 1.0
        True
    """
    if not hasattr(emulator, "calibration"):
        hint = " (a study: study.member_posterior(model))" if hasattr(emulator, "members") else ""
        raise GPMSAError(f"calibration_posterior needs a gpmsa.Emulator of a joint fit, got "
                         f"{type(emulator).__name__}{hint}")  # fmt: skip
    cal = emulator.calibration
    if not cal:
        raise GPMSAError(
            "this emulator has no calibration draws: it was fitted without observations "
            "(gpmsa.fit(data, obs, ...) samples theta jointly); calibrate it with "
            "gpmsa.calibrate or gpmsa.Calibrator instead"
        )
    theta = np.asarray(cal["theta_native"], dtype=float)
    samples = {name: theta[:, k].copy() for k, name in enumerate(emulator.t_names)}
    samples["lamOs"] = np.asarray(cal["lamOs"], dtype=float).reshape(theta.shape[0], -1)[:, 0]
    if "lamVz" in cal:
        lam_vz = np.asarray(cal["lamVz"], dtype=float).reshape(theta.shape[0], -1)
        rows, n_grp = lam_vz.shape
        beta_v = np.asarray(cal["betaV"], dtype=float).reshape(rows, emulator.p, n_grp)
        samples.update(to_samples(beta_v, lam_vz))
    n_chains = int(emulator.settings.get("n_chains", 1) or 1)
    n = theta.shape[0]
    per = n // n_chains
    chains = None
    if per >= 2 and per * n_chains == n:
        chains = {k: v.reshape(n_chains, per) for k, v in samples.items()}
    info = {
        "method": "joint fit",
        "names": list(samples),
        "n_chains": n_chains,
        **emulator_record(emulator),
        **{k: emulator.settings[k] for k in ("n_iter", "n_burn", "thin", "seed", "backend",
                                              "discrepancy", "discrepancy_sha256",
                                              "discrepancy_groups", "discrepancy_scale",
                                              "obs_lengths", "obs_sha256")
           if k in emulator.settings},
    }  # fmt: skip
    shapes = {"theta": (len(emulator.t_names),), "lamOs": (1,)}
    if "lamVz" in cal:
        shapes.update(betaV=(emulator.p, n_grp), lamVz=(n_grp,))
    held = fixed_calibration_names(emulator.settings.get("fixed"), emulator.t_names, shapes)
    if held:  # fixed=: as calibrate records it (Posterior.summary's "held")
        info["held"] = held
    codes = theta_levels_native(emulator)
    if codes:  # a categorical theta: its quantiles are levels (as calibrate's)
        info["levels"] = codes
    std = emulator.standardizer  # piled against a bound (gpmsa.fit warned of it)
    info["at_bound"] = at_bound(samples, emulator.t_names, std.t_min, std.t_max, {*held, *codes})
    return Posterior(samples, chains=chains, info=info)


def fixed_calibration_names(fixed, t_names, shapes: dict[str, tuple[int, ...]]) -> list[str]:
    """The posterior names (``calibration_posterior``'s) of the calibration parameters a fit's
    ``settings["fixed"]`` (``fixed``: name -> values held whole, or {"elements": [index, ...],
    "values": [...]}) holds, of those in ``shapes`` (name -> shape: theta, lamOs, and with a
    discrepancy betaV, lamVz); [] for none."""
    masks = {}
    for name, shape in shapes.items():
        rec = (fixed or {}).get(name)
        if rec is None:
            continue
        masks[name] = np.zeros(shape, dtype=bool)
        if isinstance(rec, dict):
            for idx in rec.get("elements", ()):
                masks[name][tuple(idx)] = True
        else:
            masks[name][...] = True
    out = [t_names[k] for k in np.flatnonzero(masks.get("theta", []))]
    out += ["lamOs"] if masks.get("lamOs", np.zeros(1, bool)).any() else []
    if "lamVz" in shapes:
        shown = to_samples(*(masks.get(k, np.zeros(shapes[k], bool)) for k in ("betaV", "lamVz")))
        out += [k for k, v in shown.items() if v]
    return out
