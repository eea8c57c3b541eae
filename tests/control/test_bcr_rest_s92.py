"""Mutation testing of control/bcr.py (session 92, the rest of the every-4th-site sample):
exact cases for the mutants that survived, on the doubles of control_doubles.py with scripted
level scores (each test's numbers are worked by hand in its comments)."""

from types import SimpleNamespace

import numpy as np
import pytest
from control_doubles import FakeBlockModel, FakeCalibrator, stream

from control import BCR, PAPER_WINDOW, BCRSettings
from control.errors import ControlError


class _Scores(FakeBlockModel):
    """FakeBlockModel whose level scores are ``scores``, one a call in turn (the last one
    repeated), and whose scatter is a Student t law of ``dof`` degrees of freedom."""

    def __init__(self, scores, dof=np.inf):
        super().__init__()
        self.scores, self.n_scores = list(scores), 0
        self.scatter = SimpleNamespace(dof=dof)

    def level_score(self, y, v, direction):
        self.n_scores += 1
        return float(self.scores[min(self.n_scores, len(self.scores)) - 1])


def _blocks(bcr: BCR, n: int, gd: float = 400.0) -> list:
    """n updates of one 125-sample block each (with update_every=125: one phase), a drive at
    1.5 m/s over GD ``gd``."""
    t, p, a, v = stream(lambda s: np.full_like(s, gd), 1.5, n * 125 / 120, seed=3)
    return [bcr.update(t[k : k + 125], p[k : k + 125], a[k : k + 125], v[k : k + 125])
            for k in range(0, t.size, 125)]  # fmt: skip


def test_the_frozen_odometry_check_reads_the_level_score_in_the_scatters_sds():
    # a Student t scatter of 3 dof: the scores' sd is sqrt(3 / (3 - 2)) = sqrt(3), so a block
    # that scores -6 reads -6 / sqrt(3) = -3.46 sd, above the limit ndtri(1e-6) = -4.75: the
    # accelerometer reads as driving while the speeds read standing (-6 * sqrt(3) = -10.4
    # would read as a robot at rest)
    model = _Scores([-6.0], dof=3.0)
    bcr = BCR(model, update_every=125)
    assert bcr._level_sd == pytest.approx(np.sqrt(3.0), rel=1e-15)
    n = 125
    t = np.arange(1, n + 1) / 120.0
    acc = np.random.default_rng(4).standard_normal(n)
    est = bcr.update(t, np.zeros(n), acc, np.zeros(n))
    assert model.n_scores == 1
    assert est.status == "out_of_domain"
    assert "level score -3.46 sd" in est.reason and "a stop's ringing" in est.reason


def test_without_quiet_scan_only_the_whole_memory_is_tested():
    # scores 0, 0, 0, -5 (one phase): their sum reads -5 / sqrt(4) = -2.5 sd, p = 0.0062, not
    # below plausibility_p = 1e-6; the newest block alone (-5 sd, p = 2.9e-7) is tested only
    # with quiet_scan
    ests = _blocks(BCR(_Scores([0.0, 0.0, 0.0, -5.0]), update_every=125, quiet_scan=False), 4)
    assert [e.status for e in ests] == ["ok"] * 4
    scan = _blocks(BCR(_Scores([0.0, 0.0, 0.0, -5.0]), update_every=125), 4)
    assert [e.status for e in scan] == ["ok"] * 3 + ["implausible"]
    assert "the last 1 block(s)" in scan[-1].reason and "level score -5 sd" in scan[-1].reason
    assert "quieter than any GD in [200, 600] explains at 1.5 m/s" in scan[-1].reason


def test_a_memory_already_implausible_is_reported_whole_not_scanned():
    # scores 0, 0, 0, -12: the sum reads -12 / 2 = -6 sd (p = 1e-9 < 1e-6), reported as the
    # last 4 blocks; the scan (newest block alone: -12 sd) runs only where the sum passes
    ests = _blocks(BCR(_Scores([0.0, 0.0, 0.0, -12.0]), update_every=125), 4)
    assert [e.status for e in ests] == ["ok"] * 3 + ["implausible"]
    assert "the last 4 block(s)" in ests[-1].reason and "level score -6 sd" in ests[-1].reason


