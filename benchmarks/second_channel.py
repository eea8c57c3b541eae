"""Would a second sensor add information about GD? And how much does the road itself hold?

    PYTHONPATH=. python benchmarks/second_channel.py            # 7 GDs x 3 speeds x 8 roads x 120 s
    PYTHONPATH=. python benchmarks/second_channel.py --quick    # 4 roads x 60 s
    PYTHONPATH=. python benchmarks/second_channel.py --help

The estimator observes one accelerometer over the Jackal's front axle. Its chassis is a rigid
body (heave, pitch), so a second sensor (an accelerometer over the rear axle, or a pitch-rate
gyro) sees the same road through another response. Per steady road (GD 250-550, 1.0 / 1.5 /
2.0 m/s), each channel is cut into the shipped blocks (125 samples, ``control.block_features``:
8 log band powers) and scored as a linear estimator of log GD:

- on the training roads (half of the road seeds; every GD level uses the same seeds, so the
  levels differ by their roughness, not by their road shapes), the mean feature is quadratic
  in log GD (least squares) and the block-to-block covariance Sigma is the long-run covariance
  (batch means of 8 blocks, as ``control.training``); the estimator weights are
  w = Sigma^-1 d, d the mean's slope;
- on the held-out roads (the other half of the seeds; then the halves swap), the information
  per block about log GD is J = (w' d_test)^2 / (w' Sigma_test w), d_test and Sigma_test
  measured there (1 / J is the variance of one block's log GD estimate).

Channels: the front accelerometer (shipped), the rear one, both (16 outputs), and the front
one with a pitch-rate gyro (the sampled pitch differentiated through the FFT; the 8 bands of
its rate); the front one with a rear axle synthesised from it and the gyro (the chassis is
rigid: a_rear = a_front - wheelbase x d(pitch rate)/dt, so without noise it is the rear axle;
with noise it carries the front's noise and the gyro noise's derivative); and the front-rear
and front-gyro pairs with their cross-spectra as well (per band, the real and imaginary parts
of the multitaper cross-spectrum over the square root of the two band powers: the relative
phase that separate band powers miss; 32 outputs), each without and with independent noise:
N(0, 1) m/s^2 on an accelerometer, N(0, 0.01^2) rad/s on the gyro (an assumed MEMS figure; the
pitch rate's rms is 0.5-1.4 rad/s on these roads). For reference, the same 8-band feature of the
road itself as the tyre sees it (``roadgen.wheel_envelope``, noise-free), in position blocks as
long as a block's drive and in the spatial band the 120 Hz sensor resolves at that speed (up to
60 / v cycles/m): what an ideal road sensor with this feature would give. Printed: J per block
(mean over the 7 GD levels and both folds), the ratio to the front channel, and the two folds'
J (their difference shows the scatter); then the elapsed time and the load average.

Run time: ~50 s at the defaults (docs/closed-loop.md's figures); ``--roads 4 --duration-s 30``
~10 s.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import numpy as np
from _host import load_average
from scipy.signal.windows import dpss

import roadgen
import vehicle
from control import FeatureSpec, block_features

GDS = (250.0, 300.0, 350.0, 400.0, 450.0, 500.0, 550.0)
SPEEDS = (1.0, 1.5, 2.0)
SPEC = FeatureSpec(quantiles=())  # the band powers: the channels' spectra
BATCH = 8  # blocks per batch mean (as control.training)
SETTLE_S = 2.0  # start-up transient dropped, s
GD_CENTRE = 400.0
GYRO_NOISE_RAD_S = 0.01  # an assumed MEMS gyro's white noise at 120 Hz, sd; the signal: 0.5-1.4
END_TRIM_S = 1.0  # dropped at the end: the spectral derivative's wrap-around, s


def spectral_derivative(x: np.ndarray, dt: float) -> np.ndarray:
    """d x / d t of a sampled signal through the FFT (exact within the band, unlike central
    differences, which fall to 0 at the Nyquist frequency), after removing the straight line
    through its ends; the ends' wrap-around leaves an error near them (END_TRIM_S)."""
    n = x.size
    trend = np.linspace(x[0], x[-1], n)
    freq = np.fft.rfftfreq(n, dt)
    rate = np.fft.irfft(2j * np.pi * freq * np.fft.rfft(x - trend), n)
    return rate + (x[-1] - x[0]) / ((n - 1) * dt)


