"""Shared theta: a beam's static deflection and its vibration frequency share Young's modulus.

    python examples/shared_theta.py                  # results in ./out/shared_theta
    python examples/shared_theta.py --out DIR --n-iter 2000 --seed 0

An aluminium cantilever (width b = 30 mm, thickness h = 5 mm, I = b h^3 / 12) is tested twice.

- Static test ("static"): a tip load P (known input, 5..50 N) on a beam of length 0.5 m; the
  tip deflection is d = P L^3 / (3 E I) (mm). Calibration parameter: Young's modulus E (GPa).
- Modal test ("modal"): beams of length L (known input, 0.3..0.8 m) ring at their first natural
  frequency f = (1.8751^2 / (2 pi L^2)) sqrt(E I / (rho b h)) (Hz). Calibration parameters: E
  and the density rho (kg/m^3). The frequency depends on E / rho only, so the modal test alone
  cannot tell E from rho: it pins their ratio.

Both tests share E. Calibrating them jointly (``gpmsa.calibrate_study(..., shared=["E"])``) lets
the static test fix E and, through the modal test's ratio, rho. Truth (the "real beam"): E = 69
GPa, rho = 2700 kg/m^3; deflections measured with 2 % noise, frequencies with 0.5 %.

Steps: simulator runs on Latin hypercubes; an emulator per test (``gpmsa.fit``, simulation only);
each test calibrated alone (``gpmsa.calibrate``); both calibrated together with E shared (the
emulators fixed); the two models fitted jointly with E shared (``gpmsa.fit_study``); the posterior
against the truth printed; the study saved (``Study.save``, read back by ``gpmsa.load_study``);
figures saved to --out.
"""

from __future__ import annotations

import argparse
import json
import warnings

import numpy as np
from _cli import (
    check_option_memory,
    check_seed,
    output_folder,
    path_option,
    run,
    save_figure,
    write_text,
)
from matplotlib.figure import Figure
from scipy.stats import qmc

import gpmsa

B, H = 0.030, 0.005  # m
INERTIA = B * H**3 / 12.0  # m^4
L_STATIC = 0.5  # m
E_RANGE, RHO_RANGE = (50.0, 90.0), (2000.0, 3500.0)  # GPa, kg/m^3
P_RANGE, L_RANGE = (5.0, 50.0), (0.3, 0.8)  # N, m
TRUTH = {"E": 69.0, "rho": 2700.0}
NOISE = {"static": 0.02, "modal": 0.005}  # relative sd


def deflection(P, E) -> np.ndarray:
    """Tip deflection (mm) of the static test under tip load P (N), modulus E (GPa)."""
    return 1e3 * np.asarray(P) * L_STATIC**3 / (3.0 * np.asarray(E) * 1e9 * INERTIA)


def frequency(L, E, rho) -> np.ndarray:
    """First natural frequency (Hz) of a cantilever of length L (m), E (GPa), rho (kg/m^3)."""
    L, E, rho = (np.asarray(a, dtype=float) for a in (L, E, rho))
    return 1.8751**2 / (2 * np.pi * L**2) * np.sqrt(E * 1e9 * INERTIA / (rho * B * H))


def _span(u: np.ndarray) -> np.ndarray:
    """A design column stretched to reach 0 and 1: a shared parameter needs the same range in
    every model's design (its unit scale must mean the same value)."""
    return (u - u.min()) / np.ptp(u)


def simulations(m_static: int, m_modal: int, seed: int) -> tuple[gpmsa.SimData, gpmsa.SimData]:
    """Latin-hypercube runs of both simulators (E spanning E_RANGE in both)."""
    u = qmc.LatinHypercube(d=2, seed=seed).random(m_static)
    u[:, 1] = _span(u[:, 1])
    P = P_RANGE[0] + u[:, 0] * np.ptp(P_RANGE)
    E = E_RANGE[0] + u[:, 1] * np.ptp(E_RANGE)
    static = gpmsa.SimData(x=P[:, None], t=E[:, None], y=deflection(P, E)[:, None],
                           x_names=["P"], t_names=["E"], y_names=["deflection"],
                           x_units=["N"], t_units=["GPa"], y_units=["mm"])  # fmt: skip
    v = qmc.LatinHypercube(d=3, seed=seed + 1).random(m_modal)
    v[:, 1] = _span(v[:, 1])
    L = L_RANGE[0] + v[:, 0] * np.ptp(L_RANGE)
    E = E_RANGE[0] + v[:, 1] * np.ptp(E_RANGE)
    rho = RHO_RANGE[0] + v[:, 2] * np.ptp(RHO_RANGE)
    modal = gpmsa.SimData(x=L[:, None], t=np.column_stack([E, rho]),
                          y=frequency(L, E, rho)[:, None], x_names=["L"], t_names=["E", "rho"],
                          y_names=["f1"], x_units=["m"], t_units=["GPa", "kg/m^3"],
                          y_units=["Hz"])  # fmt: skip
    return static, modal


