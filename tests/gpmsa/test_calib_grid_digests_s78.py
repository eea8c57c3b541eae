"""A Calibrator's grid posteriors are those it gave before its likelihood's work was rearranged
(the fit's excess_var no longer computed where only outside_sds is read, the whitening's and
dense predictive's solves made in place on right-hand sides built in LAPACK's order, the lamOs
integrand computed in blocks of nodes): digests taken before the change, to 1e-9 relative
(sums 1e-10), which float64 rounding on another BLAS or CPU stays well within."""

import warnings

import numpy as np
import pytest
from _calib_cases import road_emulator, two_param_emulator, with_draws
from test_calib_grid_posterior import peaks_data, symmetric_two_param_emulator
from test_constraint_two_params import peaks_case

from gpmsa import Calibrator
from gpmsa.calibration.model import _CHUNK, LamOsPrior, _log_integrand
from gpmsa.calibration.observations import fit_of, fixed_gp, outside_sds, reduce, theta_probe

LEVELS = [0.1, 0.5, 0.9]


def five_observations():
    """5 observations of `two_param_emulator` at a = 0.3, b = 0.6, noise sd 0.01 (s57's)."""
    x = np.linspace(0.05, 0.95, 5)[:, None]
    y = np.sin(2.0 * x + 1.5 * 0.3) + 0.8 * 0.6 * x
    return x, y + 0.01 * np.random.default_rng(1).standard_normal(x.shape)


def road_narrow():
    """40 road observations: a GD posterior the default grid refines (d = 40)."""
    rng = np.random.default_rng(0)
    v = np.linspace(0.6, 1.9, 40)[:, None]
    return v, 0.02 * 410 * v**1.6 * (1 + 0.005 * rng.standard_normal(v.shape))


def case(name):
    """(Calibrator, x_obs, y_obs) of a digest's case."""
    x5 = np.linspace(0.05, 0.95, 5)[:, None]
    if name == "two_obs":  # d = 2, refined once
        x = np.random.default_rng(1).uniform(0.05, 0.95, 40)[:2, None]
        return Calibrator(two_param_emulator()), x, np.sin(2 * x + 0.45) + 0.56 * x
    if name == "five":  # d = 5, refined twice (heavy tails: the core)
        return Calibrator(two_param_emulator()), *five_observations()
    if name == "peaks":  # d = 12, two peaks of a
        return Calibrator(symmetric_two_param_emulator()), *peaks_data()
    if name == "peaks_cut":  # and a constraint
        emu, x, y, allowed = peaks_case()
        return Calibrator(emu, constraint=lambda th: bool(allowed(th[0], th[1]))), x, y
    if name == "draws":  # three emulator parameter sets
        y = np.sin(2.0 * x5 + 1.5 * 0.3) + 0.8 * 0.6 * x5
        return Calibrator(with_draws(two_param_emulator(), n=3), emulator_params="draws"), x5, y
    if name == "road_narrow":  # one parameter, d = 40, the prepared refinement
        return Calibrator(road_emulator()), *road_narrow()
    return Calibrator(road_emulator()), [[1.2]], [[0.02 * 410 * 1.2**1.6]]  # "road_one"


# per case: nodes, the sum of log_likelihood_grid, per parameter (mean, sd, quantiles at
# LEVELS, sum of the marginal's density over its peak, sum of its nodes), and the records
DIGESTS = {
    "two_obs": (9409, -37670.27333148351, {
        "a": (0.3104646165281011, 0.029603976109510387, 0.2832518820060816, 0.3095886321652146,
              0.33782163579465646, 4.408032176525917, 47.80032040975705),
        "b": (0.7074989197140721, 0.036368012256685074, 0.6741206990430397, 0.7059590497567773,
              0.7411650156845548, 5.812291671750654, 49.579841041091754)},
        {"resolution": (1.9679580087657822, 2.471782342434675),
         "conditional_sds": (1.9306421493811294, 2.489014862239768)}),
    "five": (8550, -55180.04693483733, {
        "a": (0.30828615563365686, 0.009297310325842705, 0.2973036016263355,
              0.30834406246049095, 0.3191724198279892, 8.688299468870355, 35.010571184251525),
        "b": (0.6049150780432164, 0.016769175609386865, 0.5852124964001881, 0.6048670437155056,
              0.6246800299985843, 9.141845785805936, 51.24887883984153)},
        {"resolution": (3.5690102378063964, 3.758682015895873),
         "conditional_sds": (3.678722149287968, 3.869479437481559)}),
    "peaks": (9120, -72022.85804173394, {
        "a": (0.6442987426698455, 0.1439408092854092, 0.3016020913798535, 0.702445488813221,
              0.7130888043472985, 2.5480266590732823, 38.163906084687554),
        "b": (0.4641930390758941, 0.02706953433594692, 0.43060644104323476,
              0.46516839026261586, 0.5005152746105569, 5.340175485027462, 60.68789972073251)},
        {"resolution": (0.8149668149787743, 1.7991388128932657),
         "conditional_sds": (15.855248147707078, 0.8986052293038075)}),
    "peaks_cut": (9460, -72022.85804173394, {
        "a": (0.6977677911356188, 0.05134964716605402, 0.6945835582424565, 0.7040809481378081,
              0.7127751006791907, 22.75935545043538, 151.77831408769603),
        "b": (0.45977397089195515, 0.025330337657041794, 0.4273585185929689,
              0.4592152954542874, 0.4927723876291894, 35.38699899037525, 50.70329192533021)},
        {"resolution": (2.162886154009271, 4.1051444216731525),
         "conditional_sds": (16.091046582566364, 1.1921692848225742)}),
    "draws": (8722, -55131.357155516685, {
        "a": (0.305304171011327, 0.007179865487254366, 0.2966513467306792, 0.3053443182238063,
              0.31390265492218195, 8.953141299285397, 35.87942168112983),
        "b": (0.5998263075441441, 0.012978450310182453, 0.5842186201253662, 0.5998023853111066,
              0.6154559096790522, 9.145226008084785, 50.33487167220427)},
        {"resolution": (3.59483667594706, 3.72074717720774),
         "conditional_sds": (3.5973001547771606, 3.693671214710612)}),
    "road_narrow": (129, -2165.3424640196154, {
        "GD": (410.77174149089467, 3.6642351819340617, 406.0691400581397, 410.7722954845928,
               415.4736200322941, 18.077428745944584, 53026.46053189751)},
        {"log_evidence": 58.152008026656674, "inv_lamos": 0.11994965812507566}),
    "road_one": (129, -334.7584587618386, {
        "GD": (413.2496056342467, 30.629974651002595, 377.2008439550756, 413.4671160440226,
               449.2291528809718, 22.05276249403396, 51626.33329323269)},
        {"log_evidence": -0.3113449706520335, "inv_lamos": 16.925412560891452}),
}  # fmt: skip


