"""BCR with test doubles: the change-point method on blocks, the window methods, the guards."""

import numpy as np
import pytest
from control_doubles import FakeBlockModel, FakeCalibrator, log_f, stream
from hypothesis import example, given, settings
from hypothesis import strategies as st

from control import (
    BCR,
    PAPER_WINDOW,
    STATUSES,
    BCRSettings,
    ControlError,
    ControlWarning,
    EmulatorMismatchError,
    Estimate,
    FeatureSpec,
    SensorFault,
    Simplex,
)
from control.estimate import favoured_edge
from control.faults import FaultInjector
from control.sensor_checks import MIN_SEGMENT

WINDOW = {"feature": PAPER_WINDOW}
ONE_FILTER = {"update_every": 125}  # one change-point filter: an estimate per 125-sample block
EVERY = BCRSettings().samples_per_update  # the default: three interleaved filters


def feed(bcr, t, p, a, v, chunk=125):
    return [
        bcr.update(t[k : k + chunk], p[k : k + chunk], a[k : k + chunk], v[k : k + chunk])
        for k in range(0, t.size, chunk)
    ]


def const(gd):
    return lambda s: np.full_like(s, gd)


# --- the change-point method ----------------------------------------------------------------------


def test_every_block_gives_an_estimate_that_pools_on_steady_ground(block_model):
    ests = feed(BCR(block_model, **ONE_FILTER), *stream(const(400), 1.5, 60, seed=1))
    assert all(e.ok for e in ests) and len(ests) == 58  # 7,200 samples fed in 58 chunks
    assert block_model.calls == 57  # one per complete 125-sample block, none filling
    # pooling: the estimates beat what one block alone says about GD
    one = [block_model.gd[np.argmax(block_model.loglik(e.feature, 1.5))] for e in ests[20:]]
    pooled = [e.gd_mean for e in ests[20:]]
    assert np.sqrt(np.mean((np.array(pooled) - 400) ** 2)) < 0.6 * np.sqrt(
        np.mean((np.array(one) - 400) ** 2)
    )
    assert abs(np.mean(pooled) - 400) < 25
    assert ests[-1].prob_change < 0.2 and ests[-1].latency_s > 0
    assert ests[-1].feature.shape == (10,) and ests[-1].data_time == pytest.approx(ests[-1].time)


def test_intervals_cover_the_truth_at_about_their_level():
    inside, total = 0, 0
    for seed in range(6):
        ests = feed(BCR(FakeBlockModel()), *stream(const(350), 1.2, 60, seed=seed))
        checked = ests[10::10]  # spaced, so that the checks are nearly independent
        inside += sum(e.interval[0] <= 350 <= e.interval[1] for e in checked)
        total += len(checked)
    assert 0.75 <= inside / total <= 1.0


def test_a_step_is_followed_within_a_few_blocks(block_model):
    gd = lambda s: np.where(s < 45, 300.0, 500.0)  # noqa: E731
    ests = feed(BCR(block_model), *stream(gd, 1.5, 60, seed=3))
    pos = np.array([e.position for e in ests])
    mean = np.array([e.gd_mean for e in ests])
    delay = pos[np.argmax((pos > 45) & (mean > 400))] - 45
    assert 0 < delay < 8.0  # metres: a few 1.56 m blocks
    change = np.array([e.prob_change for e in ests])
    assert change[(pos > 45) & (pos < 45 + delay + 3)].max() > 0.5
    assert abs(mean[-5:].mean() - 500) < 50


@pytest.mark.parametrize(
    ("gd", "edge", "side", "mode"),
    [(750.0, "upper", "rougher", "safety"), (150.0, "lower", "smoother", "performance")],
)
@pytest.mark.parametrize("method", ["changepoint", "filter", "window"])
def test_a_road_beyond_the_domain_is_named_and_a_rougher_one_means_safety(
    block_model, fake_calibrator, method, gd, edge, side, mode
):
    if method == "changepoint":
        if gd < block_model.gd[0]:  # smoother than any GD: the quiet-signal check's case
            quiet = feed(BCR(block_model), *stream(const(gd), 1.5, 120, seed=0))[-10:]
            assert all(e.status == "implausible" and "read quieter" in e.reason for e in quiet)
            assert all(Simplex(gd_min=100.0, gd_max=650.0).command(e).mode == "safety"
                       for e in quiet)  # fmt: skip
        # without the check the edge is named, as by the window methods
        bcr, lo, hi = BCR(block_model, quiet_blocks=0), block_model.gd[0], block_model.gd[-1]
    else:
        bcr, lo, hi = BCR(fake_calibrator, method=method, **WINDOW), 200.0, 600.0
    ests = feed(bcr, *stream(const(gd), 1.5, 120, seed=0))
    late = [e for e in ests if e.ok][-10:]
    assert len(late) == 10 and all(e.domain_edge == edge and side in e.reason for e in late)
    # the posterior cannot leave the domain: the note is what says the road lies beyond it
    assert all(lo * (1 - 1e-12) <= e.interval[0] <= e.interval[1] <= hi * (1 + 1e-12) for e in late)
    # GD_max above the domain (check_emulator refuses it): here only the edge can mean safety
    simplex = Simplex(gd_min=100.0, gd_max=650.0)
    assert all(simplex.command(e).mode == mode for e in late)
    if method == "changepoint":  # standing: the carried estimate keeps its note
        t, p = 120.0 + np.arange(1, 251) / 120, np.full(250, 180.0)
        noise = 0.01 * np.random.default_rng(2).standard_normal(250)
        still = feed(bcr, t, p, noise, np.zeros(250))[-1]
        assert still.ok and "no new information" in still.reason and side in still.reason


