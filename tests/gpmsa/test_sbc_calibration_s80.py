"""Simulation-based calibration of the online calibration (benchmarks/sbc_calibration.py): with
theta, lamOs and the observations drawn from the very model the calibration assumes, the truth's
PIT (grid) or rank among thinned draws (MCMC) is uniform and the central intervals cover at
their level. Under exact inference a 10-bin histogram's chi-square p-value is uniform, so the
threshold 1e-4 fails falsely once in 10,000 seeds; the seeds are fixed (the draws are
deterministic) and not the reported table's (`REPORT_SEED`)."""

import numpy as np
import pytest
from _calib_cases import vector_emulator

from tests._examples import load_benchmark

P_MIN = 1e-4


@pytest.fixture(scope="module")
def sbc():
    return load_benchmark("sbc_calibration")


def test_generator_predictive_is_the_emulators(sbc) -> None:
    # the generator's own dense solves give gpmsa's predictive (mean and covariance, jointly
    # over three experiments), so the SBC draws from the model the calibration assumes
    from gpmsa.calibration.observations import fixed_gp

    emu = vector_emulator()
    xu, theta = np.array([[0.1], [0.5], [0.8]]), np.array([0.3])
    mean, cov = sbc.predictive(emu, xu, theta)
    ref_mean, ref_cov = fixed_gp(emu).predict(xu, theta[None])
    np.testing.assert_allclose(mean, ref_mean[0], rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(cov, ref_cov[0], rtol=1e-7, atol=1e-10)


@pytest.mark.filterwarnings("ignore::gpmsa.errors.OutsideEmulatorWarning")
def test_grid_pit_is_uniform_on_a_functional_output(sbc) -> None:
    # 150 replicates of one experiment (8 values, 2 basis vectors, lamOs from its vague prior):
    # the PIT's histogram and a Kolmogorov-Smirnov test, each p > 1e-4
    from scipy.stats import kstest

    emu = vector_emulator()
    case = sbc.Case("functional_q1", 1, 8, 2, 1)
    ((pit, cover),) = sbc.grid_pits(emu, case, 150, np.random.default_rng(8001)).values()
    assert sbc.histogram_p(pit, 1.0)[1] > P_MIN
    assert kstest(pit, "uniform").pvalue > P_MIN
    assert np.all((pit >= 0) & (pit <= 1))
    # the 90% interval and the PIT say the same (both from the exact marginal)
    np.testing.assert_array_equal(cover[:, 1], np.abs(pit - 0.5) <= 0.45 + 1e-9)


@pytest.mark.filterwarnings("ignore::gpmsa.errors.OutsideEmulatorWarning")
def test_grid_check_sees_observations_from_another_model(sbc, monkeypatch) -> None:
    # the same replicates with the weights drawn at 10 times the emulator's predictive
    # covariance (a generator the calibration does not assume): the PIT piles up at the ends
    # and the histogram's p falls far below the threshold (4.9e-10 here), so 150 replicates
    # have the power the uniform test above relies on
    exact = sbc.predictive

    def wider(emu, xu, theta):
        mean, cov = exact(emu, xu, theta)
        return mean, 10.0 * cov

    monkeypatch.setattr(sbc, "predictive", wider)
    case = sbc.Case("functional_q1", 1, 8, 2, 1)
    ((pit, _),) = sbc.grid_pits(vector_emulator(), case, 150, np.random.default_rng(8001)).values()
    assert sbc.histogram_p(pit, 1.0)[1] < P_MIN


def test_rank_histogram_is_flat_for_uniform_ranks_and_not_for_a_biased_posterior(sbc) -> None:
    # the statistic itself: ranks 0..99 fall 10 to a bin; ranks of a posterior centred off the
    # truth by one sd pile up at one end (p far below the threshold)
    counts, p = sbc.histogram_p(np.arange(100.0), 99.0)
    assert counts.tolist() == [10] * 10 and p == 1.0
    rng = np.random.default_rng(5)
    truth = rng.standard_normal(300)
    draws = truth[:, None] + 1.0 + rng.standard_normal((300, 99))
    assert sbc.histogram_p(np.sum(draws < truth[:, None], axis=1), 99.0)[1] < 1e-10


def test_usage_error_names_the_option(sbc, capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        sbc.main(["--replicates", "0"])
    assert exc.value.code == 2
    assert "--replicates must be >= 1, got 0" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::gpmsa.errors.OutsideEmulatorWarning")
@pytest.mark.parametrize("name", ["scalar_q1", "scalar_q2", "functional_q1", "functional_q2"])
def test_sbc_grid_and_mcmc(sbc, name: str) -> None:
    # each case's fitted emulator: 300 grid replicates and 100 MCMC ones (theta and lamOs free;
    # lamOs known); every histogram's p > 1e-4 and the 90% intervals' coverage within 4.5
    # binomial sds of 0.9 (a false failure about once in 150,000 per row)
    case = next(c for c in sbc.CASES if c.name == name)
    emu = sbc.emulator(case)
    streams = np.random.SeedSequence([sbc.DEV_SEED + 1, len(name)]).spawn(3)
    rows = list(sbc.grid_pits(emu, case, 300, np.random.default_rng(streams[0])).values())
    tops = [1.0] * len(rows)
    for known, stream in ((False, streams[1]), (True, streams[2])):
        ranks = sbc.mcmc_ranks(emu, case, 100, np.random.default_rng(stream), known)
        rows += list(ranks.values())
        tops += [float(sbc.N_RANK_DRAWS)] * len(ranks)
    for (values, cover), top in zip(rows, tops, strict=True):
        assert sbc.histogram_p(values, top)[1] > P_MIN
        n = len(values)
        assert abs(cover[:, 1].mean() - 0.9) <= 4.5 * np.sqrt(0.09 / n)
