"""Does a second sensor help in the closed loop? Front axle alone, front + rear accelerometer,
front + a rear axle synthesised from the pitch-rate gyro.

    PYTHONPATH=. python benchmarks/second_channel_loop.py            # development sets, ~22 min
    PYTHONPATH=. python benchmarks/second_channel_loop.py --sets paper,heldout,random,steady \\
        --random-tracks 120                 # held out, ~21 min with the emulators of a first run
    PYTHONPATH=. python benchmarks/second_channel_loop.py --help

`benchmarks/second_channel.py` measured the information per block of each channel on steady
roads; this benchmark measures what it does to the closed loop. Steps:

1. a training campaign as ``examples/train_emulator.py``'s (198 runs of a stretched Latin
   hypercube over v 0.5-2.0 m/s and GD 200-600, 120 s of driving each), recording both axles;
2. per channel set and case (A noise-free, B N(0, 1) m/s^2 on each accelerometer), the block
   feature of each channel (the shipped 8 log band powers of 125-sample blocks), concatenated
   (16 outputs for two channels); the run means fitted by ``gpmsa.fit`` (``--n-iter`` sweeps; 5
   principal components for the front axle alone, as shipped, and for two channels as many as
   hold 99.9% of the variance, the shipped rule) and the block scatter Sigma(v) as
   ``control.training``;
3. the closed loop on the sets of ``benchmarks/closed_loop_accuracy.py`` (same tracks, seeds,
   Simplex and reports). The front axle alone runs ``control.run_closed_loop``. Two channels
   run the same loop with a BCR that also buffers the second channel (a subclass: the shipped
   BCR takes one accelerometer), so the change-point filter, its phases, the guards and the
   Simplex are the shipped ones.

The synthesised rear axle: the chassis is a rigid body, so a_rear = a_front - wheelbase x
d(pitch rate)/dt exactly (the model's axle accelerations are its heave and pitch accelerations
combined). Synthesised from the front accelerometer and a gyro, it is the rear axle plus the
front accelerometer's noise minus the wheelbase times the derivative of the gyro's noise (white,
``second_channel.GYRO_NOISE_RAD_S``, differentiated exactly through the FFT: an ideal
differentiator on board). It needs no second accelerometer: the Jackal's IMU has the gyro.

The figures compare emulators fitted alike (``--n-iter``, default 6,000 sweeps: the shipped
ones have 30,000, which moved no closed-loop figure beyond its scatter, docs/closed-loop.md).
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

import control
import gpmsa
import roadgen
import vehicle
from control.closed_loop import simulated_sensor_settings
from control.metrics import detection_delays, gd_errors, segment_index
from control.sensor_checks import signal_fault
from control.training import block_scatter, block_statistics, feature_statistics

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "examples"))
import closed_loop_accuracy as cla  # noqa: E402
from _cli import check_option_memory, output_folder, path_option  # noqa: E402
from _host import load_average  # noqa: E402
from second_channel import GYRO_NOISE_RAD_S, spectral_derivative  # noqa: E402
from train_emulator import BATCH, LEAD_IN_M, fit_memory, stretched_design  # noqa: E402

SPEC = control.FeatureSpec(quantiles=())  # as measured: the band powers alone
FRONT_PCS = 5
"""Principal components of the front axle's band-power emulator (as shipped when measured)."""
CHANNELS = ("front", "rear", "synthesised")
"""Channel sets: the front axle alone (its band powers, as shipped when measured), front + rear
accelerometer, front + rear axle synthesised from the front accelerometer and the gyro."""
TWO_CHANNEL_VARIANCE = 0.999  # principal components of the two-channel emulators: this share
_MODELS: dict = {}


def gyro_term(rng: np.random.Generator, n: int, dt: float) -> np.ndarray:
    """wheelbase x d/dt of n samples of white gyro noise (a periodic series, so the FFT
    derivative is exact), m/s^2."""
    noise = GYRO_NOISE_RAD_S * rng.standard_normal(n)
    return vehicle.Jackal().wheelbase_m * spectral_derivative(noise, dt)


def campaign_run(job: tuple[float, float, int, float]) -> np.ndarray:
    """(4, n): front, rear noise-free; front, rear with N(0, 1) noise; the last keep_s s."""
    v, gd, seed, keep_s = job
    model = vehicle.Jackal()
    keep = int(round(keep_s * SPEC.rate_hz))
    length = LEAD_IN_M + model.wheelbase_m + v * (keep_s + 1.0)
    road = roadgen.iso8608_profile(length, gd, seed=seed, lead_in_m=LEAD_IN_M)
    noise = np.random.default_rng([seed, 1])
    trace = vehicle.simulate(model, road, v, rate_hz=SPEC.rate_hz, noise_std=1.0, seed=noise)
    last = slice(len(trace) - keep, None)
    signals = ("accel_front", "accel_rear", "accel_front_measured", "accel_rear_measured")
    return np.stack([getattr(trace, name)[last] for name in signals])