def experiments(rng: np.random.Generator) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The real beam's measurements: (x_obs, y_obs) of each test."""
    P = np.array([10.0, 20.0, 30.0, 40.0, 45.0])[:, None]
    d = deflection(P, TRUTH["E"]) * (1 + NOISE["static"] * rng.standard_normal(P.shape))
    L = np.array([0.35, 0.5, 0.65, 0.75])[:, None]
    f = frequency(L, TRUTH["E"], TRUTH["rho"])
    f = f * (1 + NOISE["modal"] * rng.standard_normal(L.shape))
    return {"static": (P, d), "modal": (L, f)}


COLOURS = {"static alone": "C0", "modal alone": "C1", "shared (emulators fixed)": "C2",
           "shared (joint fit)": "C3"}  # fmt: skip
"""One colour per posterior in every figure (the rho panel has no "static alone")."""


def _hist(ax, draws: dict[str, np.ndarray], truth: float, label: str) -> None:
    for name, d in draws.items():
        ax.hist(d, bins=40, density=True, histtype="step", label=name, color=COLOURS[name])
    ax.axvline(truth, color="k", ls="--", label="truth")
    ax.set_xlabel(label)
    ax.set_ylabel("posterior density")
    ax.legend(fontsize=8)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=path_option, default="out/shared_theta",
        help="folder for the results (default ./out/shared_theta)",
    )  # fmt: skip
    parser.add_argument(
        "--n-iter", type=int, default=2000, help="MCMC sweeps after tuning (default 2000)"
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="seed of the runs, data and fits (default 0)"
    )
    args = parser.parse_args(argv)
    if args.n_iter < 2:
        parser.error(f"--n-iter must be >= 2 (gpmsa.fit), got {args.n_iter}")
    sweep = 8.0 * 2 * 4  # bytes a sweep keeps, at least: E, lamOs and the emulator's
    check_option_memory(parser, sweep * args.n_iter, f"--n-iter {args.n_iter}: the draws")
    check_seed(parser, args.seed, offset=1)
    out = output_folder(parser, "--out", args.out)
    rng = np.random.default_rng(args.seed)
    static, modal = simulations(24, 40, args.seed)
    data = experiments(rng)
    n, burn = args.n_iter, args.n_iter // 5

    print(
        "fitting the two emulators (short single chains): with the defaults (--seed 0, "
        "--n-iter 2000) gpmsa warns (ConvergenceWarning) of each fit and later of the shared "
        "calibration: R-hat 1.013-1.025, a little short; a larger --n-iter runs longer chains.",
        flush=True,
    )
    emus = {k: gpmsa.fit(sim, n_iter=n, seed=args.seed + i, n_chains=1)
            for i, (k, sim) in enumerate((("static", static), ("modal", modal)))}  # fmt: skip
    print(
        "calibrating each test alone: the modal test alone cannot separate E from rho (it pins "
        "E / rho only), so its chain wanders along that ridge and gpmsa warns of it (with the "
        "defaults E and rho R-hat ~1.37, ESS 7). Expected: the wide 'modal alone' row below, "
        "which sharing E removes.",
        flush=True,
    )
    alone = {k: gpmsa.calibrate(emus[k], *data[k], n_samples=n, n_burn=burn, seed=args.seed)
             for k in emus}  # fmt: skip
    study = gpmsa.calibrate_study(
        [emus["static"], emus["modal"]], [data["static"][0], data["modal"][0]],
        [data["static"][1], data["modal"][1]], labels=["static", "modal"], shared=["E"],
        n_samples=n, n_burn=burn, seed=args.seed, metadata={"example": "shared_theta.py"},
    )  # fmt: skip
    with warnings.catch_warnings():  # a short joint fit of few runs: designs near their edges
        warnings.simplefilter("ignore", UserWarning)
        joint = gpmsa.fit_study(
            [static, modal], [gpmsa.ObsData(*data["static"]), gpmsa.ObsData(*data["modal"])],
            labels=["static", "modal"], shared=["E"], n_iter=n, seed=args.seed,
        )  # fmt: skip
    study.save(out / "beam_study.gpmsa")
    back = gpmsa.load_study(out / "beam_study.gpmsa")

    rows = {
        "static alone": {"E": alone["static"].samples["E"]},
        "modal alone": {"E": alone["modal"].samples["E"], "rho": alone["modal"].samples["rho"]},
        "shared (emulators fixed)": {"E": back.posterior.samples["E"],
                                     "rho": back.posterior.samples["rho[modal]"]},
        "shared (joint fit)": {"E": joint.posterior.samples["E"],
                               "rho": joint.posterior.samples["rho[modal]"]},
    }  # fmt: skip
    summary: dict[str, dict] = {"truth": TRUTH, "posterior": {}}
    lines = [f"{'':26s} {'E [GPa] mean  90% interval':32s} {'rho [kg/m^3] mean  90% interval'}"]
    for label, draws in rows.items():
        cells, rec = [], {}
        for name in ("E", "rho"):
            if name not in draws:
                cells.append(f"{'-':>9s}{'':23s}")
                continue
            d = draws[name]
            lo, hi = np.quantile(d, [0.05, 0.95])
            rec[name] = {"mean": float(d.mean()), "sd": float(d.std()), "q05": float(lo),
                         "q95": float(hi)}  # fmt: skip
            cells.append(f"{d.mean():9.4g}  [{lo:8.4g}, {hi:8.4g}]      ")
        summary["posterior"][label] = rec
        lines.append(f"{label:26s} " + " ".join(cells))
    lines.append(f"{'truth':26s} {TRUTH['E']:9.4g}{'':23s} {TRUTH['rho']:9.4g}")
    # the table is printed after the files: a reader that stops reading (`... | head`) ends the
    # script at a print

    fig = Figure(figsize=(10, 4))
    ax1, ax2 = fig.subplots(1, 2)
    _hist(ax1, {k: v["E"] for k, v in rows.items()}, TRUTH["E"], "E [GPa]")
    _hist(ax2, {k: v["rho"] for k, v in rows.items() if "rho" in v}, TRUTH["rho"],
          "rho [kg/m^3]")  # fmt: skip
    fig.suptitle("Posterior of the shared modulus E and the modal test's density")
    fig.tight_layout()
    save_figure(fig, out / "posterior_E_rho.png")
    fig = Figure(figsize=(5, 4.5))
    ax = fig.subplots()
    for label in ("modal alone", "shared (emulators fixed)"):
        ax.plot(rows[label]["E"][::4], rows[label]["rho"][::4], ".", ms=2, label=label,
                color=COLOURS[label])  # fmt: skip
    ax.plot(TRUTH["E"], TRUTH["rho"], "k*", ms=12, label="truth")
    ax.set_xlabel("E [GPa]")
    ax.set_ylabel("rho [kg/m^3]")
    ax.legend(fontsize=8)
    ax.set_title("The modal test alone pins E / rho; sharing E pins both")
    fig.tight_layout()
    save_figure(fig, out / "pairs_E_rho.png")
    fig = Figure(figsize=(8, 3))
    ax = fig.subplots()
    chains = back.posterior.chains
    assert chains is not None, "a study's posterior has its MCMC chains"
    for name in ("E", "rho[modal]"):
        ch = chains[name][0]
        # a short chain may not move at all (sd 0): drawn flat at 0, not as NaN
        ax.plot((ch - ch.mean()) / (ch.std() or 1.0), lw=0.5, label=name)
    ax.set_xlabel("sweep (after burn-in)")
    ax.set_ylabel("standardised draw")
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, out / "traces.png")
    write_text(out / "summary.json", json.dumps(summary, indent=1))
    print("\n".join(lines))
    print(f"wrote the study (beam_study*.gpmsa), the figures and summary.json to {out}")
    return summary


if __name__ == "__main__":
    run(main)