@pytest.mark.parametrize("method", ["changepoint", "filter"])
def test_inside_the_domain_no_edge_is_named(block_model, fake_calibrator, method):
    for gd in (230.0, 400.0, 550.0):
        if method == "changepoint":
            bcr = BCR(block_model)
        else:
            bcr = BCR(fake_calibrator, method=method, **WINDOW)
        ests = feed(bcr, *stream(const(gd), 1.5, 60, seed=0))
        assert all(e.domain_edge == "" and e.reason == "" for e in ests if e.ok)


def test_the_default_hdi_holds_a_gd_at_the_domains_edge_and_the_central_one_cannot(block_model):
    t, p, a, v = stream(const(200.0), 1.5, 60, seed=0)
    late = {}
    for kind in ("hdi", "central"):
        ests = feed(BCR(block_model, interval_kind=kind), t, p, a, v)
        late[kind] = [e for e in ests if e.ok][-30:]
    assert all(e.interval[0] == 200.0 for e in late["hdi"])
    assert all(e.interval[0] > 200.0 for e in late["central"])
    # the same posterior: only the interval differs
    assert [e.gd_mean for e in late["hdi"]] == [e.gd_mean for e in late["central"]]
    with pytest.raises(ControlError, match="interval_kind must be one of"):
        BCRSettings(interval_kind="equal_tails")


def test_favoured_edge_needs_strong_evidence_beyond_the_margin():
    nodes = np.geomspace(200.0, 600.0, 121)
    prior = np.full(nodes.size, 1.0 / nodes.size)

    def post(log_lik):
        mass = prior * np.exp(log_lik - log_lik.max())
        return mass / mass.sum()

    rising = 100.0 * np.log(nodes)  # the likelihood still rises at 600: its peak lies beyond
    assert favoured_edge(nodes, post(rising), prior) == "upper"
    assert favoured_edge(nodes, post(-rising), prior) == "lower"
    peak = lambda centre, sd: -0.5 * (np.log(nodes / centre) / sd) ** 2  # noqa: E731
    assert favoured_edge(nodes, post(peak(400.0, 0.05)), prior) == ""
    assert favoured_edge(nodes, post(np.zeros(nodes.size)), prior) == ""  # no information
    # a peak at the edge itself counts only with a Bayes factor > 20 against 5% inside
    assert favoured_edge(nodes, post(peak(600.0, 0.02)), prior) == "upper"
    assert favoured_edge(nodes, post(peak(600.0, 0.05)), prior) == ""
    narrow = np.linspace(590.0, 600.0, 11)  # no node 5% inside: no edge can be named
    assert favoured_edge(narrow, post(rising)[-11:], prior[-11:]) == ""
    # nodes the prior excludes carry no evidence
    fenced = np.where(nodes > 550.0, 0.0, prior)
    assert favoured_edge(nodes, post(rising) * (nodes <= 550.0), fenced) == ""


def test_a_fault_skips_its_block_and_keeps_the_run_length_posterior(block_model):
    t, p, a, v = stream(const(400), 1.5, 40, seed=2)
    a = a.copy()
    a[2510:2520] = np.nan
    bcr = BCR(block_model, **ONE_FILTER)
    k = 2510 // 125
    ests = feed(bcr, t[: (k + 2) * 125], p[: (k + 2) * 125], a[: (k + 2) * 125], v[: (k + 2) * 125])
    # the run-length posterior is that of the clean blocks before the undone one, carried over
    # the distance of the three blocks without data: unharmed, not reset
    from control import ChangePointFilter
    from control.feature import block_features

    ref = ChangePointFilter(block_model.gd, bcr.settings.changepoint)
    step = 1.5 * 125 / 120
    for j in range(k - 1):
        y = block_features(a[j * 125 : (j + 1) * 125], bcr.settings.feature)[0]
        ref.update(block_model.loglik(y, 1.5), 0.0 if j == 0 else step)
    ref.predict(2 * step)  # the undone block and the faulty one
    ref.predict(step)  # the block after it
    np.testing.assert_allclose(bcr.filter.gd_mass, ref.gd_mass, rtol=1e-9, atol=1e-15)
    ests += feed(
        bcr, t[(k + 2) * 125 :], p[(k + 2) * 125 :], a[(k + 2) * 125 :], v[(k + 2) * 125 :]
    )
    # the faulty block, and the block after it (it may hold the fault's end), are skipped; the
    # block before it is undone (it may hold the fault's start)
    assert [e.status for e in ests[k - 1 : k + 3]] == ["ok", "sensor_fault", "filling", "ok"]
    assert "10 sample(s) with non-finite accel" in ests[k].reason and np.isnan(ests[k].gd_mean)
    assert "block before it is undone" in ests[k].reason
    assert "first block after a fault" in ests[k + 1].reason
    assert ests[k + 2].ok