def drive(job: tuple[float, float, int, float]) -> dict[str, np.ndarray]:
    """Block features of one steady road: front, rear, gyro (noise-free and noisy), the road."""
    speed, gd, seed, duration_s = job
    road = roadgen.iso8608_profile(speed * (duration_s + SETTLE_S) + 1.0, gd, seed=seed)
    model = vehicle.Jackal()
    trace = vehicle.simulate(model, road, speed)
    dt = 1.0 / trace.rate_hz
    start = int(SETTLE_S * trace.rate_hz)
    n = (trace.t.size - start - int(END_TRIM_S * trace.rate_hz)) // SPEC.block_samples
    n *= SPEC.block_samples
    noise = np.random.default_rng([seed, int(gd), int(100 * speed)]).standard_normal((3, n))
    gyro_noise = GYRO_NOISE_RAD_S * noise[2]
    # the rigid chassis: a_rear = a_front - wheelbase * d(pitch rate)/dt, so the rear axle
    # synthesised from the front accelerometer and the gyro is the rear axle plus the front's
    # noise and the wheelbase times the gyro noise's derivative
    synthesised_noise = noise[0] - model.wheelbase_m * spectral_derivative(gyro_noise, dt)
    out, blocks = {}, {}
    for name, signal, eps in (
        ("front", trace.accel_front, noise[0]),
        ("rear", trace.accel_rear, noise[1]),
        ("gyro", spectral_derivative(trace.pitch, dt), gyro_noise),
        ("synthesised_rear", trace.accel_rear, synthesised_noise),
    ):
        clean = signal[start : start + n]
        for suffix, x in (("", clean), ("_noisy", clean + eps)):
            blocks[name + suffix] = x.reshape(-1, SPEC.block_samples)
            out[name + suffix] = block_features(blocks[name + suffix], SPEC)
    for other in ("rear", "gyro"):
        for suffix in ("", "_noisy"):
            out[f"cross_{other}{suffix}"] = cross_features(
                blocks["front" + suffix], blocks[other + suffix]
            )
    out["road"] = road_features(road, model.wheel_radius_m, speed)
    return out


