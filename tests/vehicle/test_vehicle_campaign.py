"""run_campaign: f per run, executors, the cache, failures, the file."""

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import vehicle

DESIGN = np.array([[0.7, 250.0], [1.6, 550.0], [1.1, 400.0]])
SHORT = {"road_length_m": 6.0, "window": 300, "lead_in_m": 0.5, "progress": False, "seed": 1}


class CountingExecutor(ThreadPoolExecutor):
    """A thread pool that counts submissions (runs in-process, so monkeypatching works)."""

    def __init__(self):
        super().__init__(max_workers=1)
        self.submitted = 0

    def submit(self, *args, **kwargs):
        self.submitted += 1
        return super().submit(*args, **kwargs)


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    cache = tmp_path_factory.mktemp("cache")
    return vehicle.run_campaign(DESIGN, cache_dir=cache, **SHORT), cache


def test_table_holds_one_f_per_run_and_matches_a_direct_simulation(table):
    camp, _ = table
    assert camp.ok.all()
    np.testing.assert_array_equal(camp.v, DESIGN[:, 0])
    assert np.all(camp.f_full > 0) and np.all(camp.f_window > 0)
    # f grows with speed and roughness: the slow smooth run is the smallest
    assert camp.f_full[0] == camp.f_full.min()
    # recompute run 1 by hand: the same road, the same drive, the same spans
    import roadgen

    road = roadgen.iso8608_profile(6.0, 550.0, seed=int(camp.seed[1]), lead_in_m=0.5)
    rng = np.random.default_rng([int(camp.seed[1]), 1])
    tr = vehicle.simulate(vehicle.Jackal(), road, 1.6, noise_std=1.0, seed=rng)
    full = tr.position >= 0.5 + vehicle.Jackal().wheelbase_m
    assert camp.f_full[1] == pytest.approx(np.var(tr.accel_front[full]), rel=1e-12)
    assert camp.f_window[1] == pytest.approx(np.var(tr.accel_front[-300:]), rel=1e-12)
    assert camp.f_window_noisy[1] == pytest.approx(np.var(tr.accel_front_measured[-300:]))


def test_noise_adds_about_its_variance(table):
    """E[f_noisy - f] = noise_std^2 = 1; the spread is the cross term 2 cov(a, e) ~ 2 sqrt(f/N)."""
    camp, _ = table
    n = SHORT["window"]  # each span has at least this many samples
    for f, f_noisy in ((camp.f_full, camp.f_full_noisy), (camp.f_window, camp.f_window_noisy)):
        sd = 2 * np.sqrt(f / n) + np.sqrt(2 / n)
        assert np.all(np.abs(f_noisy - f - 1.0) < 4 * sd)


def test_cache_resumes_and_loses_nothing(table, tmp_path):
    camp, cache = table
    files = sorted(cache.glob("run-*.npz"))
    assert len(files) == len(DESIGN)
    files[0].unlink()  # as if the campaign had been interrupted before this run finished
    ex = CountingExecutor()
    again = vehicle.run_campaign(DESIGN, cache_dir=cache, executor=ex, **SHORT)
    ex.shutdown()
    assert ex.submitted == 1
    for name in ("f_full", "f_window", "f_full_noisy", "f_window_noisy"):
        np.testing.assert_array_equal(getattr(again, name), getattr(camp, name))


def test_a_diverged_run_is_recorded_and_the_rest_goes_on(table):
    """GD 1e9 gives ~20 m bumps: the vehicle is thrown off and the run diverges."""
    camp, _ = table
    design = DESIGN.copy()
    design[1, 1] = 1e9
    with ThreadPoolExecutor(1) as ex:
        got = vehicle.run_campaign(design, executor=ex, **SHORT)
    assert list(got.ok) == [True, False, True]
    assert got.status[1].startswith("SimulationDivergedError: states out of range")
    assert np.isnan(got.f_full[1])
    np.testing.assert_array_equal(got.f_full[[0, 2]], camp.f_full[[0, 2]])


def test_save_and_load_round_trip_without_pickle(table, tmp_path):
    camp, _ = table
    path = tmp_path / "campaign.npz"
    camp.save(path)
    with np.load(path, allow_pickle=False) as data:
        assert "settings" in data.files
    back = vehicle.load_campaign(path)
    for name in ("v", "gd", "seed", "f_full", "f_window_noisy", "status"):
        np.testing.assert_array_equal(getattr(back, name), getattr(camp, name))
    assert back.settings == camp.settings
    assert back.settings["model"] == vehicle.Jackal().describe()


