"""The profile/PSD figure and the example script that repeats the paper's check."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
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