def cross_features(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(n, 16): per band of SPEC, Re and Im of the multitaper cross-spectrum of blocks x and y
    (n, B) summed over the band, over sqrt(band power of x * band power of y) (a coherency in
    [-1, 1]; same tapers and bands as the shipped feature)."""
    tapers = dpss(SPEC.block_samples, SPEC.taper_nw, SPEC.n_tapers)
    fx, fy = (
        np.fft.rfft((b - b.mean(axis=1, keepdims=True))[:, None] * tapers[None], axis=2)
        for b in (x, y)
    )
    freq = np.fft.rfftfreq(SPEC.block_samples, 1.0 / SPEC.rate_hz)
    edges = np.asarray(SPEC.bands_hz)
    bands = [(freq >= lo) & (freq < hi) for lo, hi in zip(edges[:-1], edges[1:], strict=True)]

    def band_sum(spec: np.ndarray) -> np.ndarray:
        return np.column_stack([spec[:, b].sum(axis=1) for b in bands])

    cross = band_sum((fx * fy.conj()).mean(axis=1))
    scale = np.sqrt(
        band_sum((np.abs(fx) ** 2).mean(axis=1)) * band_sum((np.abs(fy) ** 2).mean(axis=1))
    )
    return np.hstack([cross.real / scale, cross.imag / scale])


def road_features(road, wheel_radius_m: float, speed: float) -> np.ndarray:
    """8 log band powers of the enveloped road in blocks of one block's drive (m), bands
    log-spaced over the spatial frequencies the sensor resolves at ``speed`` (1.5 / v to
    60 / v cycles/m), multitaper as the shipped feature (NW 2, 3 tapers)."""
    z = roadgen.wheel_envelope(road, wheel_radius_m).z[int(SETTLE_S * speed / road.dx_m) :]
    n = int(round(speed * SPEC.block_s / road.dx_m))
    blocks = z[: z.size // n * n].reshape(-1, n)
    blocks = blocks - blocks.mean(axis=1, keepdims=True)
    tapers = dpss(n, SPEC.taper_nw, SPEC.n_tapers)
    power = (np.abs(np.fft.rfft(blocks[:, None] * tapers[None], axis=2)) ** 2).mean(axis=1)
    freq = np.fft.rfftfreq(n, road.dx_m)
    edges = np.geomspace(1.5 / speed, 60.0 / speed, 9)
    bands = [(freq >= lo) & (freq < hi) for lo, hi in zip(edges[:-1], edges[1:], strict=True)]
    return np.log(np.column_stack([power[:, b].sum(axis=1) for b in bands]))


def long_run_cov(runs: list[np.ndarray]) -> np.ndarray:
    """Long-run covariance of blocks about each run's mean (batch means of BATCH blocks)."""
    devs = []
    for x in runs:
        m = x.shape[0] // BATCH
        centred = x[: m * BATCH] - x.mean(axis=0)
        devs.append(centred.reshape(m, BATCH, -1).mean(axis=1) * np.sqrt(BATCH))
    d = np.concatenate(devs)
    return d.T @ d / d.shape[0]


def slope(runs: list[tuple[float, np.ndarray]], log_gd: float) -> np.ndarray:
    """d(mean feature)/d(log GD) at ``log_gd`` from a quadratic fit over (gd, blocks) runs."""
    x = np.concatenate([np.full(b.shape[0], np.log(gd / GD_CENTRE)) for gd, b in runs])
    y = np.vstack([b for _, b in runs])
    coef, *_ = np.linalg.lstsq(np.column_stack([np.ones_like(x), x, x * x]), y, rcond=None)
    return coef[1] + 2.0 * coef[2] * (log_gd - np.log(GD_CENTRE))


def held_out_information(train, test) -> float:
    """Mean over GD levels of the held-out J per block (see the module docstring)."""
    sigma = long_run_cov([b for _, b in train])
    out = []
    for gd in GDS:
        weights = np.linalg.solve(sigma, slope(train, np.log(gd)))
        gain = weights @ slope(test, np.log(gd))
        spread = weights @ long_run_cov([b for g, b in test if g == gd]) @ weights
        out.append(gain**2 / spread)
    return float(np.mean(out))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--roads", type=int, default=8, help="roads per (speed, GD), even")
    parser.add_argument("--duration-s", type=float, default=120.0, help="seconds per road")
    parser.add_argument("--workers", type=int, default=2, help="worker processes")
    parser.add_argument("--quick", action="store_true", help="4 roads x 60 s")
    args = parser.parse_args()
    if args.quick:
        args.roads, args.duration_s = 4, 60.0
    if args.roads < 4 or args.roads % 2:
        parser.error(f"--roads must be an even integer >= 4, got {args.roads}")
    if not 30.0 <= args.duration_s < np.inf:  # NaN fails too
        parser.error(
            f"--duration-s must be >= 30 (two batches per road) and finite, got {args.duration_s}"
        )
    if args.workers < 1:
        parser.error(f"--workers must be >= 1, got {args.workers}")

    tic = time.perf_counter()
    jobs = [
        (v, gd, seed, args.duration_s)
        for v in SPEEDS
        for gd in GDS
        for seed in range(1, args.roads + 1)
    ]
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(drive, jobs))
    channels = {
        "front (shipped)": ["front"],
        "rear": ["rear"],
        "front + rear": ["front", "rear"],
        "front + pitch-rate gyro": ["front", "gyro"],
        "front + rear, with cross-spectra": ["front", "rear", "cross_rear"],
        "front + gyro, with cross-spectra": ["front", "gyro", "cross_gyro"],
        "front + rear synthesised from the gyro": ["front", "synthesised_rear"],
        "front-rear cross-spectra alone": ["cross_rear"],
        "front-gyro cross-spectra alone": ["cross_gyro"],
    }
    print(
        f"{args.roads} roads x {args.duration_s:g} s per (speed, GD); J per block of "
        f"{SPEC.block_samples} samples ({SPEC.block_s:.2f} s), held out; fold 1 / fold 2"
    )
    for speed in SPEEDS:
        rows = [(job, res) for job, res in zip(jobs, results, strict=True) if job[0] == speed]
        print(f"\nv = {speed} m/s")
        lines = [
            (f"{name}{tag}", [k + suffix for k in keys])
            for suffix, tag in (("", ""), ("_noisy", ", N(0,1) noise"))
            for name, keys in channels.items()
        ]
        lines.append(("enveloped road, sensor's band (ideal road sensor)", ["road"]))
        base: dict[str, Any] = {}
        for label, keys in lines:
            folds = []
            for parity in (0, 1):
                sets = [
                    [
                        (job[1], np.hstack([res[k] for k in keys]))
                        for job, res in rows
                        if job[2] % 2 == p
                    ]
                    for p in (parity, 1 - parity)
                ]
                folds.append(held_out_information(*sets))
            j = float(np.mean(folds))
            ref = base.setdefault("noisy" if "noise" in label else "clean", j)
            print(f"  {label:52s} J {j:6.2f}  x{j / ref:4.2f}  ({folds[0]:.2f} / {folds[1]:.2f})")
    load = " ".join(f"{x:.2f}" for x in load_average())
    print(f"\n{time.perf_counter() - tic:.0f} s; load average {load}")


if __name__ == "__main__":
    main()