def test_a_hold_ends_once_every_phase_read_a_loud_enough_block():
    # one phase; scores -5 (p = 2.9e-7: implausible, the hold begins), 0 (read since the flag:
    # 0 sd, p = 0.5 >= release_p = 0.05: the hold ends), -3: the quiet check's sum
    # (-5 + 0 - 3) / sqrt(3) = -4.62 sd (p = 1.9e-6) passes, and no hold is on any more (the
    # blocks since the flag would read (0 - 3) / sqrt(2) = -2.12 sd, p = 0.017 < 0.05)
    bcr = BCR(_Scores([-5.0, 0.0, -3.0]), update_every=125)
    ests = _blocks(bcr, 3)
    assert [e.status for e in ests] == ["implausible", "ok", "ok"]
    assert bcr._held_by is None


def test_a_hold_stays_on_while_a_phase_has_read_no_block_since():
    # three phases (update_every 42 of 125): scores -5 (phase 2: implausible, the hold begins),
    # 0 (phase 0: 0 sd since the flag, p = 0.5, but phases 1 and 2 read nothing since: the hold
    # stays), -2.5 (phase 1: its quiet check passes at -2.5 sd, p = 0.0062, but it is held,
    # p = 0.0062 < release_p = 0.05)
    bcr = BCR(_Scores([-5.0, 0.0, -2.5]))
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 210 / 120, seed=3)
    ests = [bcr.update(t[k : k + 42], p[k : k + 42], a[k : k + 42], v[k : k + 42])
            for k in range(0, t.size, 42)]  # fmt: skip
    assert [e.status for e in ests] == ["filling", "filling", "implausible", "ok", "implausible"]
    assert ests[-1].reason.startswith("held since the implausible estimate at 1.05 s")
    assert "level score -2.5 sd" in ests[-1].reason


def test_a_window_at_exactly_plausibility_p_is_plausible():
    # y 2 predictive sds from every GD's mean: z^2 = 4, p = chi2.sf(4, 1); at p equal to
    # plausibility_p the window is plausible, as a block is (implausible below it only)
    from scipy.stats import chi2

    limit = float(chi2.sf(4.0, 1))
    model = FakeCalibrator()
    model.emulator.predict = lambda v, gd: (np.zeros((gd.size, 1)), np.ones((gd.size, 1)))
    bcr = BCR(model, method="window", feature=PAPER_WINDOW, plausibility_p=limit)
    assert bcr._window_implausible(1.5, 2.0) == ("", limit)
    below = BCR(model, method="window", feature=PAPER_WINDOW, plausibility_p=np.nextafter(limit, 1))
    why, p = below._window_implausible(1.5, 2.0)
    assert p == limit and "2 predictive sds from the nearest" in why


class _Implausible(FakeBlockModel):
    """FakeBlockModel whose every block is implausible (p = 0) and whose band powers read as
    an acceleration ``gain`` times the smoothest or roughest ground's (`band_gain`)."""

    def __init__(self, gain):
        super().__init__()
        self.gain = gain

    def plausibility(self, y, v):
        return 100.0, 0.0

    def band_gain(self, y, v, bands):
        self.bands = bands
        return self.gain


@pytest.mark.parametrize(
    ("gain", "clause"),
    [
        # exactly 1 / UNIT_HINT_GAIN (3): beyond the window (1/3, 3), so the gain is named
        (1 / 3.0, "; its band powers read as the smoothest ground's acceleration times 0.33"),
        # exactly twice the cm/s^2 slip's 100: the gain, but no slip (within a factor 2 only)
        (200.0, "; its band powers read as the roughest ground's acceleration times 2e+02"),
    ],
)
def test_the_gain_hint_at_its_edges(gain, clause):
    model = _Implausible(gain)
    est = _blocks(BCR(model, update_every=125), 1)[0]
    assert model.bands == slice(0, 8)  # the default feature's 8 band powers, then 2 quantiles
    assert est.status == "implausible"
    assert est.reason.endswith(clause)


