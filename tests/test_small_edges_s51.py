"""Small edges: the posterior grid's GD axis follows its draws; a one-segment track needs no
blend; the GD fits leave out the Nyquist bin; Campaign.save writes through a symbolic link;
shared_theta's traces stay finite for a short chain (ball_drop's summary stays valid JSON for
one: tests/gpmsa/test_example_ball_drop.py checks it in its run of the example)."""

import os
from types import SimpleNamespace

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import roadgen  # noqa: E402
import vehicle  # noqa: E402
from control import ControlError  # noqa: E402
from control.plotting import plot_posterior_grid  # noqa: E402
from tests._examples import load_example  # noqa: E402


def _bars(fig) -> tuple[float, float, float, float]:
    """(left edge, right edge, bar width, area) of the first axes' histogram."""
    bars = fig.axes[0].patches
    width = bars[0].get_width()
    area = sum(b.get_height() for b in bars) * width
    return bars[0].get_x(), bars[-1].get_x() + bars[-1].get_width(), width, area


def test_posterior_grid_axis_holds_draws_of_another_gd_domain():
    # an emulator trained over GD [800, 1600]: the old fixed (200, 600) axis held none of them
    cells = [(1.0, gd, np.linspace(gd - 100.0, gd + 150.0, 200)) for gd in (1100.0, 1300.0)]
    left, right, width, area = _bars(plot_posterior_grid(cells))
    assert (left, right) == pytest.approx((1000.0, 1500.0), abs=1e-9)
    assert width == pytest.approx(12.5, rel=1e-12)
    assert area == pytest.approx(1.0, rel=1e-9)  # nothing clipped
    left, right, width, _ = _bars(plot_posterior_grid(cells, gd_range=(800, 1600)))
    assert (left, right, width) == pytest.approx((800.0, 1600.0, 20.0), abs=1e-9)


def test_posterior_grid_keeps_the_paper_axis_for_its_cells():
    rng = np.random.default_rng(0)
    cells = [
        (v, gd, np.clip(rng.normal(gd, 40.0, 500), 205.0, 590.0))
        for v in (0.75, 1.25, 1.75)
        for gd in (250, 300, 350, 400, 450, 500, 550)
    ]
    left, right, width, _ = _bars(plot_posterior_grid(cells))
    assert (left, right, width) == pytest.approx((200.0, 600.0, 10.0), abs=1e-9)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (
            {"cells": [(1.0, 300.0, np.arange(3.0)), (1.0, 400.0, np.array([1.0, np.nan]))]},
            r"^cells\[1\]: the draws must be a non-empty array of finite GD values and the "
            r"true GD a finite number, got 2 draws \(1 not finite\) and GD 400.0$",
        ),
        ({"cells": []}, r"^cells is empty"),
        (
            {"cells": [(1.0, 300.0, np.arange(3.0))], "gd_range": (600, 200)},
            r"^gd_range=\(600, 200\) must be two finite GD values lo < hi$",
        ),
    ],
)
def test_posterior_grid_refuses_what_it_cannot_draw(kwargs, match):
    with pytest.raises(ControlError, match=match):
        plot_posterior_grid(**kwargs)


def test_one_segment_track_shorter_than_the_blend_is_built():
    # one segment has no boundary: the default blend_m = 1 m does not apply to a 0.5 m track
    t = roadgen.track([(0.5, 300.0)], seed=1, lead_in_m=0.2)
    p = roadgen.iso8608_profile(0.5, 300.0, seed=1, lead_in_m=0.2)
    np.testing.assert_allclose(t.z, p.z, rtol=0, atol=1e-15)
    assert t.gd_at(0.3) == 300.0
    with pytest.raises(
        roadgen.RoadgenError,
        match=r"^lead_in_m=1 is out of range: allowed \[0, 0.5\] m \(the first segment, 0.5 m\);",
    ):
        roadgen.track([(0.5, 300.0)], seed=1)
    with pytest.raises(roadgen.RoadgenError, match=r"^blend_m=1 is out of range"):
        roadgen.track([(0.5, 300.0), (0.5, 400.0)], seed=1, lead_in_m=0.0)


