"""The profile/PSD figure and the example script that repeats the paper's check."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

import roadgen  # noqa: E402
from tests._examples import load_example  # noqa: E402


def test_plot_profile_psd_shows_profile_psd_and_prescribed_lines(tmp_path):
    road = roadgen.track([(10, 300), (10, 500)], seed=0)
    fig = roadgen.plot_profile_psd(road, title="t")
    assert isinstance(fig, Figure)
    ax_z, ax_p = fig.axes
    labels = [line.get_label() for line in ax_p.get_lines()]
    assert "prescribed GD 300" in labels and "prescribed GD 500" in labels
    assert ax_p.get_xscale() == "log" and ax_p.get_yscale() == "log"
    assert ax_z.get_lines()[0].get_xdata().size == road.x.size
    fig.savefig(tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 10_000


def test_the_periodogram_stays_visible_on_its_prescribed_line(tmp_path):
    """With deterministic amplitudes the periodogram equals the line: the line is drawn
    underneath, wide and translucent; the periodogram on top, with a marker per ordinate."""
    road = roadgen.iso8608_profile(60.0, 450.0, seed=0)
    fig = roadgen.plot_profile_psd(road)
    _, ax_p = fig.axes
    lines = {line.get_label(): line for line in ax_p.get_lines()}
    psd, line = lines["periodogram of z"], lines["prescribed GD 450"]
    assert psd.get_zorder() > line.get_zorder()
    assert line.get_alpha() is not None and line.get_alpha() < 0.5
    assert line.get_linewidth() > 3 * psd.get_linewidth()
    assert psd.get_marker() not in (None, "None", "")
    assert psd.get_color() != line.get_color()
    np.testing.assert_allclose(psd.get_ydata(), line.get_ydata(), rtol=1e-9)  # they coincide
    legend = [t.get_text() for t in ax_p.get_legend().get_texts()]
    assert "periodogram of z" in legend and "prescribed GD 450" in legend
    fig.savefig(tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 10_000


def test_example_prints_the_check_and_saves_figures(tmp_path, capsys):
    module = load_example("roadgen_psd_check")
    module.main(["--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert "periodogram at 0.1 cycles/m gives 450.0" in out
    assert (tmp_path / "roadgen_psd_gd450.png").exists()
    assert (tmp_path / "roadgen_track.png").exists()


def test_example_saves_its_figures_before_a_closed_pipe_stops_it(tmp_path, monkeypatch):
    """`python examples/roadgen_psd_check.py | head` (with PYTHONUNBUFFERED, each print is
    written at once) ends the script at its first print after the reader went away: the figures
    come first."""
    module = load_example("roadgen_psd_check")
    saved = []

    def closed_pipe(*args, **kwargs):
        raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(module, "print", closed_pipe, raising=False)
    monkeypatch.setattr(roadgen, "plot_profile_psd", lambda road, title: title)  # fast
    monkeypatch.setattr(module, "save_figure", lambda fig, path: saved.append(path.name))
    with pytest.raises(BrokenPipeError):
        module.main(["--out", str(tmp_path)])
    assert saved == ["roadgen_psd_gd450.png", "roadgen_track.png"]


def test_a_flat_road_has_no_psd_to_draw():
    x = np.arange(0.0, 30.0, 0.006)
    flat = roadgen.Road(x=x, z=np.full_like(x, 0.01), dx_m=0.006)
    with pytest.raises(roadgen.RoadgenError, match="road is flat: its periodogram is zero"):
        roadgen.plot_profile_psd(flat)


def _recovered(fig: Figure) -> float:
    """The GD in the figure's "recovered GD ..." legend label."""
    labels = [line.get_label() for line in fig.axes[1].get_lines()]
    return float(next(lb for lb in labels if lb.startswith("recovered GD")).split()[-1])


def test_the_fit_band_follows_a_coarse_grid_and_the_profiles_band():
    coarse = roadgen.iso8608_profile(150.0, 450.0, dx_m=1.0, seed=0)  # Nyquist 0.5 cycles/m
    assert _recovered(roadgen.plot_profile_psd(coarse)) == pytest.approx(450.0, rel=0.01)
    too_coarse = roadgen.iso8608_profile(400.0, 450.0, dx_m=10.0, seed=0)
    with pytest.raises(roadgen.RoadgenError, match=r"dx_m=10 m \(Nyquist frequency 0.05 "
                       r"cycles/m\) is too coarse for the GD fit band FIT_BAND"):  # fmt: skip
        roadgen.plot_profile_psd(too_coarse)
    high = roadgen.iso8608_profile(60.0, 450.0, seed=0, band=(2.0, 10.0))
    with pytest.raises(roadgen.RoadgenError, match=r"settings.band=\(2, 10\)"):
        roadgen.plot_profile_psd(high)  # the default band holds none of its content
    fig = roadgen.plot_profile_psd(high, band=(2.0, 10.0))
    assert _recovered(fig) == pytest.approx(450.0, rel=0.01)
