"""control under a caller's ``np.seterr(all="raise")`` (session 86): a sensor fault that starts
at t = 0 s (one ulp below it is a subnormal) is injected as it is in numpy's default state."""

import numpy as np

import control


def _faulted():
    faults = [control.SensorFault(0.0, 0.5, "nan"), control.SensorFault(0.25, 0.5, "stuck")]
    inject = control.FaultInjector(faults, np.random.default_rng(0))
    t = np.arange(120) / 120.0
    return inject(t, 1.25 * t, np.sin(t), np.full(t.size, 1.25))


def test_a_fault_from_time_zero_is_injected_alike_under_raise():
    default = _faulted()
    with np.errstate(all="raise"):
        raised = _faulted()
        assert np.geterr()["under"] == "raise"
    for a, b in zip(raised, default, strict=True):
        np.testing.assert_array_equal(a, b)
    assert np.isnan(default[2][0])


def _estimates(model, risk_speeds: list) -> list:
    from control_doubles import stream

    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 60, seed=1)
    bcr, simplex = control.BCR(model, update_every=125), control.Simplex(risk=0.1)
    out = []
    for k in range(0, t.size, 125):
        e = bcr.update(t[k : k + 125], p[k : k + 125], a[k : k + 125], v[k : k + 125])
        out.append((e.status, e.gd_mean, e.gd_sd, e.interval, e.prob_change))
        risk_speeds.append(simplex.command(e).speed)
    return out


def test_the_bcr_and_the_simplex_give_the_same_numbers_under_raise(block_model):
    # a sharp block likelihood: the posterior's far tails underflow (exp, products)
    speeds, raised_speeds = [], []
    default = _estimates(block_model, speeds)
    with np.errstate(all="raise"):
        raised = _estimates(block_model, raised_speeds)
        assert np.geterr()["under"] == "raise"  # BCR.update leaves the caller's state
    assert raised == default and raised_speeds == speeds
    assert sum(e[0] == "ok" for e in default) > 10