@pytest.mark.parametrize("name", sorted(DIGESTS))
def test_grid_posteriors_are_the_ones_before_the_rearranged_work(name):
    cal, x, y = case(name)
    with warnings.catch_warnings():  # peaks: unresolved (test_calib_grid_posterior's case)
        warnings.simplefilter("ignore")
        post = cal.update(x, y)
        loglik = cal.log_likelihood_grid(x, y)[1]
    n_nodes, loglik_sum, marginals, records = DIGESTS[name]
    assert post.info["n_nodes"] == n_nodes
    assert loglik.sum() == pytest.approx(loglik_sum, rel=1e-10)
    for param, (mean, sd, *rest) in marginals.items():
        grid = post.grids[param]
        assert post.mean(param) == pytest.approx(mean, rel=1e-9)
        assert post.sd(param) == pytest.approx(sd, rel=1e-9)
        np.testing.assert_allclose(post.quantile(param, LEVELS), rest[:3], rtol=1e-9)
        assert grid.density.sum() / grid.density.max() == pytest.approx(rest[3], rel=1e-10)
        assert grid.nodes.sum() == pytest.approx(rest[4], rel=1e-10)
    for key in ("resolution", "conditional_sds", "log_evidence"):
        if key in records:
            np.testing.assert_allclose(post.info[key], records[key], rtol=1e-9)
    if "inv_lamos" in records:
        inv = post.info["expected_inv_lamOs"].sum()
        assert inv == pytest.approx(records["inv_lamos"], rel=1e-9)


@pytest.mark.parametrize("name", ["two_obs", "five", "road_narrow", "road_one"])
def test_outside_sds_is_the_fits_number_without_its_excess(name):
    """`outside_sds` (what an update reads) is `fit_of`'s outside_sds, on the probe and on
    scattered theta values, for one datum and for several."""
    cal, x, y = case(name)
    data = reduce(cal.emulator, x, y, False)
    gp = fixed_gp(cal.emulator)
    q = cal.q
    for theta, layout in [(theta_probe(q), (129,) if q == 1 else (33, 33)),
                          (np.random.default_rng(2).uniform(0, 1, (50, q)), None)]:  # fmt: skip
        mean, cov = gp.predict(data.x, theta)
        assert outside_sds(mean, cov, data, layout) == fit_of(mean, cov, data, layout).outside_sds


@pytest.mark.parametrize("d", [2, 5, 40])
def test_the_lamos_integrand_in_blocks_is_the_one_pass(d):
    """`_log_integrand` over more nodes than one block (`_CHUNK`) holds: each row as the whole
    array's expression gives it."""
    rng = np.random.default_rng(d)
    s = np.linspace(-3.0, 6.0, 61)
    G = 3 * _CHUNK // (s.size * d) + 7  # three blocks and a part
    e, y2 = rng.uniform(0.0, 2.0, (G, d)), rng.uniform(0.0, 3.0, (G, d)) ** 2
    prior = LamOsPrior(5.0, 5.0)
    lam = np.exp(s)
    tail = (prior.shape - 0.5) * s - prior.rate * lam + 0.3
    var = e[:, None, :] + 1.0 / lam[None, :, None]
    whole = tail - 0.5 * np.sum(np.log(var) + y2[:, None, :] / var, axis=2)
    np.testing.assert_allclose(_log_integrand(s, e, y2, prior, 0.3, 1), whole, rtol=1e-14)
