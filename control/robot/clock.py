"""A sensor stream's stamps on its own regular clock: jitter removed, drops and clock steps kept.

A ROS driver stamps an IMU's messages with 1-3 ms of jitter (USB, receive-time stamping) while
it delivers every sample; at 120 Hz the BCR reads a step outside 0.5-1.5 periods as a dropped or
repeated sample, a sensor fault. `restamp` fits the stream's clock and gives each message its
slot's time, so that jitter well below half a period goes while a dropped message still leaves
an empty slot (a gap), a duplicate shares one and a clock step shows; `stamp_order` puts
messages delivered late (stamped right) back in stamp order, and `into_gaps` (odometry) those
later still whose stamps fill the gaps they left. The replay uses them
(`control.robot.replay`, docs/robot.md "Time stamps"), and `header_skew` to find an IMU whose
header stamps run on another clock than the odometry's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from control.robot.condition import GAP_PERIODS, increasing, nominal_period, robust_sd

REORDER_PERIODS = 3.0
"""Messages whose stamps step back by at most this many nominal periods are put in stamp order
(`stamp_order`): delivered late, not stamped wrong. A longer step back is a clock step, kept."""
RESTAMP_MAX_JITTER = 1 / 6
"""Largest jitter (robust sd of the stamps about the fitted clock, in periods) re-stamped by
`restamp` (1.39 ms at 120 Hz): at 1/6 period a sample lies half a period off its slot, on a
neighbour's, with probability 0.3 % (Gaussian jitter), and nearly all of those are put back by
their order (`_move_to_free_slots`; 100,000 messages at 120 Hz: no false gap at 0.15 period,
about 10 at 0.18, 100 at 0.21). Closer to half a period a late sample and a dropped one cannot
be told apart, and the stamps are left as recorded."""
RESTAMP_EXACT_S = 1e-6
"""Stamps within this of the fitted clock are kept as recorded (bit for bit): nothing to do."""
RESTAMP_MIN_RUN = 256
"""Shortest run of messages (between pauses and clock steps) whose clock is fitted; shorter runs
keep their stamps (their jitter stays a fault). The clock-step check (`_phase_step`) compares
blocks of 32, and in a short run the fitted rate absorbs part of a step: a step of 0.6-0.7
period in the middle of a run of 100 messages (jitter sd 0.05-0.1 period, 150 seeds each) was
re-stamped away in up to 14 of 141 runs whose recorded stamps showed it, 150-200 messages 1,
256 and 400 none (with 32 as the shortest run)."""
RESTAMP_SPLIT_PERIODS = 16.0
"""A step longer than this many periods (or a step back) starts a new run, its clock fitted
afresh: after a pause or a clock step the phase is another."""
RESTAMP_MOVE_PERIODS = 0.75
"""Two messages rounded onto one slot next to an empty one: the one nearer the empty slot moves
there when that puts it within this many periods of that slot's centre on the rounding phase
(`_cut_phase`: the clock itself for jitter symmetric about it; for receive times, late only, the
middle of where a slot's messages arrive, so that a message late by most of a period still goes
back to its slot) (a late or early sample, not a duplicate: a duplicate stays a repeated
stamp). Measured from the fitted clock instead, all 10 such pairs of 20,000 receive times with
exponential latency (mean 0.12 period) stayed (20 stamp faults, against 0); a lone message off
exact stamps by 0.625 period, which leaves the rounding phase 0.17 period off the clock, stays
a repeated stamp (a fault: one odd message cannot tell where its slot's messages arrive)."""


@dataclass(frozen=True)
class Restamping:
    """What `restamp` did to a stream's stamps.

    Attributes:
        restamped: whether the stamps were replaced by the fitted clock's.
        rate_hz: the fitted clock's rate, Hz (NaN where none was fitted).
        jitter_sd_s: robust sd (`condition.robust_sd`) of the stamps about the clock, s (NaN: none).
        jitter_max_s: largest distance of a stamp from its slot on the clock, s (NaN: none).
        runs: runs fitted (split at pauses and clock steps).
        moved: messages moved to a free neighbouring slot.
        note: what was done, for a person ("" where the stamps were exact or too few).
    """

    restamped: bool
    rate_hz: float = np.nan
    jitter_sd_s: float = np.nan
    jitter_max_s: float = np.nan
    runs: int = 0
    moved: int = 0
    note: str = ""


def stamp_order(t: np.ndarray, window_s: float) -> np.ndarray:
    """The order (indices) that sorts messages with times ``t`` (s, in received order, finite)
    by time wherever a time steps back by at most ``window_s`` (late delivery); a step back by
    more is a clock step: the messages on either side keep their order (a stable sort within
    the runs between such steps; repeated times keep theirs)."""
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        return np.arange(t.size)
    run = np.concatenate([[0], np.cumsum(np.diff(t) < -window_s)])
    return np.lexsort((t, run))


def into_gaps(t: np.ndarray, order: np.ndarray, period: float) -> tuple[np.ndarray, int]:
    """``order`` (`stamp_order`'s of times ``t``, s) with each message it leaves behind a later
    one (more than its window late, a repeated stamp, a clock step back) moved into stamp
    order where its time fills a gap the messages in order leave: it lies between two of them
    more than `GAP_PERIODS` ``period`` apart, at least half a period from each, and the gap
    takes as many as its missing slots hold (each half a period from the next). A message
    received late, stamped right, fills the slot it left empty; a message after a clock step
    back, a repeated or stale stamp, or a stamp of 0 lands on slots taken (or outside the
    stream), and stays behind. Messages left behind one after another in ``order`` (a burst
    delivered late, the stretch after a clock step back) move together or not at all: a
    clock step's messages that land in a gap stay behind with the rest. Returns (the order,
    the messages moved)."""
    ts = t[order]
    kept = increasing(ts)
    late = np.flatnonzero(~kept & np.isfinite(ts))
    if not late.size or np.count_nonzero(kept) < 2 or not np.isfinite(period):
        return order, 0
    at = np.flatnonzero(kept)
    k, tc = ts[at], ts[late]
    j = np.clip(np.searchsorted(k, tc), 1, k.size - 1)  # the gap (k[j - 1], k[j])
    lo, hi = k[j - 1], k[j]
    fits = (hi - lo > GAP_PERIODS * period) & (tc - lo >= period / 2) & (hi - tc >= period / 2)
    block = np.cumsum(kept)[late]  # messages left behind one after another: one block
    fits &= ~np.isin(block, block[~fits])
    fits[_overfilled(j, tc, fits, k, period)] = False  # not (only) late messages
    fits &= ~np.isin(block, block[~fits])  # a block moves whole or not at all
    if not fits.any():
        return order, 0
    anchor = np.arange(ts.size, dtype=float)  # each moved message right after the gap's start
    anchor[late[fits]] = at[j[fits] - 1] + 0.5
    return order[np.lexsort((ts, anchor))], int(np.count_nonzero(fits))


def _overfilled(
    j: np.ndarray, tc: np.ndarray, fits: np.ndarray, k: np.ndarray, period: float
) -> np.ndarray:
    """Mask of the late messages that fit (``fits``; time ``tc``, in gap ``j`` between the
    times ``k[j - 1]`` and ``k[j]`` in order) whose gap gets more than its missing slots hold,
    or two of them less than half a period apart. One sort for all gaps (a loop over the gaps
    cost a pass over every late message per gap: quadratic in a long stream's gaps)."""
    out = np.zeros(fits.shape, dtype=bool)
    idx = np.flatnonzero(fits)
    if not idx.size:
        return out
    idx = idx[np.lexsort((tc[idx], j[idx]))]  # by gap, then by time
    gap, times = j[idx], tc[idx]
    new = np.r_[True, gap[1:] != gap[:-1]]  # a gap's first message
    first = np.flatnonzero(new)
    gaps, count = gap[first], np.diff(np.r_[first, gap.size])
    slots = np.rint((k[gaps] - k[gaps - 1]) / period) - 1
    close = np.r_[False, (np.diff(times) < period / 2) & ~new[1:]]  # within one gap
    bad = (count > slots) | np.logical_or.reduceat(close, first)
    out[idx[np.repeat(bad, count)]] = True
    return out


def _fit_line(k: np.ndarray, t: np.ndarray) -> tuple[float, float]:
    """(c, period) of the least-squares line t = c + period * k (k not all equal)."""
    km, tm = k.mean(), t.mean()
    dk = k - km
    period = float(np.dot(dk, t - tm) / np.dot(dk, dk))
    return float(tm - period * km), period


def _clock_slots(t: np.ndarray, period: float) -> tuple[np.ndarray, float, float, float]:
    """(slot index of each time, c, period, c') of the clock c + period * k fitted to ``t`` (one
    run) on a window that grows by half from 64 messages, so that the period is known well
    enough to round the next window's indices (jitter never adds up): per window, twice, the
    clock's phase is the circular mean of the times modulo the period, the indices the times
    rounded on it, and the line is fitted to the messages within 0.4 period of their slots.
    The final slots are rounded on c' + period * k, whose edges lie where the times fall least
    often (`_cut_phase`)."""
    c, w = float(t[0]), min(64, t.size)
    while True:
        for _ in range(2):
            x = t[:w] - c
            c += period * float(np.angle(np.mean(np.exp(2j * np.pi * x / period)))) / (2 * np.pi)
            k = np.rint((t[:w] - c) / period)
            near = np.abs(t[:w] - c - period * k) <= 0.4 * period
            kn = k[near]
            if kn.size > 1 and kn[-1] > kn[0]:
                c, period = _fit_line(kn, t[:w][near])
        if w == t.size:
            cut = _cut_phase(t, c, period)
            k = np.rint((t - cut) / period)
            return k, c + period * np.rint((cut - c) / period), period, cut
        w = min(w + w // 2, t.size)


def _cut_phase(t: np.ndarray, c: float, period: float) -> float:
    """The phase (c' of c' + period * k) whose rounding puts the slots' edges where the times
    fall least often (of 32 phase bins about the clock c + period * k; among equally empty
    bins the middle of the longest run): for jitter symmetric about the clock that is ``c``,
    for latency (receive times: late only) just before the earliest arrivals, so that a late
    sample is less often rounded onto the next slot."""
    bins = 32
    phase = np.mod((t - c) / period + 0.5, 1.0)  # 0.5: on the clock, 0 and 1: an edge
    counts = np.bincount(np.minimum((phase * bins).astype(int), bins - 1), minlength=bins)
    smooth = counts + np.roll(counts, 1) + np.roll(counts, -1)
    low = np.flatnonzero(smooth == smooth.min())
    # the longest circular run of the emptiest bins, from its first bin
    runs = np.split(low, np.flatnonzero(np.diff(low) > 1) + 1)
    if len(runs) > 1 and runs[0][0] == 0 and runs[-1][-1] == bins - 1:
        runs[0] = np.concatenate([runs.pop() - bins, runs[0]])
    run = max(runs, key=len)
    edge = ((run[0] + run[-1]) / 2 + 0.5) / bins
    return c + period * (edge - round(edge))


def _move_to_free_slots(k: np.ndarray, r: np.ndarray, period: float) -> int:
    """Resolve two messages on one slot next to a free one (``k`` and the times' offsets ``r``
    from their slots' centres, in place): the one nearer the free slot moves there where its
    time lies within RESTAMP_MOVE_PERIODS of that slot's centre; the count moved."""
    moved = 0
    limit = RESTAMP_MOVE_PERIODS * period
    for i in np.flatnonzero(k[1:] == k[:-1]) + 1:
        if k[i] != k[i - 1] or r[i] == r[i - 1]:
            continue  # resolved by an earlier move, or a duplicate (one stamp twice): kept
        late = r[i] - period  # message i on the next slot
        early = r[i - 1] + period  # message i - 1 on the slot before
        free_next = i + 1 == k.size or k[i + 1] > k[i] + 1
        free_before = i - 1 == 0 or k[i - 2] < k[i] - 1
        if free_next and abs(late) <= limit and (not free_before or abs(late) <= abs(early)):
            k[i] += 1
            r[i] = late
        elif free_before and abs(early) <= limit:
            k[i - 1] -= 1
            r[i - 1] = early
        else:
            continue
        moved += 1
    return moved


RESTAMP_STEP_PERIODS = 0.25
"""A shift of the stamps' phase by more than this many periods (the median offset from the
clock of 32 messages against the 32 before) is a clock step: the run is split there, so that the
step reaches the BCR (`restamp`). Smaller steps are taken for jitter."""


def _phase_step(r: np.ndarray, period: float) -> int:
    """Index (> 0) where the offsets ``r`` of a run's times from its clock shift by more than
    RESTAMP_STEP_PERIODS periods (medians of blocks of 32, each against the one two blocks on:
    a step inside the block between splits its median; located at the split of those 96 into
    two levels that fits them best), or 0: none."""
    n = r.size // 32
    if n < 3:
        return 0
    med = np.median(r[: n * 32].reshape(n, 32), axis=1)
    jump = np.flatnonzero(np.abs(med[2:] - med[:-2]) > RESTAMP_STEP_PERIODS * period)
    if not jump.size:
        return 0
    j = 32 * int(jump[0])  # the step lies in these 96: at the split that fits them best by
    w = r[j : j + 96]  # two levels (least squares: one jittered offset cannot move it far)
    i = np.arange(1, w.size)
    before = np.cumsum(w)[:-1]
    shift = before / i - (w.sum() - before) / (w.size - i)
    return j + int(np.argmax(i * (w.size - i) * shift * shift)) + 1


def restamp(t: np.ndarray, what: str = "the stamps") -> tuple[np.ndarray, Restamping]:
    """``t`` (s, finite, in stamp order) on its own regular clock: jitter removed, nothing else.

    The stream is cut into runs at pauses (steps longer than RESTAMP_SPLIT_PERIODS nominal
    periods), at steps back and where the stamps' phase shifts (a clock step of more than
    RESTAMP_STEP_PERIODS, `_phase_step`); on each run of at least RESTAMP_MIN_RUN messages a clock
    c + period * k is fitted and each message given its slot k (its time rounded on the
    clock; two messages on one slot next to a free one are told apart by their order,
    `_move_to_free_slots`). The new time of a message is its slot's. A dropped message leaves
    its slot empty (a gap of two periods), a duplicate shares a slot (a repeated stamp) and a
    clock step shows as a slot skipped or repeated, so the BCR still reports each as a
    sensor fault; jitter below half a period is gone.

    The stamps are kept as recorded where every one lies within RESTAMP_EXACT_S of its clock
    (nothing to remove: exact stamps give the same samples bit for bit) or where the jitter's
    robust sd (`condition.robust_sd` about the clock, over all runs) exceeds RESTAMP_MAX_JITTER
    periods: there a sample half a period late cannot be told from a dropped one, and the note
    says so. ``what`` names the stamps in the note ("the IMU topic '/imu/data''s header
    stamps").
    """
    t = np.asarray(t, dtype=float)
    period = nominal_period(t)
    if t.size < RESTAMP_MIN_RUN or not np.isfinite(period):
        return t, Restamping(False)
    step = np.diff(t)
    splits = np.flatnonzero((step > RESTAMP_SPLIT_PERIODS * period) | (step < 0)) + 1
    bounds = np.concatenate([[0], splits, [t.size]])
    out, resid, fitted = t.copy(), np.full(t.size, np.nan), np.zeros(t.size, dtype=bool)
    rates, moved = [], 0  # rates: (messages, Hz) of each run fitted
    todo = list(zip(bounds[:-1], bounds[1:], strict=True))
    while todo:
        lo, hi = todo.pop()
        if hi - lo < RESTAMP_MIN_RUN:
            continue
        k, c, p, edge = _clock_slots(t[lo:hi], period)
        at = _phase_step(t[lo:hi] - (c + p * k), p)
        if at:  # the clock stepped inside the run: fit each side on its own
            todo += [(lo, lo + at), (lo + at, hi)]
            continue
        moved += _move_to_free_slots(k, t[lo:hi] - (edge + p * k), p)
        out[lo:hi], resid[lo:hi], fitted[lo:hi] = c + p * k, t[lo:hi] - (c + p * k), True
        rates.append((hi - lo, 1.0 / p))
    runs = len(rates)
    if not runs:
        return t, Restamping(False)
    r = resid[fitted]
    sd = robust_sd(r)
    worst = float(np.max(np.abs(r)))
    rate = float(max(rates)[1])  # the longest run's
    info = dict(rate_hz=rate, jitter_sd_s=sd, jitter_max_s=worst, runs=runs, moved=moved)
    if worst <= RESTAMP_EXACT_S:
        return t, Restamping(False, **info)
    if sd > RESTAMP_MAX_JITTER * period:
        return t, Restamping(False, **info, note=(
            f"{what} were not re-stamped: they jitter by sd {sd * 1e3:.2g} ms about a "
            f"{rate:.2f} Hz clock, more than {RESTAMP_MAX_JITTER:g} of its "
            f"{1e3 / rate:.3g} ms period: a sample half a period late cannot be told from a "
            "dropped one, so the BCR sees the stamps as recorded (steps outside 0.5-1.5 "
            "periods are sensor faults); stamp the messages at the sensor, or with less "
            "latency"
        ))  # fmt: skip
    text = (
        f"{what} re-stamped on a {rate:.2f} Hz clock"
        + (f" ({runs} runs, split at pauses and clock steps)" if runs > 1 else "")
        + f": jitter sd {sd * 1e3:.2g} ms, max {worst * 1e3:.2g} ms"
        + (f"; {moved} late or early message(s) moved to a free neighbouring slot" if moved else "")
    )
    if not fitted.all():
        text += (
            f"; {np.count_nonzero(~fitted)} message(s) in runs too short to fit kept as recorded"
        )
    return out, Restamping(True, **info, note=text)


SKEW_BIN_S = 1.0
"""`header_skew` takes the median over the messages received within each such span, s: a
message delivered late by a loaded recorder moves no median."""


def header_skew(
    imu_stamp_ns: np.ndarray, imu_log_ns: np.ndarray, odom_stamp_ns: np.ndarray,
    odom_log_ns: np.ndarray,
) -> np.ndarray | None:  # fmt: skip
    """How far each IMU message's header clock runs from the odometry's, s (> 0: the IMU's
    ahead), against the receive times both share: (stamp - receive time) of the IMU less that
    of the odometry (interpolated at the IMU's receive time), its median over each
    `SKEW_BIN_S` of receive time. On one clock it is the difference of the two topics'
    delivery latencies (ms); on two, their offset (an IMU stamped in GPS time, a driver's clock
    step). Receive times in received (rising) order, as `read_recording` gives them. None where
    either topic's are not usable: fewer than two distinct ones, or fewer distinct than half
    its messages (a bag whose writer set them all alike)."""
    logs = (np.asarray(imu_log_ns, dtype=np.int64), np.asarray(odom_log_ns, dtype=np.int64))
    if any(np.count_nonzero(np.diff(x)) + 1 < max(2, x.size // 2) for x in logs):
        return None
    il, ol = logs
    t0 = int(il[0])
    imu = (np.asarray(imu_stamp_ns, dtype=np.int64) - il) / 1e9
    odom = (np.asarray(odom_stamp_ns, dtype=np.int64) - ol) / 1e9
    skew = imu - np.interp((il - t0) / 1e9, (ol - t0) / 1e9, odom)
    key = np.floor((il - t0) / 1e9 / SKEW_BIN_S)
    edges = np.r_[0, np.flatnonzero(np.diff(key)) + 1, key.size]  # received order: key rises
    out = np.empty_like(skew)
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        out[a:b] = np.median(skew[a:b])
    return out