@pytest.mark.parametrize("every", [63, 42])
def test_interleaved_phases_each_pool_their_own_disjoint_blocks(block_model, every):
    """update_every = 63 (42) of 125: two (three) filters, each on blocks ending 126 samples
    apart; every update reports their mixture, the phase whose block just ended weighing K, the
    one before it K - 1, and so on."""
    from control import ChangePointFilter
    from control.changepoint import mixture_posterior
    from control.feature import block_features

    t, p, a, v = stream(const(400), 1.5, 30, seed=4)
    bcr = BCR(block_model, update_every=every)
    k = bcr.settings.phases
    assert k == -(-125 // every)
    ests = feed(bcr, t, p, a, v, chunk=every)
    n_filling = -(-125 // every) - 1  # updates before the first whole block
    assert all(e.status == "filling" for e in ests[:n_filling])
    assert f"{every} of 125" in ests[0].reason
    assert all(e.ok for e in ests[n_filling:])
    # one likelihood per update after filling: each block is the newest 125 samples
    n_updates = t.size // every
    assert block_model.calls == n_updates - n_filling
    step = 1.5 * k * every / 120  # metres between the ends of one phase's blocks
    refs = []
    for last in range(n_updates - 1, n_updates - 1 - k, -1):  # the newest update of each phase
        ends = [every * (u + 1) for u in range(last % k, last + 1, k) if u >= n_filling]
        ref = ChangePointFilter(block_model.gd, bcr.settings.changepoint)
        for j, end in enumerate(ends):
            y = block_features(a[end - 125 : end], bcr.settings.feature)[0]
            ref.update(block_model.loglik(y, 1.5), 0.0 if j == 0 else step)
        phase = bcr._phases[last % k].filter
        np.testing.assert_allclose(phase.gd_mass, ref.gd_mass, rtol=1e-9, atol=1e-300)
        refs.append(ref)
    pooled = mixture_posterior(refs, np.arange(k, 0, -1.0))
    np.testing.assert_allclose(
        ests[-1].posterior.grids["GD"].density, pooled.grids["GD"].density, rtol=1e-9
    )
    # each estimate at least as well pooled as those of one filter
    one = feed(BCR(block_model, **ONE_FILTER), t, p, a, v)
    assert ests[-1].gd_sd == pytest.approx(one[-1].gd_sd, rel=0.15)


def test_the_pooled_mass_by_run_length_is_the_estimates_posterior(block_model, fake_calibrator):
    t, p, a, v = stream(const(400), 1.5, 30, seed=4)
    bcr = BCR(block_model)
    with pytest.raises(ControlError, match="no block has been used yet"):
        bcr.mass_by_run([5.0])
    est = feed(bcr, t, p, a, v, chunk=EVERY)[-1]
    parts = bcr.mass_by_run([5.0, 15.0])
    marginal = est.posterior.grids["GD"]
    mass = marginal.density * marginal.weights
    np.testing.assert_allclose(parts.sum(axis=0), mass / mass.sum(), rtol=1e-9, atol=1e-300)
    assert parts[0].sum() == pytest.approx(est.prob_change, rel=1e-9)  # 5 m = recent_change_m
    with pytest.raises(ControlError, match="needs method 'changepoint'"):
        BCR(fake_calibrator, method="window", **WINDOW).mass_by_run([5.0])


def test_with_phases_the_estimate_holds_still_while_no_information_comes(block_model):
    """Crawling (speed below the emulator's range): no phase learns anything, so the pooled
    estimate must not alternate with the phase that happens to update; it only drifts as the
    chance of a change grows with the distance crawled."""
    t, p, a, v = stream(const(400), 1.5, 12, seed=6)
    t2, p2, a2, v2 = stream(const(400), 0.2, 3, seed=7, t0=t[-1], s0=p[-1])
    bcr = BCR(block_model)
    feed(bcr, t, p, a, v, chunk=EVERY)
    still = feed(bcr, t2, p2, a2, v2, chunk=EVERY)[2:]  # the first blocks straddle the stop
    still = list({e.time: e for e in still}.values())  # a short last chunk repeats the last
    assert len(still) >= 3 and all(e.ok and "no new information" in e.reason for e in still)
    steps = np.diff([e.gd_mean for e in still])
    assert np.all(steps < 0) or np.all(steps > 0)  # one way, not back and forth
    assert np.max(np.abs(steps)) < 0.5 and len({e.data_time for e in still}) == 1


def test_with_phases_a_fault_undoes_and_skips_the_blocks_around_it_in_every_phase(block_model):
    t, p, a, v = stream(const(400), 1.5, 40, seed=2)
    a = a.copy()
    a[2510:2520] = np.nan  # in the update ending at sample 2520 (63 * 40)
    bcr = BCR(block_model, update_every=63)
    ests = []
    for start in range(0, t.size, 63):
        part = slice(start, start + 63)
        ests.append(bcr.update(t[part], p[part], a[part], v[part]))
        if start + 63 == 2331:  # update 36, phase 0's block before its newest one at the fault
            kept = bcr._phases[0].filter.state()
        if start + 63 == 2520:
            at_fault = bcr._phases[0].filter.state(), bcr._phases[0].pending_m
    k = 2520 // 63 - 1  # that update; the NaN samples' time stamps are sound: no gap after
    assert [e.status for e in ests[k - 1 : k + 5]] == [
        "ok", "sensor_fault", "filling", "filling", "filling", "ok"
    ]  # fmt: skip
    assert "non-finite accel" in ests[k].reason and "block before it is undone" in ests[k].reason
    assert "block holds 63 of 125" in ests[k + 1].reason  # restarted after the NaN samples
    assert not any("gap" in e.reason for e in ests)
    # the first complete block after the restart, in each phase, may hold the fault's end
    assert all("first block after a fault" in e.reason for e in ests[k + 2 : k + 4])
    assert all(e.ok for e in ests[k + 4 :]) and abs(ests[-1].gd_mean - 400) < 60
    # the other phase's newest block (update 38, overlapping the faulty block) was taken back:
    # its filter is as after update 36, and that block's distance waits for its next update
    (mass, dist, has_data), pending = at_fault
    np.testing.assert_array_equal(mass, kept[0])
    np.testing.assert_array_equal(dist, kept[1])
    assert has_data and pending == pytest.approx(1.5 * 126 / 120)


@pytest.mark.parametrize(
    ("kind", "magnitude", "status", "words"),
    [
        ("nan", 1.0, "sensor_fault", "non-finite accel"),
        ("time_nan", 1.0, "sensor_fault", "non-finite t"),
        ("position_nan", 1.0, "sensor_fault", "non-finite position"),
        ("drop", 1.0, "sensor_fault", "gap"),
        ("stuck", 1.0, "sensor_fault", "stuck sensor"),
        ("quantize", 5.0, "sensor_fault", "quantised"),
        ("clip", 0.05, "sensor_fault", "clipped"),
        ("spike", 10.0, "sensor_fault", "out of range"),  # spikes of +-1e6 m/s^2: no sensor reads
        ("scale", 1e-3, "implausible", "no GD in"),
        ("noise", 100.0, "implausible", "no GD in"),
    ],
)
def test_each_fault_kind_gives_no_estimate_and_the_bcr_recovers(
    block_model, kind, magnitude, status, words
):
    t, p, a, v = stream(const(400), 1.5, 30, seed=5)
    fault = SensorFault(10.0, 2.0, kind, magnitude)
    obs = FaultInjector([fault], np.random.default_rng(0))(t, p, a, v)
    bcr = BCR(block_model)
    every = bcr.settings.samples_per_update  # one update per call, as in the closed loop
    ests = feed(bcr, *obs, chunk=every)
    ends = obs[0][every - 1 :: every]  # the time of each call's last sample (after any drop)
    hit = [e for e, end in zip(ests, ends, strict=False) if 10.0 <= end < 12.0 + 125 / 120]
    assert hit and all(not e.ok for e in hit[1:-1])
    assert any(e.status == status and words in e.reason for e in hit)
    assert ests[-1].ok and abs(ests[-1].gd_mean - 400) < 60


def test_a_quantisation_of_seven_samples_is_a_sensor_fault(block_model):
    """Soak seed 19, #131: steps of 2.6 m/s^2 for 0.06 s, unflagged before the lattice check,
    drove 3.5 m too fast on rough ground."""
    t, p, a, v = stream(const(400), 1.5, 20, seed=5)
    fault = SensorFault(10.001, 0.058, "quantize", 2.6)
    obs = FaultInjector([fault], np.random.default_rng(0))(t, p, a, v)
    assert np.sum(obs[2] != a) == 7
    bcr = BCR(block_model)
    ests = feed(bcr, *obs, chunk=bcr.settings.samples_per_update)
    hit = [e for e in ests if e.status == "sensor_fault"]
    assert hit and all("quantised signal" in e.reason for e in hit)
    assert all(10.0 <= e.time < 10.06 + 2 * 125 / 120 for e in hit)
    assert ests[-1].ok


def test_a_call_with_many_updates_returns_its_gravest_fault_not_only_the_newest(block_model):
    t, p, a, v = stream(const(400), 1.5, 30, seed=5)
    a = a.copy()
    a[1200:1210] = np.nan  # a fault 10 s into a 30 s call: later updates are "ok" again
    bcr = BCR(block_model)
    est = bcr.update(t, p, a, v)
    assert est.status == "sensor_fault" and "non-finite accel" in est.reason
    assert bcr.last.ok  # the newest estimate, which the next call starts from
    nxt = bcr.update(t[-1] + np.arange(1, EVERY + 1) / 120, p[-1] + 1.5 * np.arange(1, EVERY + 1)
                     / 120, a[:EVERY], v[:EVERY])  # fmt: skip
    assert nxt.ok


def test_the_gravest_fault_is_a_sensor_fault_else_the_least_plausible_block():
    from control.estimate import graver_fault

    def est(status, p=np.nan, tag=""):
        return Estimate(0.0, 0.0, status, tag, plausibility_p=p)

    ok, filling = est("ok"), est("filling")
    low, high = est("implausible", 1e-9, "low"), est("implausible", 1e-7, "high")
    first, second = est("sensor_fault", tag="first"), est("sensor_fault", tag="second")
    assert graver_fault(None, ok) is None and graver_fault(high, filling) is high
    assert graver_fault(None, high) is high and graver_fault(high, low) is low
    assert graver_fault(low, high) is low and graver_fault(low, first) is first
    assert graver_fault(first, low) is first and graver_fault(first, second) is first


SHAPE_FAULTS = ("scale", "quantize", "clip", "stuck")
"""Faults that change the signal's shape but not its time stamps or finiteness: the block checks
see them from MIN_SEGMENT samples of a block on. A block that holds fewer (a short fault, or a
longer fault's first samples at the end of the block, before the next update's block holds
enough) is below what they see, and the fault removes at most a quarter of its power
(`docs/closed-loop.md`, "Guards")."""
STREAM_START = 24
"""A shape fault from the stream's first STREAM_START samples (0.2 s) has too few healthy samples
before it in the first block for the level checks to tell a drop from a level that rises, which
they do not count (a robot driving onto rough ground): it can go unflagged (docs)."""
FAULT_SIZES = {  # fault-like magnitudes: a mild miscalibration (a gain of 0.7, say) looks like
    # another roughness to any check of the signal alone, and is not a sensor fault here
    "spike": (1.0, 60.0),  # one spike every 1 to 60 samples
    "noise": (5.0, 1e4),  # m/s^2, above the signal's own ~6 m/s^2
    # gains below 0.05, the level check's 400x in variance, by a margin for the scatter of a
    # segment's variance: at 0.05 itself a fault is flagged about half the time
    "scale": (1e-4, 0.035),
    "quantize": (2.0, 1e3),  # m/s^2 steps
    "clip": (1e-3, 2.0),  # m/s^2
}


@settings(max_examples=40, deadline=None)
@given(
    kind=st.sampled_from(
        [
            "nan",
            "drop",
            "spike",
            "noise",
            "scale",
            "quantize",
            "stuck",
            "clip",
            "time_nan",
            "position_nan",
        ]
    ),  # fmt: skip
    start=st.floats(0.0, 20.0),
    duration=st.floats(0.01, 8.0),
    size=st.floats(0.0, 1.0),
)
# a fault's last 31 samples open the first whole block, its first sample never in a block: the
# exemption counted 32 when it counted by time (data_time - block_s rounds below t[0])
@example(kind="scale", start=0.0078125, duration=0.25, size=1.0)
# a gain of 0.035 with 29 healthy samples before it in its first block: too few for the level
# check's drops (32), read [200, 281] with the truth at 400 (the short level check, session 71)
@example(kind="scale", start=0.25, duration=0.25, size=1.0)
def test_no_fault_crashes_the_bcr_or_makes_it_confidently_too_low(kind, start, duration, size):
    if kind in SHAPE_FAULTS:  # shorter ones are below what the block checks see (docs)
        duration = max(duration, MIN_SEGMENT / 120.0)
    t, p, a, v = stream(const(400), 1.5, 25, seed=7)
    lo, hi = FAULT_SIZES.get(kind, (1.0, 1.0))
    magnitude = float(np.exp(np.log(lo) + size * (np.log(hi) - np.log(lo))))
    fault = SensorFault(start, duration, kind, magnitude)
    bcr = BCR(FakeBlockModel())
    faulted = FaultInjector([fault], np.random.default_rng(1))(t, p, a, v)
    ests = feed(bcr, *faulted, chunk=bcr.settings.samples_per_update)  # every estimate
    assert all(e.status in STATUSES for e in ests)
    in_fault = (t >= start) & (t < start + duration)
    first = int(np.searchsorted(t, start))  # the fault's first sample
    block = bcr.settings.feature.block_samples
    for e in ests:  # an accepted estimate is never far below the truth (a faster robot)
        if not e.ok:
            continue
        newest = int(np.searchsorted(t, e.data_time, side="right"))  # by index: no rounding
        seen = np.count_nonzero(in_fault[max(newest - block, 0) : newest])
        if kind in SHAPE_FAULTS and 0 < seen < MIN_SEGMENT:
            continue  # the newest block holds too few of the fault's samples (SHAPE_FAULTS)
        if kind in SHAPE_FAULTS and seen and first < STREAM_START:
            continue  # from the stream's first samples (STREAM_START)
        assert e.interval[1] + (e.interval[1] - e.interval[0]) >= 400


def test_standing_still_keeps_the_estimate_until_it_turns_stale(block_model):
    bcr = BCR(block_model, max_age_s=3.0)
    t, p, a, v = stream(const(400), 1.5, 10, seed=1)
    assert feed(bcr, t, p, a, v)[-1].ok
    n = 125 * 5
    ts = t[-1] + np.arange(1, n + 1) / 120
    ests = feed(bcr, ts, np.full(n, p[-1]), 0.01 * np.random.default_rng(2).standard_normal(n),
                np.zeros(n))  # fmt: skip
    assert ests[1].ok and "no new information" in ests[1].reason  # ests[0] ends a moving block
    assert ests[1].gd_mean == pytest.approx(ests[0].gd_mean, rel=0.05)
    assert ests[-1].status == "stale" and "s old" in ests[-1].reason


def test_a_silent_sensor_is_a_fault_when_the_caller_gives_its_clock(block_model):
    bcr = BCR(block_model)
    t, p, a, v = stream(const(400), 1.5, 10, seed=1)
    assert feed(bcr, t, p, a, v)[-1].ok
    empty = np.empty(0)
    assert bcr.update(empty, empty, empty, empty, now=t[-1] + 0.4).ok  # within max_silence_s
    est = bcr.update(empty, empty, empty, empty, now=t[-1] + 0.8)
    assert est.status == "sensor_fault" and "no samples for 0.80 s" in est.reason
    assert est.time == pytest.approx(t[-1] + 0.8)
    assert bcr.update(empty, empty, empty, empty).status == "sensor_fault"  # still silent
    t2, p2, a2, v2 = stream(const(400), 1.5, 20, seed=1)
    later = t2 > t[-1] + 1.0  # samples again (after a gap: the stream restarts)
    ests = feed(bcr, t2[later], p2[later], a2[later], v2[later])
    assert ests[-1].ok
    with pytest.raises(ControlError, match="now must be a finite time"):
        bcr.update(empty, empty, empty, empty, now=np.nan)
    quiet = BCR(block_model)  # without the clock a silent sensor keeps the last estimate
    assert feed(quiet, t, p, a, v)[-1].ok
    assert quiet.update(empty, empty, empty, empty).ok


@settings(max_examples=25, deadline=None)
@given(missing=st.integers(1, EVERY - 1))
def test_with_an_exact_clock_any_missing_trailing_sample_is_a_fault(missing):
    """The closed loop's setting (max_silence_s below one sample period): samples missing at
    the end of an update are a fault at that update, however few."""
    bcr = BCR(FakeBlockModel(), max_silence_s=0.5 / 120)
    t, p, a, v = stream(const(400), 1.5, 10, seed=1)
    n = EVERY * 16
    for k in range(0, n, EVERY):  # on time, every sample: estimates (after the first block)
        est = bcr.update(t[k : k + EVERY], p[k : k + EVERY], a[k : k + EVERY], v[k : k + EVERY],
                         now=t[k + EVERY - 1])  # fmt: skip
        assert est.ok or k + EVERY < 125
    keep = slice(n, n + EVERY - missing)
    est = bcr.update(t[keep], p[keep], a[keep], v[keep], now=t[n + EVERY - 1])
    assert est.status == "sensor_fault" and "no samples for" in est.reason


def test_speed_outside_the_domain_before_any_estimate(block_model):
    ests = feed(BCR(block_model), *stream(const(400), 0.3, 3, seed=1))
    assert ests[-1].status == "out_of_domain" and "0.3 m/s" in ests[-1].reason


def test_changepoint_settings_are_checked(block_model):
    with pytest.raises(ControlError, match="needs the log_band_power feature"):
        BCR(block_model, method="changepoint", feature=PAPER_WINDOW)
    for every in (126, 15):  # more than a block; more than 8 phases
        with pytest.raises(ControlError, match=r"update_every must lie in .* = \[15.625, 125\]"):
            BCR(block_model, update_every=every)
    for every in (0, True, 42.0):
        with pytest.raises(ControlError, match="update_every must be an integer >= 1"):
            BCR(block_model, update_every=every)
    assert BCRSettings(update_every=63).phases == 2 and BCRSettings(update_every=16).phases == 8
    assert BCRSettings().phases == 3 and BCRSettings().samples_per_update == 42  # the default
    with pytest.raises(ControlError, match="needs an ObservationModel"):
        BCR(FakeCalibrator())
    bcr = BCR(block_model)
    with pytest.raises(ControlError, match="accel must have t's length 3, got 2"):
        bcr.update(np.arange(3.0), np.arange(3.0), np.arange(2.0), np.ones(3))
    with pytest.raises(ControlError, match=r"t must be 1-D, got shape \(2, 2\)"):
        bcr.update(np.zeros((2, 2)), np.zeros(4), np.zeros(4), np.ones(4))
    for junk in (["a", "b", "c"], np.ones(3, complex), np.array([b"x"] * 3)):
        with pytest.raises(ControlError, match="speed must hold real numbers"):
            bcr.update(np.arange(3.0), np.arange(3.0), np.arange(3.0), junk)
    with pytest.raises(ControlError, match="position must hold real numbers"):
        bcr.update(np.arange(3.0), np.array([1.0, "x", 2.0], dtype=object), np.ones(3), np.ones(3))


def test_settings_of_the_wrong_type_are_named(block_model):
    for field in ("feature", "changepoint", "tracker", "sensor"):
        with pytest.raises(ControlError, match=f"BCRSettings.{field} must be a"):
            BCRSettings(**{field: None})
    with pytest.raises(ControlError, match="BCRSettings.max_age_s must be a real number"):
        BCRSettings(max_age_s="5")
    with pytest.raises(ControlError, match="now must be a finite time"):
        BCR(block_model).update(np.arange(3.0), np.arange(3.0), np.ones(3), np.ones(3), now="x")


def test_a_feature_other_than_the_models_emulators_is_refused():
    model = FakeBlockModel()
    model.emulator.metadata = {"feature": FeatureSpec().to_dict()}
    BCR(model)  # the same feature
    for other in (FeatureSpec(block_samples=250), FeatureSpec(taper_nw=3.0, n_tapers=5)):
        with pytest.raises(EmulatorMismatchError, match="the BCR's feature differs"):
            BCR(model, feature=other)


@pytest.mark.parametrize("bad", [np.inf, -np.inf, np.nan])
def test_a_non_finite_time_stamp_is_a_sensor_fault_not_an_error(block_model, bad):
    t, p, a, v = stream(const(400), 1.5, 6, seed=1)
    t = t.copy()
    t[300] = bad
    ests = feed(BCR(block_model), t, p, a, v, chunk=42)
    faults = [e for e in ests if e.status == "sensor_fault"]
    assert faults and "non-finite t" in faults[0].reason
    assert ests[-1].ok


def test_backwards_and_repeated_time_stamps_are_faults(block_model):
    t, p, a, v = stream(const(400), 1.5, 10, seed=1)
    t = t.copy()
    t[300] = t[299]  # repeated
    t[400] = t[398]  # backwards
    ests = feed(BCR(block_model), t, p, a, v)
    assert [e.status for e in ests[2:4]] == ["sensor_fault", "sensor_fault"]
    assert "repeated or backwards" in ests[2].reason
    assert ests[-1].ok


# --- the window methods (the paper's and the earlier filters) ------------------------------------


def test_window_methods_need_a_full_window(fake_calibrator):
    bcr = BCR(fake_calibrator, method="filter", **WINDOW)
    ests = feed(bcr, *stream(const(400), 1.5, 12.5, seed=1))
    assert [e.status for e in ests[:7]] == ["filling"] * 7
    assert all(np.isnan(e.gd_mean) and "buffer holds" in e.reason for e in ests[:7])
    assert ests[7].ok and np.isfinite(ests[7].gd_mean) and ests[7].latency_s > 0
    assert fake_calibrator.calls == len(ests) - 7


def test_filters_beat_one_window_on_steady_ground():
    errors = {"filter": [], "tempered": [], "window": []}
    for seed in range(4):
        t, p, a, v = stream(const(420), 1.2, 120, seed=seed)
        for method in errors:
            ests = feed(BCR(FakeCalibrator(), method=method, **WINDOW), t, p, a, v)
            errors[method] += [e.gd_mean - 420 for e in ests if e.ok]
    rmse = {k: np.sqrt(np.mean(np.square(e))) for k, e in errors.items()}
    assert rmse["filter"] < 0.7 * rmse["window"]
    assert rmse["tempered"] < 0.7 * rmse["window"]


def test_window_faults_restart_the_buffer(fake_calibrator):
    t, p, a, v = stream(const(400), 1.5, 40, seed=2)
    a = a.copy()
    a[2000:2010] = np.nan
    ests = feed(BCR(fake_calibrator, method="filter", **WINDOW), t, p, a, v)
    status = [e.status for e in ests]
    k = 2000 // 125
    assert status[k - 1] == "ok" and status[k] == "sensor_fault"
    assert set(status[k + 1 : k + 8]) == {"filling"}
    assert set(status[k + 9 :]) == {"ok"}


def test_window_interleaved_filters_and_settings(fake_calibrator):
    assert len(BCR(fake_calibrator, method="filter", **WINDOW).trackers) == 8
    assert len(BCR(fake_calibrator, method="filter", update_every=300, **WINDOW).trackers) == 4
    assert len(BCR(fake_calibrator, method="window", **WINDOW).trackers) == 1
    with pytest.raises(ControlError, match="method must be one of"):
        BCRSettings(method="kalman")
    with pytest.raises(ControlError, match="must not exceed the window"):
        BCRSettings(method="window", feature=PAPER_WINDOW, update_every=2000)


def test_the_speed_domain_edge_is_inside():
    cal = FakeCalibrator(v_range=(0.5, float(np.nextafter(2.0, 0.0))))  # 1.9999999999999998
    ests = feed(BCR(cal, method="window", **WINDOW), *stream(const(400), 2.0, 10, seed=1))
    assert ests[-1].ok and ests[-1].speed == 2.0
    ests = feed(BCR(cal, method="window", **WINDOW), *stream(const(400), 2.001, 10, seed=1))
    assert ests[-1].status == "out_of_domain"


def test_calibrator_errors_become_a_status():
    class Refusing(FakeCalibrator):
        def log_likelihood_grid(self, x_obs, y_obs):
            raise ValueError("x_obs outside the domain")

    ests = feed(BCR(Refusing(), method="window", **WINDOW), *stream(const(400), 1.5, 10, seed=1))
    assert ests[-1].status == "calibration_failed" and "outside" in ests[-1].reason


def test_an_old_window_estimate_turns_stale(fake_calibrator):
    with pytest.warns(ControlWarning, match="longer than max_age_s"):
        bcr = BCR(fake_calibrator, method="window", update_every=1000, max_age_s=1.0, **WINDOW)
    t, p, a, v = stream(const(400), 1.5, 13, seed=1)
    assert bcr.update(t[:1000], p[:1000], a[:1000], v[:1000]).ok
    late = bcr.update(t[1000:1500], p[1000:1500], a[1000:1500], v[1000:1500])
    assert late.status == "stale" and "s old" in late.reason and np.isnan(late.gd_mean)


def test_the_window_feature_of_the_paper(fake_calibrator):
    t, p, a, v = stream(const(400), 1.5, 9, seed=1)
    est = feed(BCR(fake_calibrator, method="window", **WINDOW), t, p, a, v)[-1]
    assert est.feature[0] == pytest.approx(np.log(np.var(a[:1000])))  # 1,080 samples fed
    assert est.feature[0] == pytest.approx(log_f(1.5, 400), abs=0.3)


def test_a_stuck_sensor_holds_its_last_good_value_across_batches():
    t = np.arange(240) / 120.0
    a = np.arange(240, dtype=float)
    inject = FaultInjector([SensorFault(0.5, 1.0, "stuck")], np.random.default_rng(0))
    read = np.concatenate(
        [inject(t[k : k + 42], t[k : k + 42], a[k : k + 42], np.ones(42)[: t[k : k + 42].size])[2]
         for k in range(0, 240, 42)]
    )  # fmt: skip
    stuck = (t >= 0.5) & (t < 1.5)
    assert np.all(read[stuck] == a[59]) and np.array_equal(read[~stuck], a[~stuck])
    # after a NaN fault it holds the last good value before the NaNs, not NaN
    faults = [SensorFault(0.4, 0.2, "nan"), SensorFault(0.6, 0.5, "stuck")]
    inject = FaultInjector(faults, np.random.default_rng(0))
    read = np.concatenate(
        [inject(t[k : k + 42], t[k : k + 42], a[k : k + 42], np.ones(42)[: t[k : k + 42].size])[2]
         for k in range(0, 240, 42)]
    )  # fmt: skip
    assert np.all(read[(t >= 0.6) & (t < 1.1)] == a[47])  # 47: the sample before t = 0.4


def test_the_fault_injector_names_what_it_cannot_inject():
    with pytest.raises(ControlError, match=r"faults\[0\] must be a control.SensorFault"):
        FaultInjector(["nan"], np.random.default_rng(0))
    with pytest.raises(ControlError, match="rng must be a numpy.Generator"):
        FaultInjector([SensorFault(0.5, 1.0, "noise", 3.0)], None)
    t, a = np.arange(120) / 120.0, np.zeros(120)
    spiked = FaultInjector([SensorFault(0.0, 1.0, "spike", 2.9)], np.random.default_rng(0))
    assert np.flatnonzero(spiked(t, t, a, np.ones(120))[2])[:3].tolist() == [0, 3, 6]  # not 2


def test_an_emulator_passed_as_the_model_is_named_with_the_way_to_build_one(emulator_a):
    """BCR(emulator) said only "needs an ObservationModel", as for None, without naming what it
    got or that BCR.from_emulator builds the model."""
    with pytest.raises(ControlError, match=r"needs an ObservationModel, got Emulator .*from_emul"):
        BCR(emulator_a)
    window = BCRSettings(method="window", feature=PAPER_WINDOW)
    with pytest.raises(ControlError, match=r"needs a gpmsa.Calibrator, got NoneType .*from_emul"):
        BCR(None, window)