def test_gd_fit_leaves_out_the_empty_nyquist_bin_of_an_even_record():
    # dx 0.5 m: Nyquist 1 cycles/m is in the default fit band; 302 heights (even) put a bin
    # there, which roadgen never fills (it counted as a zero: -0.7 %)
    road = roadgen.iso8608_profile(150.5, 300.0, seed=1, dx_m=0.5, lead_in_m=0.0)
    assert road.z.size % 2 == 0
    assert roadgen.estimate_gd(road) == pytest.approx(300.0, rel=1e-3)
    # dx 5 m: the harmonic nearest n0 = 0.1 cycles/m was the (empty) Nyquist bin: GD ~1e-26
    road = roadgen.iso8608_profile(1005.0, 300.0, seed=1, dx_m=5.0, lead_in_m=0.0)
    assert road.z.size % 2 == 0
    assert roadgen.estimate_gd(road, method="periodogram") == pytest.approx(300.0, rel=1e-9)
    two = SimpleNamespace(z=np.array([0.0, 1e-3]), dx_m=0.5)
    with pytest.raises(
        roadgen.RoadgenError,
        match=r"^the road holds 2 heights: its only PSD bin above n = 0 is the Nyquist frequency "
        r"1 cycles/m, which the GD and slope fits leave out; need >= 3 heights$",
    ):
        roadgen.estimate_gd(two)


def _campaign(v0: float) -> vehicle.Campaign:
    fs = np.array([40.0, 80.0])
    return vehicle.Campaign(
        v=np.array([v0, 1.6]), gd=np.array([250.0, 550.0]), seed=np.array([3, 4]),
        f_full=fs, f_window=fs, f_full_noisy=fs + 1, f_window_noisy=fs + 1,
        status=np.array(["ok", "ok"]), settings={},
    )  # fmt: skip


def test_campaign_save_writes_through_a_symbolic_link(tmp_path):
    (tmp_path / "real").mkdir()
    _campaign(0.7).save(tmp_path / "real" / "c.npz")
    link = tmp_path / "c.npz"
    link.symlink_to(os.path.join("real", "c.npz"))
    _campaign(0.9).save(link)
    assert link.is_symlink()  # the link stays, its target holds the new table
    assert vehicle.load_campaign(tmp_path / "real" / "c.npz").v[0] == 0.9
    dangling = tmp_path / "new.npz"
    dangling.symlink_to(os.path.join("real", "made.npz"))
    _campaign(0.8).save(dangling)
    assert (
        dangling.is_symlink() and vehicle.load_campaign(tmp_path / "real" / "made.npz").v[0] == 0.8
    )
    notes = tmp_path / "notes.txt"
    notes.write_text("field notes\n")
    (tmp_path / "to_notes.npz").symlink_to("notes.txt")
    with pytest.raises(vehicle.CampaignFileError, match=r"notes\.txt'.*not a campaign file"):
        _campaign(0.9).save(tmp_path / "to_notes.npz")
    assert notes.read_text() == "field notes\n"
    (tmp_path / "a.npz").symlink_to("b.npz")
    (tmp_path / "b.npz").symlink_to("a.npz")
    with pytest.raises(vehicle.CampaignFileError, match=r"a\.npz'.*Too many levels of symbolic"):
        _campaign(0.9).save(tmp_path / "a.npz")
    assert (tmp_path / "a.npz").is_symlink()


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_shared_theta_draws_a_chain_that_never_moved(tmp_path):
    summary = load_example("shared_theta").main(["--n-iter", "2", "--out", str(tmp_path)])
    # two sweeps: the shared E never moves, so its trace (standardised by sd 0) was NaN
    assert summary["posterior"]["shared (emulators fixed)"]["E"]["sd"] == 0.0
    assert (tmp_path / "traces.png").stat().st_size > 0
