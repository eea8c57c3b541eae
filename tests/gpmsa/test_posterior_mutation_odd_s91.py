"""Posterior, GridMarginal and LevelMarginal: exact cases that mutation testing of the odd half
of gpmsa/calibration/posterior.py's sites (session 91) found free."""

import numpy as np
import pytest

from gpmsa import GPMSAError, Posterior
from gpmsa.calibration.posterior import GridMarginal, LevelMarginal, _float_hdi_probabilities


@pytest.mark.parametrize(
    ("nodes", "span"), [([-0.0, 1.0], "on [0, 1]"), ([-1.0, -0.0], "on [-1, 0]")]
)
def test_a_grid_repr_writes_a_negative_zero_end_as_0(nodes, span):
    g = GridMarginal.from_log_density(np.array(nodes), np.zeros(2))
    assert repr(g) == f"GridMarginal(2 nodes {span}, mean={g.mean():.4g}, sd=0.5)"


def test_info_names_as_one_string_is_refused():
    with pytest.raises(GPMSAError, match=r"info\['names'\] must be a list of parameter names"):
        Posterior({"a": np.zeros(2)}, info={"names": "a"})


def test_the_plot_has_a_legend_of_the_draws_the_grid_and_the_mean():
    g = GridMarginal.from_log_density(np.array([0.0, 1.0, 2.0]), np.zeros(3))
    fig = Posterior(grids={"t": g}, draw=lambda: {"t": np.array([0.5, 1.5])}).plot("t", bins=2)
    legend = fig.axes[0].get_legend()
    assert legend is not None
    assert [t.get_text() for t in legend.get_texts()] == ["draws", "exact (grid)", "mean"]


def test_the_plot_histogram_of_draws_is_a_density():
    """Draws 0.5, 1.5, 1.6, 1.7 in 2 bins of width 0.6 on [0.5, 1.7]: 1 and 3 of 4 draws,
    heights 1 / (4 * 0.6) and 3 / (4 * 0.6) (counts 1 and 3 without density=True)."""
    g = GridMarginal.from_log_density(np.array([0.0, 1.0, 2.0]), np.zeros(3))
    draws = {"t": np.array([0.5, 1.5, 1.6, 1.7])}
    fig = Posterior(grids={"t": g}, draw=lambda: draws).plot("t", bins=2)
    bars = fig.axes[0].patches
    assert [b.get_x() for b in bars] == pytest.approx([0.5, 1.1], rel=1e-12)
    assert [b.get_height() for b in bars] == pytest.approx([1 / 2.4, 3 / 2.4], rel=1e-12)


def test_the_kept_hdi_probabilities_of_a_float_level_are_read_only():
    """Every GridMarginal.hdi at that level shares them: a write would change the next one's."""
    kept = _float_hdi_probabilities(0.5)
    assert kept is _float_hdi_probabilities(0.5)
    np.testing.assert_array_equal(kept[[0, 200, 201, 401]], [0.0, 0.5, 0.5, 1.0])
    with pytest.raises(ValueError, match="read-only"):
        kept[0] = 1.0


def test_a_level_cdf_is_clipped_to_1_where_the_cumulative_sum_rounds_above():
    """Probabilities 5/9, 1/9 x 4: their float cumulative sum ends at 1 + 2^-52."""
    m = LevelMarginal.from_probabilities(np.arange(5.0), [5.0, 1.0, 1.0, 1.0, 1.0])
    assert np.cumsum(m.density)[-1] > 1.0
    assert m.cdf(4.0) == 1.0 and m.cdf(9.0) == 1.0


def test_a_grid_named_by_a_non_string_is_refused_before_the_names_are_known():
    g = GridMarginal.from_log_density(np.array([0.0, 1.0]), np.zeros(2))
    with pytest.raises(GPMSAError, match="grids: parameter names must be strings, got 1"):
        Posterior(grids={1: g}, draw=lambda: {"a": np.zeros(2)})


def test_the_names_of_lazily_drawn_samples_come_from_info_without_drawing():
    calls = []
    post = Posterior(draw=lambda: calls.append(1) or {"a": np.zeros(2)}, info={"names": ["a"]})
    assert post.names == ("a",)
    assert calls == []


def test_a_categorical_parameters_draws_give_the_lower_quantile():
    """Draws 0, 1 of a parameter with levels 0, 1: the median is level 0 (linear: 0.5)."""
    post = Posterior({"c": np.array([0.0, 1.0])}, info={"levels": {"c": [0, 1]}})
    assert post.quantile("c", 0.5) == 0.0


def test_a_held_parameter_of_one_draw_is_held():
    post = Posterior({"a": np.array([2.0]), "b": np.array([3.0])}, info={"held": ["a"]})
    summary = post.summary()
    assert summary["a"]["held"] is True and summary["b"]["held"] is False


def test_the_plot_marks_the_mean_with_a_thin_line():
    g = GridMarginal.from_log_density(np.array([0.0, 1.0, 2.0]), np.zeros(3))
    fig = Posterior(grids={"t": g}, draw=lambda: {"t": np.array([0.5, 1.5])}).plot("t", bins=2)
    mean_line = [ln for ln in fig.axes[0].lines if ln.get_label() == "mean"]
    assert [ln.get_linewidth() for ln in mean_line] == [1.0]
    assert mean_line[0].get_xdata()[0] == 1.0