def channel_signals(acc: np.ndarray, case: str, channels: str) -> list[np.ndarray]:
    """The campaign's (m, n) signals of a channel set in a case (see the module docstring)."""
    front_true, rear_true, front_meas, rear_meas = (acc[:, k] for k in range(4))
    front = front_true if case == "A" else front_meas
    if channels == "front":
        return [front]
    if channels == "rear":
        return [front, rear_true if case == "A" else rear_meas]
    dt = 1.0 / SPEC.rate_hz
    gyro = np.stack(
        [gyro_term(np.random.default_rng([r, 99]), acc.shape[2], dt) for r in range(acc.shape[0])]
    )
    return [front, rear_true + (front - front_true) - gyro]


def fit(
    design: np.ndarray, acc: np.ndarray, case: str, channels: str, n_iter: int, pcs: int | None
):
    """The block-feature emulator of a channel set, its block scatter in the metadata; ``pcs``
    principal components for two channels (None: TWO_CHANNEL_VARIANCE of the variance)."""
    signals = channel_signals(acc, case, channels)
    stats_ = feature_statistics(
        np.concatenate([block_statistics(x, SPEC, BATCH).features for x in signals], axis=2), BATCH
    )
    y = stats_.mean
    if channels == "front":
        n_pc = FRONT_PCS
    elif pcs is None:
        z = (y - y.mean(axis=0)) / y.std()
        share = np.cumsum(np.linalg.svd(z, compute_uv=False) ** 2)
        n_pc = int(np.searchsorted(share / share[-1], TWO_CHANNEL_VARIANCE)) + 1
    else:
        n_pc = pcs
    scatter = block_scatter(design[:, 0], stats_, nodes=np.linspace(0.5, 2.0, 16))
    data = gpmsa.SimData(
        x=design[:, :1], t=design[:, 1:], y=y, x_names=["v"], t_names=["GD"],
        y_names=[f"y{k}" for k in range(y.shape[1])],
    )  # fmt: skip
    meta = {"block_scatter": scatter.to_dict(), "channels": channels, "case": case}
    return gpmsa.fit(data, n_iter=n_iter, seed=0, n_pc=n_pc, metadata=meta), n_pc


class TwoChannelBCR(control.BCR):
    """The shipped change-point BCR with a second channel buffered beside the first: the feature
    is both channels' band powers, and both channels pass the signal checks. Clean streams only
    (the benchmark injects no faults): ``update2`` takes the second channel's samples."""

    def reset(self) -> None:
        super().reset()
        self._second = np.empty(0)
        self._second_in, self._offset = np.empty(0), 0

    def update2(self, t, position, first, second, speed, *, now: float) -> control.Estimate:
        self._second_in, self._offset = np.asarray(second, dtype=float), 0
        return self.update(t, position, first, speed, now=now)

    def _take(self, t, pos, acc, spd) -> None:
        part = self._second_in[self._offset : self._offset + acc.size]
        self._offset += acc.size
        super()._take(t, pos, acc, spd)
        n = self._acc.size  # the first channel's contiguous clean samples: the same tail
        self._second = np.concatenate([self._second, part])[-n:] if n else np.empty(0)

    def _block_feature(self, block: np.ndarray) -> np.ndarray:
        second = control.block_features(self._second[-block.size :], self.settings.feature)[0]
        return np.concatenate([super()._block_feature(block), second])

    def _signal_reason(
        self, accel: np.ndarray, timing: bool = True, slow: np.ndarray | None = None
    ) -> str:
        """The shipped checks (time stamps, odometry, the first channel), then the signal
        checks on the second channel's samples alongside ``accel``."""
        return super()._signal_reason(accel, timing, slow) or signal_fault(
            self._second[-accel.size :], self.settings.sensor, steady=slow is None, slow=slow
        )


