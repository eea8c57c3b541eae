"""Mutation testing of control/bcr.py (session 92, six survivors of the sample): exact cases on
the doubles of control_doubles.py (each test's numbers are worked by hand in its comments)."""

import copy
from types import SimpleNamespace

import numpy as np
import pytest
from control_doubles import FakeBlockModel, bcr_of, stream

from control import BCR
from control.feature import FeatureSpec


def test_the_edge_note_weighs_the_density_by_the_quadrature_weights():
    # trapezoid weights on GD 200, 300, ..., 600 (the end nodes hold half a step) and prior
    # masses 1/8, 1/4, 1/4, 1/4, 1/8; the posterior density (0.01, 1, 1, 1, 10) / 400 has masses
    # (0.00125, 0.25, 0.25, 0.25, 1.25): posterior-to-prior ratios (0.01, 1, 1, 1, 10), so the
    # top edge is favoured by 10 only, below EDGE_BAYES_FACTOR = 20 (density / weights would
    # read the half-weight end 4 times higher: a ratio of 40, "upper")
    bcr = bcr_of("changepoint")
    nodes = np.linspace(200.0, 600.0, 5)
    weights = np.array([50.0, 100.0, 100.0, 100.0, 50.0])
    marginal = SimpleNamespace(
        nodes=nodes, weights=weights, density=np.array([0.01, 1.0, 1.0, 1.0, 10.0]) / 400.0
    )
    post = SimpleNamespace(grids={"GD": marginal})
    prior = weights / weights.sum()
    assert bcr._edge_note(post, prior) == ("", "")
    marginal.density = np.array([0.01, 1.0, 1.0, 1.0, 21.0]) / 400.0  # a ratio of 21 > 20
    edge, note = bcr._edge_note(post, prior)
    assert edge == "upper" and note


def test_before_any_sample_the_placeholder_reads_time_and_position_zero():
    bcr = bcr_of("changepoint")
    assert (bcr.last.time, bcr.last.position, bcr.last.status) == (0.0, 0.0, "filling")
    empty = np.zeros(0)
    est = bcr.update(empty, empty, empty, empty)
    assert (est.time, est.position, est.status) == (0.0, 0.0, "filling")
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 1.0, seed=3)
    bcr.update(t, p, a, v)
    bcr.reset()
    assert (bcr.last.time, bcr.last.position, bcr.last.reason) == (0.0, 0.0, "no samples yet")


def test_an_earlier_updates_fault_is_not_named_with_the_silence_of_a_later_call():
    # a block of zeros is a sensor fault (a stuck sensor); a later call that completes no
    # update and comes 10 s after its newest sample (max_silence_s = 0.5) names the silence
    # alone: the fault is not this call's ("fresh" only where this call updated)
    bcr = BCR(FakeBlockModel(), update_every=125)
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 250 / 120, seed=3)
    first = bcr.update(t[:125], p[:125], np.zeros(125), v[:125])
    assert first.status == "sensor_fault" and first.reason
    silent = bcr.update(t[125:130], p[125:130], a[125:130], v[125:130], now=t[129] + 10.0)
    assert silent.status == "sensor_fault"
    assert silent.reason.startswith("no samples for 10.00 s (max_silence_s = ")
    # the same fault in the call that gives it is named first
    bcr = BCR(FakeBlockModel(), update_every=125)
    late = bcr.update(t[:125], p[:125], np.zeros(125), v[:125], now=t[124] + 10.0)
    assert late.reason.startswith(f"{first.reason}; no samples for 10.00 s")


def test_frozen_odometry_settles_on_the_blocks_first_sample_time():
    # 128 Hz (exact stamps), updates of 85 samples, 125-sample blocks; the odometry freezes
    # after 4 s. The standing blocks start 255 / 128 = 1.9922 s after the first (below
    # STANDING_SETTLE_S = 2: still a stop's ringing; their second sample is 2 s after it)
    # and then 2.656 s after it (the first fault)
    spec = FeatureSpec(rate_hz=128.0)
    bcr = BCR(FakeBlockModel(spec), feature=spec, update_every=85)
    _, p, a, v = stream(lambda s: np.full_like(s, 300.0), 1.5, 9.0, rate_hz=128.0, seed=4)
    t = np.arange(1, a.size + 1) / 128.0
    frozen = t > 4.0
    p, v = p.copy(), v.copy()
    p[frozen], v[frozen] = p[frozen][0], 0.0
    statuses = []
    for k in range(0, t.size - 84, 85):
        est = bcr.update(t[k : k + 85], p[k : k + 85], a[k : k + 85], v[k : k + 85])
        if est.time > 5.0:
            statuses.append(est.status)
    assert statuses == ["out_of_domain"] * 4 + ["sensor_fault"] * 2


def test_the_window_methods_check_a_full_windows_odometry():
    # positions that advance at 3 m/s while the speeds read 1.5: the full window (1,000
    # samples, the eighth update of 125) fails the timing checks, which run on a full window
    for kind in ("window", "filter"):
        bcr = bcr_of(kind)
        t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 1000 / 120, seed=3)
        p = 2.0 * p
        ests = [bcr.update(t[k : k + 125], p[k : k + 125], a[k : k + 125], v[k : k + 125])
                for k in range(0, t.size, 125)]  # fmt: skip
        assert [e.status for e in ests] == ["filling"] * 7 + ["sensor_fault"]
        assert ests[-1].reason.startswith("odometry disagrees with the speeds: the position moved")


def test_the_first_update_after_resume_predicts_no_distance():
    # resume(0.0): the trackers keep their posterior (predicted over 0 m, no change); the
    # first update of the new stream has no position before it on the tracker's chain, so it
    # moves the tracker 0 m too: its posterior is the kept one times the window's likelihood
    bcr = bcr_of("filter")
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 2000 / 120, seed=3)
    for k in range(0, 1000, 125):
        bcr.update(t[k : k + 125], p[k : k + 125], a[k : k + 125], v[k : k + 125])
    bcr.resume(0.0)
    kept = copy.deepcopy(bcr.trackers)
    for k in range(1000, 2000, 125):
        est = bcr.update(t[k : k + 125], p[k : k + 125], a[k : k + 125], v[k : k + 125])
    assert est.status == "ok"
    tracker = kept[7 % len(kept)]  # the eighth update of the new stream (0-based: 7)
    grid, loglik = bcr.model.log_likelihood_grid([[est.speed]], [[est.feature[0]]])
    tracker.update(np.ravel(grid), np.ravel(loglik))
    post = tracker.posterior("GD")  # (a 0 m predict renormalises: equal to rounding)
    assert est.gd_mean == pytest.approx(post.mean("GD"), rel=1e-13)
    assert est.gd_sd == pytest.approx(post.sd("GD"), rel=1e-12)
