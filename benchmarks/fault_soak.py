"""Fault-injection soak of the closed loop (issue 15): random sensor faults on random tracks.

    PYTHONPATH=. python benchmarks/fault_soak.py              # 400 scenarios + the issue's examples
    PYTHONPATH=. python benchmarks/fault_soak.py --quick      # 20 scenarios + examples on seed 1
    PYTHONPATH=. python benchmarks/fault_soak.py --only 17    # one scenario, with its trace
    PYTHONPATH=. python benchmarks/fault_soak.py --help

Each scenario (seeded by ``--seed`` and its index) draws a random track (3-5 segments of 20-60 m,
GD uniform in [220, 580]), a noise case (alternating: A noise-free with
``control.shipped_emulator("A")``, B with noise_std = 1 m/s^2 and ``shipped_emulator("B")``) and
one `control.SensorFault`: the kind cycles through ``control.FAULT_KINDS`` (so that every kind
gets the same share of each case), the start is uniform over the clean run's duration, the
duration log-uniform in [0.05, 20] s, and the magnitude log-uniform over a fault-like range per
kind (spike: one every 1-60 samples; noise: sd 5-1e4 m/s^2; scale: 1e-4-0.05 or 20-1e4; quantize:
steps of 2-1000 m/s^2; clip: at 1e-3-2 m/s^2; the other kinds take none). The loop runs with and
without the fault (same track, same noise seed) and the scenario records any exception, the
distance driven faster than v_safe + 0.02 m/s where the prescribed GD > GD_max
(``metrics.fast_on_rough_m``) with and without the fault, over the whole run and while the fault
lasts (from its start to its end plus two blocks: what the fault handling itself decides), and
the statuses of the updates in that time.

Then the issue's concrete examples on the paper's track [(50, 300), (50, 500), (50, 300)] (rough
part 50-100 m; the fault starts when the clean run reaches 50 m, plus an offset), both cases,
seeds 1-3 (``--quick``: 1): spikes of 1e6 m/s^2, heavy added noise, the signal scaled by 1e-3,
coarse quantisation over the whole rough part, a partly stuck sensor, NaN time stamps and NaN
positions; and one extra example (not the issue's): all samples dropped for 20 s from 3 s
before the rough part.

The loop is chaotic: a perturbation of the samples far below anything a check could see (a gain
of 1 + 1e-9 over the fault's time, the "null" run, made for every random scenario) already
changes later estimates, speeds and so the fast-on-rough distance by metres either way. The
faults are therefore also compared with the null runs, per scenario (paired).

Printed (with the load average): scenarios run, crashes (with their exceptions), per fault kind
the scenarios whose faulted run drove farther too fast on rough ground than the clean one (how
many, the worst excess and its scenario) and the distribution of the difference (faulted minus
clean, m: the loop is chaotic, a fault that changes one estimate changes later speeds, so a
fault can also make a run safer), the same against the null runs, the statuses the faults
produced, the examples' table, and for the ``--explain`` worst scenarios (faster while the fault
lasts; faster over the whole run) the updates around the fault (faulted and clean), the
fast-on-rough distance per rough segment (clean, faulted, null) and the call that reproduces
them (with one BLAS thread: the soak's workers run with one, and a different thread count
changes the emulator's factors in the last bits, which the chaotic loop amplifies). Exits with
status 1 if any run crashed.

Run time: ~22 min for the default 400 scenarios on 2 workers (README.md's figures: ``--seed 37``
and the defaults); ``--scenarios 2 --no-examples`` ~10 s.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
import traceback
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field

import numpy as np
from _host import load_average
from scipy import stats

import control
import roadgen
from gpmsa.model.data import MAX_SEED

NOISE_STD = {"A": 0.0, "B": 1.0}
PAPER_TRACK = ((50.0, 300.0), (50.0, 500.0), (50.0, 300.0))
MAGNITUDE = {  # log-uniform ranges of the fault-like magnitudes
    "spike": ((1.0, 60.0),),
    "noise": ((5.0, 1e4),),
    "scale": ((1e-4, 0.05), (20.0, 1e4)),
    "quantize": ((2.0, 1000.0),),
    "clip": ((1e-3, 2.0),),
}
DURATION_S = (0.05, 20.0)
NULL_GAIN = 1.0 + 1e-9  # the null perturbation: a gain error no check can see
ROUGH_PART_S = 50.0  # the paper track's rough part lasts at most 50 m / v_safe = 50 s
EXAMPLES = (  # (name, kind, start after entering the rough part s, duration s, magnitude)
    ("spikes 1e6 every sample", "spike", 0.0, ROUGH_PART_S, 1.0),
    ("spikes 1e6 every 30th sample", "spike", 0.0, ROUGH_PART_S, 30.0),
    ("added noise sd 100", "noise", 0.0, ROUGH_PART_S, 100.0),
    ("added noise sd 1e4", "noise", 0.0, ROUGH_PART_S, 1e4),
    ("scaled by 1e-3", "scale", 0.0, ROUGH_PART_S, 1e-3),
    ("quantised to 5 m/s^2", "quantize", 0.0, ROUGH_PART_S, 5.0),
    ("quantised to 2 m/s^2", "quantize", 0.0, ROUGH_PART_S, 2.0),
    ("stuck 0.3 s, 10 s in", "stuck", 10.0, 0.3, 1.0),
    ("stuck 0.06 s, 10 s in", "stuck", 10.0, 0.06, 1.0),
    ("NaN time stamps 2 s, 10 s in", "time_nan", 10.0, 2.0, 1.0),
    ("NaN positions 2 s, 10 s in", "position_nan", 10.0, 2.0, 1.0),
    ("NaN time stamps, whole part", "time_nan", 0.0, ROUGH_PART_S, 1.0),
    ("NaN positions, whole part", "position_nan", 0.0, ROUGH_PART_S, 1.0),
    ("(extra) samples dropped 20 s, 3 s before", "drop", -3.0, 20.0, 1.0),
)


@dataclass(frozen=True)
class Scenario:
    """One fault scenario (picklable). The fault starts at ``start_frac`` of the clean run's
    duration (random scenarios) or ``offset_s`` after the clean run reaches ``start_at_m``."""

    name: str
    case: str
    segments: tuple[tuple[float, float], ...]
    track_seed: int
    noise_seed: int
    kind: str
    duration_s: float
    magnitude: float
    start_frac: float = np.nan
    start_at_m: float = np.nan
    offset_s: float = 0.0

    def fault(self, clean) -> control.SensorFault:
        """The fault, its start placed by the clean run."""
        if np.isfinite(self.start_frac):
            start = self.start_frac * float(clean.sample_time[-1])
        else:
            k = int(np.searchsorted(clean.sample_position, self.start_at_m))
            start = float(clean.sample_time[min(k, clean.sample_time.size - 1)]) + self.offset_s
        return control.SensorFault(start, self.duration_s, self.kind, self.magnitude)

    def reproduce(self, fault: control.SensorFault, simplex: control.Simplex) -> str:
        """Python that reruns the faulted loop (with ``simplex``'s settings that are not the
        defaults)."""
        changed = {
            f.name: getattr(simplex, f.name)
            for f in dataclasses.fields(simplex)
            if getattr(simplex, f.name) != getattr(DEFAULT_SIMPLEX, f.name)
        }
        settings = ", ".join(f"{k}={v!r}" for k, v in changed.items())
        return (
            f"control.run_closed_loop(roadgen.track({list(self.segments)}, "
            f"seed={self.track_seed}), control.shipped_emulator({self.case!r}), "
            f"noise_std={NOISE_STD[self.case]}, seed={self.noise_seed}, "
            f"faults=[control.SensorFault({fault.start_s!r}, {fault.duration_s!r}, "
            f"{fault.kind!r}, {fault.magnitude!r})]"
            + (f", simplex=control.Simplex({settings})" if changed else "")
            + ")"
        )


@dataclass
class Outcome:
    """What one scenario did (``crash``: "" or the exception with its traceback tail)."""

    scenario: Scenario
    fault: control.SensorFault | None = None
    crash: str = ""
    fast_clean: float = np.nan
    fast_fault: float = np.nan
    during_clean: float = np.nan
    during_fault: float = np.nan
    fast_null: float = np.nan
    during_null: float = np.nan
    statuses: Counter = field(default_factory=Counter)
    excerpt: list = field(default_factory=list)
    segments: list = field(default_factory=list)
    fault_span_m: tuple = (np.nan, np.nan)
    latched: bool = False
    clean_latched: bool = False
    simplex: control.Simplex = field(default_factory=control.Simplex)

    @property
    def diff(self) -> float:
        return self.fast_fault - self.fast_clean

    @property
    def during_diff(self) -> float:
        return self.during_fault - self.during_clean

    @property
    def null_diff(self) -> float:
        return self.fast_null - self.fast_clean

    @property
    def null_during_diff(self) -> float:
        return self.during_null - self.during_clean


def fast_between(result, track, t0: float, t1: float) -> float:
    """Distance driven faster than v_safe + 0.02 m/s on GD > GD_max between sample times t0, t1."""
    sel = (result.sample_time >= t0) & (result.sample_time <= t1)
    simplex = result.settings["simplex"]
    return control.fast_on_rough_m(
        track, result.sample_position[sel], result.sample_speed[sel], simplex.gd_max,
        simplex.v_safe,
    )  # fmt: skip


def log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def random_scenario(seed: int, index: int) -> Scenario:
    """Scenario ``index`` of the soak seeded ``seed``."""
    rng = np.random.default_rng([seed, index])
    n_seg = int(rng.integers(3, 6))
    segments = tuple(
        (round(float(rng.uniform(20, 60)), 3), round(float(rng.uniform(220, 580)), 1))
        for _ in range(n_seg)
    )
    kind = control.FAULT_KINDS[(index // 2) % len(control.FAULT_KINDS)]
    ranges = MAGNITUDE.get(kind)
    magnitude = 1.0
    if ranges is not None:
        magnitude = log_uniform(rng, *ranges[int(rng.integers(len(ranges)))])
        if kind == "spike":
            magnitude = float(round(magnitude))
    return Scenario(
        name=f"#{index}",
        case="AB"[index % 2],
        segments=segments,
        track_seed=int(rng.integers(2**31)),
        noise_seed=int(rng.integers(2**31)),
        kind=kind,
        duration_s=log_uniform(rng, *DURATION_S),
        magnitude=magnitude,
        start_frac=float(rng.uniform(0, 1)),
    )


def example_scenarios(seeds) -> list[Scenario]:
    return [
        Scenario(name, case, PAPER_TRACK, seed, seed, kind, dur, mag, start_at_m=50.0,
                 offset_s=offset)
        for name, kind, offset, dur, mag in EXAMPLES
        for case in ("A", "B")
        for seed in seeds
    ]  # fmt: skip


_LIKELIHOOD: dict = {}


DEFAULT_SIMPLEX = control.Simplex()


def _init_worker() -> None:
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)  # two workers on two cores: no BLAS threads on top


def _loop(sc: Scenario, track, faults=(), simplex: control.Simplex = DEFAULT_SIMPLEX):
    if sc.case not in _LIKELIHOOD:
        emu = control.shipped_emulator(sc.case)
        _LIKELIHOOD[sc.case] = (emu, control.ObservationModel(emu))
    emu, lik = _LIKELIHOOD[sc.case]
    return control.run_closed_loop(
        track, emu, noise_std=NOISE_STD[sc.case], seed=sc.noise_seed, likelihood=lik,
        faults=faults, simplex=simplex,
    )  # fmt: skip


def _crash(exc: BaseException, which: str) -> str:
    tail = traceback.format_exception(type(exc), exc, exc.__traceback__)[-3:]
    return f"{which} run: {type(exc).__name__}: {exc}\n" + "".join(tail)


def rough_segments(track, runs, gd_max: float) -> list:
    """Per segment with GD > gd_max: (start m, end m, GD, fast-on-rough m of each run there)."""
    edges = [*track.boundaries_m, track.length_m]
    out = []
    for k, (_, gd) in enumerate(track.segments):
        if gd <= gd_max:
            continue
        fast = []
        for r in runs:
            sel = (r.sample_position >= edges[k]) & (r.sample_position < edges[k + 1])
            fast.append(control.fast_on_rough_m(
                track, r.sample_position[sel], r.sample_speed[sel], gd_max,
                r.settings["simplex"].v_safe,
            ))  # fmt: skip
        out.append((edges[k], edges[k + 1], gd, *fast))
    return out


def run_scenario(
    sc: Scenario,
    keep_excerpt: bool = False,
    null: bool = True,
    simplex: control.Simplex = DEFAULT_SIMPLEX,
) -> Outcome:
    """Clean, faulted and (``null``) imperceptibly perturbed loop of one scenario."""
    out = Outcome(sc, simplex=simplex)
    try:
        track = roadgen.track(sc.segments, seed=sc.track_seed)
        clean = _loop(sc, track, simplex=simplex)
    except Exception as exc:  # noqa: BLE001 - a crash is what the soak counts
        out.crash = _crash(exc, "clean")
        return out
    out.fault = fault = sc.fault(clean)
    out.fast_clean = clean.metrics.fast_on_rough_m
    try:
        faulted = _loop(sc, track, (fault,), simplex)
    except Exception as exc:  # noqa: BLE001
        out.crash = _crash(exc, "faulted")
        return out
    out.fast_fault = faulted.metrics.fast_on_rough_m
    out.latched = bool(np.isfinite(faulted.metrics.latched_at_s))
    out.clean_latched = bool(np.isfinite(clean.metrics.latched_at_s))
    end = fault.start_s + fault.duration_s + 2 * 125 / 120.0
    out.during_clean = fast_between(clean, track, fault.start_s, end)
    out.during_fault = fast_between(faulted, track, fault.start_s, end)
    during = (faulted.time >= fault.start_s) & (faulted.time <= end)
    out.statuses = Counter(faulted.status[during].tolist())
    runs = [clean, faulted]
    if null:
        try:
            perturbed = _loop(sc, track, (control.SensorFault(
                fault.start_s, fault.duration_s, "scale", NULL_GAIN),), simplex)  # fmt: skip
        except Exception as exc:  # noqa: BLE001
            out.crash = _crash(exc, "null")
            return out
        out.fast_null = perturbed.metrics.fast_on_rough_m
        out.during_null = fast_between(perturbed, track, fault.start_s, end)
        runs.append(perturbed)
    if keep_excerpt or out.diff > 0 or out.during_diff > 0:
        out.excerpt = excerpt(clean, faulted, fault)
        out.segments = rough_segments(track, runs, clean.settings["simplex"].gd_max)
        out.fault_span_m = tuple(
            float(np.interp(t, faulted.sample_time, faulted.sample_position))
            for t in (fault.start_s, fault.start_s + fault.duration_s)
        )
    return out


def _job(job: tuple[Scenario, bool, control.Simplex]) -> Outcome:
    sc, null, simplex = job
    return run_scenario(sc, null=null, simplex=simplex)


def excerpt(clean, faulted, fault, before_s: float = 3.0, after_s: float = 12.0) -> list:
    """Rows (t, position, GD true, status, GD mean, command, clean GD mean, clean command,
    clean position, reason) of the updates from before_s before the fault to after_s after."""
    n = min(clean.time.size, faulted.time.size)
    t = faulted.time[:n]
    sel = (t >= fault.start_s - before_s) & (t <= fault.start_s + fault.duration_s + after_s)
    return [
        (float(t[i]), float(faulted.position[i]), float(faulted.gd_true[i]), str(faulted.status[i]),
         float(faulted.gd_mean[i]), float(faulted.command[i]), float(clean.gd_mean[i]),
         float(clean.command[i]), float(clean.position[i]), str(faulted.reason[i]))
        for i in np.flatnonzero(sel)
    ]  # fmt: skip


def load() -> str:
    return "load average {:.2f} {:.2f} {:.2f}".format(*load_average())


def print_excerpt(o: Outcome) -> None:
    sc, f = o.scenario, o.fault
    assert f is not None, "an excerpt is of a faulted run"
    print(
        f"\n{sc.name} case {sc.case} {f.kind} magnitude {f.magnitude:.4g} at {f.start_s:.2f} s "
        f"for {f.duration_s:.3g} s; track {list(sc.segments)}; fast on rough: clean "
        f"{o.fast_clean:.2f} m, faulted {o.fast_fault:.2f} m"
    )
    print(
        f"  reproduce (with one BLAS thread, as the soak's workers): {sc.reproduce(f, o.simplex)}"
    )
    names = ("clean", "faulted", "null")
    print(
        f"  fault from {o.fault_span_m[0]:.1f} to {o.fault_span_m[1]:.1f} m; fast on rough per "
        "segment with GD > GD_max: "
        + "; ".join(
            f"[{a:.0f}-{b:.0f} m, GD {gd:.0f}] "
            + " ".join(f"{n} {x:.1f}" for n, x in zip(names, fast, strict=False))
            for a, b, gd, *fast in o.segments
        )
    )
    print(
        f"  {'t s':>7}{'pos m':>8}{'GD':>5} {'status':<12}{'GD est':>7}{'cmd':>6} | "
        f"{'clean GD':>8}{'cmd':>6}{'pos m':>8}  reason (faulted)"
    )
    for t, pos, gd, st, est, cmd, c_est, c_cmd, c_pos, reason in o.excerpt:
        simplex = control.Simplex()
        flag = "!" if gd > simplex.gd_max and cmd > simplex.v_safe + 0.02 else " "
        print(
            f"  {t:7.2f}{pos:8.2f}{gd:5.0f} {st:<12}{est:7.0f}{cmd:6.2f}{flag}| "
            f"{c_est:8.0f}{c_cmd:6.2f}{c_pos:8.2f}  {reason[:90]}"
        )


def summarise(outcomes: list[Outcome]) -> None:
    done = [o for o in outcomes if not o.crash]
    print(f"\nper fault kind: faulted minus clean fast-on-rough distance, m ({load()})")
    print("left: over the whole run; right of '|': while the fault lasts (to its end + 2 blocks)")
    print(
        f"{'kind':<13}{'n':>4}{'crash':>6}{'worse':>6}{'same':>6}{'safer':>6}"
        f"{'worst +m':>9} {'(scenario)':<11}{'min':>7}{'p5':>7}{'median':>7}{'p95':>7}{'max':>7}"
        f" | {'worse':>5}{'worst +m':>9} {'(scenario)':<11}"
    )
    for kind in (*control.FAULT_KINDS, "all"):
        sel = [o for o in outcomes if kind == "all" or o.scenario.kind == kind]
        ok = [o for o in sel if not o.crash]
        if not sel:
            continue
        d = np.array([o.diff for o in ok])
        worse = [o for o in ok if o.diff > 0]
        worst = max(worse, key=lambda o: o.diff) if worse else None
        # every run of the kind crashed: no distances ("-")
        q = np.percentile(d, [0, 5, 50, 95, 100]) if d.size else [None] * 5
        worse_in = [o for o in ok if o.during_diff > 0]
        worst_in = max(worse_in, key=lambda o: o.during_diff) if worse_in else None
        print(
            f"{kind:<13}{len(sel):4d}{len(sel) - len(ok):6d}{len(worse):6d}"
            f"{int(np.sum(d == 0)):6d}{int(np.sum(d < 0)):6d}"
            f"{(worst.diff if worst else 0.0):9.2f} {(worst.scenario.name if worst else '-'):<11}"
            + "".join(f"{x:7.2f}" if x is not None else f"{'-':>7}" for x in q)
            + f" | {len(worse_in):5d}{(worst_in.during_diff if worst_in else 0.0):9.2f} "
            f"{(worst_in.scenario.name if worst_in else '-'):<11}"
        )
    unlatched = [o for o in done if not o.latched]
    seen = [any(o.statuses[s] for s in control.FAULT_STATUSES) for o in unlatched]
    flagged = [o for o, f in zip(unlatched, seen, strict=True) if f]
    unseen = [o for o, f in zip(unlatched, seen, strict=True) if not f]
    print(
        f"faulted runs latched in safety mode: {sum(o.latched for o in done)} of {len(done)}; "
        f"not latched: {len(flagged)} flagged during the fault (p above latch_p), worse than "
        f"clean {sum(o.diff > 0 for o in flagged)}; {len(unseen)} never flagged, worse "
        f"{sum(o.diff > 0 for o in unseen)}; clean runs latched (false alarms): "
        f"{sum(o.clean_latched for o in done)}"
    )
    for case in ("A", "B"):
        mine = [o for o in done if o.scenario.case == case]
        d = np.array([o.diff for o in mine])
        if d.size:
            print(
                f"case {case}: {d.size} scenarios, worse {int(np.sum(d > 0))}, mean difference "
                f"{d.mean():+.2f} m; total fast on rough: clean "
                f"{sum(o.fast_clean for o in mine):.1f} m, faulted "
                f"{sum(o.fast_fault for o in mine):.1f} m"
            )
    with_null = [o for o in done if np.isfinite(o.fast_null)]
    if not with_null:
        return
    print(
        f"\nthe faults against the chaos of the loop ({load()}): 'null' reruns each scenario with "
        f"the fault replaced by a gain of 1 + 1e-9 over the same time (no check can see it); "
        "the loop is chaotic, so the null run also drives differently from the clean one. "
        "p: one-sided Wilcoxon signed-rank test that the faulted run is faster on rough ground "
        "than the null run (pairs per scenario; '-': no pair differs, nothing to test)"
    )
    print(
        f"{'kind':<13}{'n':>4}{'worse: fault':>13}{'null':>6}{'mean diff: fault':>17}{'null':>7}"
        f"{'p95: fault':>11}{'null':>7}{'p':>8} | during: {'fault worse':>11}{'null worse':>11}"
    )
    for kind in (*control.FAULT_KINDS, "all"):
        sel = [o for o in with_null if kind == "all" or o.scenario.kind == kind]
        if not sel:
            continue
        d = np.array([o.diff for o in sel])
        d0 = np.array([o.null_diff for o in sel])
        paired = d - d0
        p_text = (f"{stats.wilcoxon(paired, alternative='greater').pvalue:8.3f}"
                  if np.any(paired != 0) else f"{'-':>8}")  # fmt: skip
        print(
            f"{kind:<13}{len(sel):4d}{int(np.sum(d > 0)):13d}{int(np.sum(d0 > 0)):6d}"
            f"{d.mean():+17.2f}{d0.mean():+7.2f}{np.percentile(d, 95):11.2f}"
            f"{np.percentile(d0, 95):7.2f}{p_text} | {'':8}"
            f"{sum(o.during_diff > 0 for o in sel):11d}"
            f"{sum(o.null_during_diff > 0 for o in sel):11d}"
        )
    print("\nstatuses of the updates during the faults (to their end + 2 blocks), per kind")
    for kind in control.FAULT_KINDS:
        total = sum((o.statuses for o in done if o.scenario.kind == kind), Counter())
        print(f"  {kind:<13}" + ", ".join(f"{k} {v}" for k, v in total.most_common()))


def worst_outcomes(random_out: list[Outcome], example_out: list[Outcome]) -> tuple[list, list]:
    """(runs that drove faster on rough ground than their clean run while the fault lasted, of
    the random scenarios and the examples; random scenarios faster over the whole run), each
    worst first; crashed runs are left out."""
    ok = [o for o in (*random_out, *example_out) if not o.crash]
    during = sorted((o for o in ok if o.during_diff > 0), key=lambda o: -o.during_diff)
    worse = sorted((o for o in random_out if not o.crash and o.diff > 0), key=lambda o: -o.diff)
    return during, worse


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick", action="store_true", help="20 scenarios and the examples on seed 1 only"
    )
    parser.add_argument(
        "--scenarios",
        type=int,
        default=400,
        help="random scenarios, half per noise case (full run; the documented figures use 400)",
    )
    parser.add_argument("--seed", type=int, default=15, help="master seed of the scenarios")
    parser.add_argument(
        "--example-seeds",
        type=int,
        nargs="+",
        default=[1, 2, 3],
        help="track and noise seeds of the issue's examples (--quick: 1)",
    )
    parser.add_argument("--no-examples", action="store_true", help="skip the issue's examples")
    parser.add_argument(
        "--workers", type=int, default=2, help="worker processes (at most 2 on this shared machine)"
    )
    parser.add_argument(
        "--explain",
        type=int,
        default=5,
        help="print the updates around the fault of this many worst scenarios",
    )
    parser.add_argument(
        "--no-null",
        action="store_true",
        help="skip the null runs (the fault replaced by an invisible 1e-9 gain error)",
    )
    parser.add_argument(
        "--after-fault",
        choices=["latch", "resume"],
        default="latch",
        help="the Simplex's policy after a fault (default: latch, the library's default)",
    )
    parser.add_argument(
        "--only",
        type=int,
        default=None,
        help="run the random scenario of this index only, with its trace",
    )
    parser.add_argument(
        "--speed-step",
        type=float,
        default=control.Simplex().speed_step_mps,
        help="the Simplex's speed grid, m/s (control.Simplex.speed_step_mps; default: the "
        "library's)",
    )
    args = parser.parse_args(argv)  # fmt: skip
    for option, value, minimum in (
        ("--scenarios", args.scenarios, 1), ("--seed", args.seed, 0),
        ("--workers", args.workers, 1), ("--explain", args.explain, 0),
        ("--only", 0 if args.only is None else args.only, 0),
        *(("--example-seeds", seed, 0) for seed in args.example_seeds),
    ):  # fmt: skip
        if value < minimum:
            parser.error(f"{option} must be >= {minimum}, got {value}")
    for seed in args.example_seeds:  # each a track and a noise seed
        if seed >= MAX_SEED:
            parser.error(f"--example-seeds must be < 2**128 (the seeds' range), got {seed}")
    try:
        simplex = control.Simplex(after_fault=args.after_fault, speed_step_mps=args.speed_step)
    except control.ControlError as exc:
        parser.error(f"--speed-step: {exc}")
    if args.only is not None:
        _init_worker()  # one BLAS thread, as in the soak: the loop is chaotic to the last bit
        o = run_scenario(random_scenario(args.seed, args.only), keep_excerpt=True, simplex=simplex)
        if o.crash:
            print(o.crash)
            return 1
        print_excerpt(o)
        print(f"statuses during the fault: {dict(o.statuses)}")
        return 0
    n = 20 if args.quick else args.scenarios
    seeds = [args.example_seeds[0]] if args.quick else args.example_seeds
    scenarios = [random_scenario(args.seed, i) for i in range(n)]
    examples = [] if args.no_examples else example_scenarios(seeds)

    tic = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers, initializer=_init_worker) as pool:
        jobs = [(sc, not args.no_null, simplex) for sc in scenarios] + [
            (sc, False, simplex) for sc in examples
        ]
        outcomes = list(pool.map(_job, jobs, chunksize=1))
    wall = time.perf_counter() - tic
    random_out, example_out = outcomes[:n], outcomes[n:]
    crashes = [o for o in outcomes if o.crash]
    print(
        f"fault soak: {n} random scenarios ({sum(s.case == 'A' for s in scenarios)} case A, "
        f"{sum(s.case == 'B' for s in scenarios)} case B; seed {args.seed}) + {len(examples)} "
        f"examples, {2 * len(outcomes) + (0 if args.no_null else n)} loop runs in {wall:.0f} s "
        f"on {args.workers} workers; after_fault={args.after_fault!r}, "
        f"speed step {args.speed_step:g} m/s; "
        f"{load()}"
    )
    print(f"crashes: {len(crashes)}")
    for o in crashes:
        print(f"  {o.scenario.name} case {o.scenario.case} {o.scenario.kind}: {o.crash}")
    summarise(random_out)

    if example_out:
        print(f"\nthe issue's examples on the paper's track, fault from 50 m + offset ({load()})")
        print(
            f"{'example':<42}{'case':>5}{'seed':>5}{'clean m':>9}{'fault m':>9}{'diff':>7}"
            f"{'during':>7}  statuses during the fault"
        )
        for o in example_out:
            sc = o.scenario
            if o.crash:
                first = o.crash.splitlines()[0]
                print(f"{sc.name:<42}{sc.case:>5}{sc.track_seed:>5}  CRASH {first}")
                continue
            st = ", ".join(f"{k} {v}" for k, v in o.statuses.most_common())
            print(
                f"{sc.name:<42}{sc.case:>5}{sc.track_seed:>5}{o.fast_clean:9.2f}"
                f"{o.fast_fault:9.2f}{o.diff:+7.2f}{o.during_diff:+7.2f}  {st}"
            )

    during, worse = worst_outcomes(random_out, example_out)
    for title, chosen in (
        ("faster on rough ground than the clean run while the fault lasts", during),
        ("random scenarios with the largest excess over the whole run", worse),
    ):
        if chosen and args.explain:
            print(
                f"\n{title}: {len(chosen)}; the first {min(args.explain, len(chosen))}, with the "
                "updates around the fault ('!': faster than v_safe on GD > GD_max)"
            )
            for o in chosen[: args.explain]:
                print_excerpt(o)
    print(f"\ntotal {time.perf_counter() - tic:.0f} s; {load()}")
    return 1 if crashes else 0


if __name__ == "__main__":
    sys.exit(main())