def test_damaged_files_raise(tmp_path, table):
    camp, _ = table
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip file")
    with pytest.raises(vehicle.CampaignFileError, match="damaged"):
        vehicle.load_campaign(bad)
    with pytest.raises(vehicle.CampaignFileError, match="does not exist"):
        vehicle.load_campaign(tmp_path / "missing.npz")
    other = tmp_path / "other.npz"
    np.savez(other, v=camp.v)
    with pytest.raises(vehicle.CampaignFileError, match="damaged or not a campaign"):
        vehicle.load_campaign(other)


def test_bad_campaign_input_raises():
    with pytest.raises(vehicle.VehicleError, match="v=2.4 m/s"):
        vehicle.run_campaign(np.array([[2.4, 300.0]]), **SHORT)
    with pytest.raises(vehicle.VehicleError, match="road_length_m=3.0 is too short"):
        vehicle.run_campaign(DESIGN, **{**SHORT, "road_length_m": 3.0})


def test_dask_executor_gives_the_same_table(table):
    distributed = pytest.importorskip("distributed")
    camp, _ = table
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        got = vehicle.run_campaign(DESIGN[:2], executor=client.get_executor(), **SHORT)
    np.testing.assert_array_equal(got.f_full, camp.f_full[:2])
    np.testing.assert_array_equal(got.f_window_noisy, camp.f_window_noisy[:2])


def _fields(camp, **change):
    names = ("v", "gd", "seed", "f_full", "f_window", "f_full_noisy", "f_window_noisy", "status",
             "settings", "accel", "accel_measured")  # fmt: skip
    return {**{k: getattr(camp, k) for k in names}, **change}


@pytest.mark.parametrize(
    "change, match",
    [
        ({"v": np.array([0.7, 1.6])}, "one length"),
        ({"gd": np.array([250.0, np.nan, 400.0])}, "Campaign.gd must be finite"),
        ({"f_full": np.array([1.0, -1.0, 2.0])}, "Campaign.f_full must be >= 0"),
        ({"seed": np.array([1.0, 2.0, 3.0])}, "seed must hold integers"),
        ({"status": np.array([1, 2, 3])}, "status must hold strings"),
        ({"settings": {"format": "mine"}}, "without the key 'format'"),
        ({"settings": {"road": object()}}, "JSON-able"),
        ({"accel": np.zeros((3, 4))}, "both given or both None"),
        ({"accel": np.zeros((3, 4)), "accel_measured": np.zeros((3, 5))}, r"\(3, samples\)"),
    ],
)
def test_a_campaign_that_could_not_be_saved_and_read_back_is_refused(table, change, match):
    camp, _ = table
    with pytest.raises(vehicle.VehicleError, match=match):
        vehicle.Campaign(**_fields(camp, **change))


def test_a_campaign_built_from_lists_is_held_as_arrays_and_round_trips(table, tmp_path):
    camp, _ = table
    lists = {k: getattr(camp, k).tolist() for k in ("v", "gd", "seed", "status")}
    built = vehicle.Campaign(**_fields(camp, **lists))
    assert built.ok.tolist() == [True, True, True]  # a list status would give one False
    built.save(tmp_path / "c.npz")
    back = vehicle.load_campaign(tmp_path / "c.npz")
    np.testing.assert_array_equal(back.gd, camp.gd)
    assert back.status.tolist() == camp.status.tolist()


def test_a_save_that_fails_leaves_the_earlier_file_whole(table, tmp_path, monkeypatch):
    camp, _ = table
    path = tmp_path / "campaign.npz"
    camp.save(path)
    before = path.read_bytes()

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(np, "savez", full_disk)
    with pytest.raises(vehicle.CampaignFileError, match="No space left"):
        camp.save(path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["campaign.npz"]
    with pytest.raises(vehicle.CampaignFileError, match="cannot write"):
        camp.save(tmp_path / "missing-folder" / "c.npz")


def test_a_file_whose_table_is_invalid_is_a_campaign_file_error(table, tmp_path):
    camp, _ = table
    path = tmp_path / "c.npz"
    camp.save(path)
    with np.load(path) as data:
        arrays = dict(data)
    arrays["gd"] = np.array([250.0, -1.0, 400.0])
    np.savez(path, **arrays)
    with pytest.raises(vehicle.CampaignFileError, match="not a valid campaign.*gd"):
        vehicle.load_campaign(path)