def test_a_zero_dimensional_array_is_one_sample_as_a_list_of_one_is():
    # np.array(x) (0-d float64) takes the general path, which makes it 1-D: one sample
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 1 / 120, seed=3)
    zero_d, listed = BCR(FakeBlockModel()), BCR(FakeBlockModel())
    est = zero_d.update(*(np.array(x[0]) for x in (t, p, a, v)))
    ref = listed.update(*([x[0]] for x in (t, p, a, v)))
    assert zero_d._acc.shape == (1,) and (est.status, est.reason) == (ref.status, ref.reason)


def test_an_update_that_raises_leaves_the_quiet_checks_memory_as_it_was():
    # one phase; scores 0 and -1, then NaN: the third update raises, and the BCR is rolled back
    # to its state before that update, the quiet check's two scores included
    bcr = BCR(_Scores([0.0, -1.0, np.nan]), update_every=125)
    assert [e.status for e in _blocks(bcr, 2)] == ["ok", "ok"]
    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 375 / 120, seed=3)
    with pytest.raises(ControlError, match="level_score"):
        bcr.update(t[250:], p[250:], a[250:], v[250:])
    assert list(bcr._phases[0].levels) == [0.0, -1.0]


def test_the_scan_names_the_fewest_newest_blocks_at_a_tie():
    # scores 2, -2, -2, -2, -6 (one phase): the whole memory reads -10 / sqrt(5) = -4.47 sd
    # (p = 3.9e-6, passes); the newest block alone and the newest 4 both read -6 sd (-6 / 1,
    # -12 / 2), below the newest 2 and 3 (-5.66, -5.77): the fewest blocks, 1, are named
    ests = _blocks(BCR(_Scores([2.0, -2.0, -2.0, -2.0, -6.0]), update_every=125), 5)
    assert [e.status for e in ests] == ["ok"] * 4 + ["implausible"]
    assert "the last 1 block(s)" in ests[-1].reason and "level score -6 sd" in ests[-1].reason


def test_the_hold_reads_its_blocks_in_the_scatters_sds():
    # a Student t scatter of 3 dof (scores' sd sqrt(3)), one phase: -8.7 reads -5.02 sd
    # (p = 2.5e-7: implausible, the hold begins); -2.5: the memory reads -11.2 / (sqrt(2)
    # sqrt(3)) = -4.57 sd (p = 2.4e-6, passes), and the block since the flag -2.5 / sqrt(3) =
    # -1.44 sd (p = 0.075 >= release_p = 0.05): the hold ends (-2.5 sqrt(3) = -4.33 sd would hold)
    bcr = BCR(_Scores([-8.7, -2.5], dof=3.0), update_every=125)
    assert [e.status for e in _blocks(bcr, 2)] == ["implausible", "ok"]
    assert bcr._held_by is None


def test_release_p_zero_begins_no_hold():
    # release_p = 0 switches the hold off: after an implausible block (-5 sd), a block at
    # 2.5 m/s (beyond the model's 2 m/s) carries the estimate, with no "held since" reason
    bcr = BCR(_Scores([-5.0]), update_every=125, release_p=0.0)
    assert _blocks(bcr, 1)[0].status == "implausible"
    assert bcr._held_by is None
    t = (126 + np.arange(125)) / 120
    acc = np.random.default_rng(5).standard_normal(125)
    est = bcr.update(t, 125 * 1.5 / 120 + 2.5 * (t - t[0]), acc, np.full(125, 2.5))
    assert est.status == "ok"
    assert est.reason.startswith("no new information: speed 2.5 m/s outside")


def test_quiet_blocks_may_be_its_largest_value():
    from control.bcr import MAX_QUIET_BLOCKS

    assert BCRSettings(quiet_blocks=MAX_QUIET_BLOCKS).quiet_blocks == MAX_QUIET_BLOCKS == 1024
    with pytest.raises(ControlError, match="quiet_blocks must be an integer in"):
        BCRSettings(quiet_blocks=MAX_QUIET_BLOCKS + 1)