def two_channel_loop(track, likelihood, bcr, simplex, noise_std: float, seed: int, channels: str):
    """`control.run_closed_loop` (same noise draws, BCR settings and Simplex) with the second
    channel; returns (position, mean, lo, hi, command) per update."""
    model = vehicle.Jackal()
    bcr = simulated_sensor_settings(bcr, noise_std)
    estimator = TwoChannelBCR(likelihood, bcr)
    noise_seed = np.random.default_rng(seed).integers(2**63)
    sim = vehicle.Simulation(
        model, track, rate_hz=bcr.rate_hz, noise_std=noise_std, seed=int(noise_seed)
    )
    longest = int(20 * track.length_m / simplex.v_safe * bcr.rate_hz)  # run_closed_loop's limit
    gyro = gyro_term(np.random.default_rng([seed, 99]), longest, 1.0 / bcr.rate_hz)
    controller = simplex.start()
    command = controller.command(estimator.last)
    rows, used = [], 0
    while not sim.finished:
        s = sim.advance(bcr.samples_per_update / bcr.rate_hz, command.speed)
        if len(s) == 0:
            break
        second = s.accel_rear
        if channels == "synthesised":
            noise_front = s.accel_front - s.accel_front_true
            second = s.accel_rear_true + noise_front - gyro[used : used + len(s)]
        if used + len(s) > gyro.size:
            raise control.ControlError("the vehicle stood or crawled past run_closed_loop's limit")
        used += len(s)
        estimate = estimator.update2(
            s.t, s.position, s.accel_front, second, s.speed, now=float(s.t[-1])
        )
        command = controller.command(estimate)
        rows.append((float(s.position[-1]), estimate, command.speed))
    position = np.array([p for p, _, _ in rows])
    mean = np.array([e.gd_mean for _, e, _ in rows])
    lo, hi = (np.array([e.interval[k] for _, e, _ in rows]) for k in (0, 1))
    return position, mean, lo, hi, np.array([c for _, _, c in rows])


def loop_settings() -> control.BCRSettings:
    """The BCR's defaults with the feature the benchmark's emulators were fitted to (`SPEC`, the
    band powers alone: the shipped feature has added two quantiles since)."""
    return control.BCRSettings(feature=SPEC)


def drive(job: tuple) -> dict:
    """One closed-loop run of closed_loop_accuracy's kinds, with one channel set."""
    channels, case, kind, seed, extra, emulator_dir, pcs = job
    path = emulator_path(Path(emulator_dir), channels, case, pcs)
    if path not in _MODELS:
        emu = gpmsa.load(path)
        _MODELS[path] = (emu, control.ObservationModel(emu))
    emu, likelihood = _MODELS[path]
    bcr = loop_settings()
    simplex = control.Simplex()
    segments: tuple[tuple[float, float], ...]
    if kind == "steady":
        gd, speed = extra
        segments = ((100.0, gd),)
        simplex = control.Simplex(v_max=speed, v_safe=speed, law="switch")
    else:
        segments = cla.random_segments(seed) if kind == "random" else cla.PAPER_TRACK
    track = roadgen.track(segments, seed=seed)
    noise = cla.NOISE_STD[case]
    if channels == "front":
        r = control.run_closed_loop(
            track, emu, noise_std=noise, seed=seed, bcr=bcr, simplex=simplex,
            likelihood=likelihood, check=False,
        )  # fmt: skip
        position, mean, lo, hi, command = r.position, r.gd_mean, r.gd_lo, r.gd_hi, r.command
    else:
        position, mean, lo, hi, command = two_channel_loop(
            track, likelihood, bcr, simplex, noise, seed, channels
        )
    seg_gd = np.array([gd for _, gd in segments], dtype=float)
    steps = [(segments[k - 1][1], segments[k][1]) for k in range(1, len(segments))]
    return {
        "case": case, "kind": kind, "seed": seed, "method": "changepoint", "extra": extra,
        "position": position, "mean": mean, "lo": lo, "hi": hi,
        "true": seg_gd[segment_index(track, position)],
        "errors": gd_errors(track, position, mean),
        "delays": detection_delays(track, position, mean),
        "steps": [s for s in steps if s[0] != s[1]],
        "speed_steps": cla.speed_steps(position, command, segments),
    }  # fmt: skip


def emulator_path(folder: Path, channels: str, case: str, pcs: int | None) -> Path:
    """Where the benchmark keeps the emulator of a channel set, case and basis size."""
    basis = f"_{pcs}pc" if pcs is not None and channels != "front" else ""
    return folder / f"{channels}_{case}{basis}.gpmsa"


def jobs_for(name: str, channels: str, cases, emulator_dir: str, random_tracks: int, pcs) -> list:
    out: list[tuple] = []
    for case in cases:
        if name == "dev":
            out += [(channels, case, "paper", s, None) for s in cla.SETS["dev"]]
            out += [(channels, case, "random", s + 100, None) for s in cla.SETS["dev"]]
        elif name in ("paper", "heldout"):
            out += [(channels, case, "paper", s, None) for s in cla.SETS[name]]
        elif name == "random":
            seeds = range(cla.SETS["random"].start, cla.SETS["random"].start + random_tracks)
            out += [(channels, case, "random", s, None) for s in seeds]
        else:  # steady, steady-dev
            out += [(channels, case, "steady", s, (gd, v)) for gd in cla.STEADY_GD
                    for v in cla.STEADY_SPEEDS for s in cla.SETS[name]]  # fmt: skip
    return [(*job, emulator_dir, pcs) for job in out]


def main() -> None:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    sets = ("dev", "steady-dev", "paper", "heldout", "random", "steady")
    parser.add_argument("--sets", default="dev,steady-dev", help=f"comma-separated, among {sets}")
    parser.add_argument("--channels", default=",".join(CHANNELS), help=f"among {CHANNELS}")
    parser.add_argument("--n-iter", type=int, default=6000, help="MCMC sweeps per fit")
    parser.add_argument(
        "--two-channel-pcs", type=int, default=None,
        help=f"principal components of the two-channel emulators, 1 to {2 * SPEC.dim} (default: "
        f"those that hold {100 * TWO_CHANNEL_VARIANCE:g}%% of the variance)",
    )  # fmt: skip
    parser.add_argument("--random-tracks", type=int, default=40, help="random set: seeds 401 on")
    parser.add_argument("--workers", type=int, default=2, help="worker processes")
    parser.add_argument(
        "--out", type=path_option, default="out/second_channel_loop",
        help="campaign and emulators",
    )  # fmt: skip
    args = parser.parse_args()
    names = [n for n in args.sets.split(",") if n]
    channel_sets = [c for c in args.channels.split(",") if c]
    if not names or not set(names) <= set(sets):
        parser.error(f"--sets must name sets among {sets}, got {args.sets!r}")
    if not channel_sets or not set(channel_sets) <= set(CHANNELS):
        parser.error(f"--channels must be among {CHANNELS}, got {args.channels!r}")
    pcs = args.two_channel_pcs
    if pcs is not None and not 1 <= pcs <= 2 * SPEC.dim:
        parser.error(f"--two-channel-pcs must be in [1, {2 * SPEC.dim}], got {pcs}")
    if args.n_iter < 2:
        parser.error(f"--n-iter must be >= 2, got {args.n_iter}")
    if args.random_tracks < 1:
        parser.error(f"--random-tracks must be >= 1, got {args.random_tracks}")
    if args.workers < 1:
        parser.error(f"--workers must be >= 1, got {args.workers}")
    out = output_folder(parser, "--out", args.out)
    cases = tuple(cla.NOISE_STD)
    tic = time.perf_counter()
    design = stretched_design(198, 0)
    emulators = [emulator_path(out, c, case, pcs) for c in channel_sets for case in cases]
    if all(p.exists() for p in emulators):
        print(f"emulators from {out} (delete them to refit)")
    else:
        check_option_memory(  # before the campaign; the fewest components, a lower bound
            parser, fit_memory(design.shape[0], 1, args.n_iter),
            f"--n-iter {args.n_iter}: gpmsa.fit's draws",
        )  # fmt: skip
        seeds = np.random.SeedSequence(0).generate_state(design.shape[0]).astype(int)
        jobs = [(v, gd, int(s), 120.0) for (v, gd), s in zip(design, seeds, strict=True)]
        with ProcessPoolExecutor(args.workers) as pool:
            acc = np.stack(list(pool.map(campaign_run, jobs, chunksize=4)))
        print(f"campaign: {design.shape[0]} runs x 120 s, {time.perf_counter() - tic:.0f} s")
        for channels in channel_sets:
            for case in cases:
                t0 = time.perf_counter()
                emu, n_pc = fit(design, acc, case, channels, args.n_iter, pcs)
                emu.save(emulator_path(out, channels, case, pcs))
                print(f"fit {channels} {case}: {n_pc} PCs, {time.perf_counter() - t0:.0f} s")
    for channels in channel_sets:
        print(f"\n=== {channels}" + ("" if channels == "front" else " + front"))
        for name in names:
            jobs = jobs_for(name, channels, cases, str(out), args.random_tracks, pcs)
            with ProcessPoolExecutor(args.workers) as pool:
                results = list(pool.map(drive, jobs, chunksize=2))
            for case in cases:
                if name in ("dev", "paper", "heldout"):
                    print("\n".join(cla.report_paper(results, name, case)))
                if name in ("dev", "random"):
                    print(cla.report_random(results, case))
                if name.startswith("steady"):
                    print("\n".join(cla.report_steady(results, case)))
    load = " ".join(f"{x:.2f}" for x in load_average())
    print(f"\n{time.perf_counter() - tic:.0f} s on {args.workers} worker(s), load average {load}")


if __name__ == "__main__":
    main()
