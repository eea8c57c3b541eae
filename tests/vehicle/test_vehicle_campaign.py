"""run_campaign: f per run, executors, the cache, failures, the file."""

import dataclasses
import io
import json
import os
import threading
import time
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import vehicle
from vehicle import campaign

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


def test_no_seed_draws_a_fresh_one_and_records_it(tmp_path):
    """seed=None ran every run and then failed to record None; now the campaign draws a seed,
    records it, and the recorded seed runs the same campaign again."""
    kw = {**SHORT, "seed": None}
    first = vehicle.run_campaign(DESIGN[:2], **kw)
    seed = first.settings["seed"]
    assert isinstance(seed, int) and 0 <= seed < 2**128
    again = vehicle.run_campaign(DESIGN[:2], **{**kw, "seed": seed})
    np.testing.assert_array_equal(first.f_full, again.f_full)
    first.save(tmp_path / "c.npz")
    assert vehicle.load_campaign(tmp_path / "c.npz").settings["seed"] == seed


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
        (
            {"f_window": np.array([np.nan, 1.0, 2.0])},
            r"f_window\[0\] is NaN but status\[0\] is 'ok'",
        ),
        ({"seed": np.array([1, -2, 3])}, r"seed\[1\]=-2 is out of range: allowed integers in \[0"),
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
        good = dict(data)
    for change, match in (
        ({"gd": np.array([250.0, -1.0, 400.0])}, "gd"),
        ({"f_full": np.array([1.0, np.nan, 2.0])}, r"f_full\[1\] is NaN but status\[1\] is 'ok'"),
        ({"seed": np.array([-1, 2, 3])}, r"seed\[0\]=-1 is out of range"),
    ):
        np.savez(path, **(good | change))
        with pytest.raises(vehicle.CampaignFileError, match="not a valid campaign.*" + match):
            vehicle.load_campaign(path)


@pytest.mark.parametrize(
    "spoil",
    [
        lambda c: c.f_full.__setitem__(0, -1.0),
        lambda c: c.f_window.__setitem__(1, np.nan),
        lambda c: c.seed.__setitem__(2, -5),
        lambda c: c.settings.__setitem__("format", "mine"),
        lambda c: c.settings.__setitem__("road", object()),
    ],
    ids=["negative f", "NaN f of an ok run", "negative seed", "format key", "not JSON"],
)
def test_save_checks_the_table_again_and_keeps_the_earlier_file(table, tmp_path, spoil):
    """In-place changes after construction are caught before anything is written."""
    camp, _ = table
    mine = vehicle.Campaign(**_fields(camp, seed=camp.seed.copy(), settings=dict(camp.settings)))
    path = tmp_path / "campaign.npz"
    mine.save(path)
    before = path.read_bytes()
    spoil(mine)
    with pytest.raises(vehicle.VehicleError, match="^Campaign"):
        mine.save(path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["campaign.npz"]


@pytest.mark.parametrize(
    ("path", "match"),
    [("", "names no file"), (".", "names no file"), ("..", "names no file"), ("a\0b.npz", "NUL")],
)
def test_save_refuses_a_path_that_names_no_file(table, path, match):
    camp, _ = table
    with pytest.raises(vehicle.VehicleError, match=r"^path=.*" + match):
        camp.save(path)


def test_save_takes_the_longest_file_name(table, tmp_path):
    """A 255-character name (the file system's limit) is written: the temporary name is short."""
    camp, _ = table
    path = tmp_path / ("c" * 251 + ".npz")
    camp.save(path)
    camp.save(path)  # and replaced
    np.testing.assert_array_equal(vehicle.load_campaign(path).f_full, camp.f_full)
    assert list(tmp_path.iterdir()) == [path]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this system")
def test_loading_a_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "c.npz"
    os.mkfifo(fifo)
    errors = []

    def load():
        try:
            vehicle.load_campaign(fifo)
        except vehicle.CampaignFileError as exc:
            errors.append(str(exc))

    thread = threading.Thread(target=load, daemon=True)
    thread.start()
    thread.join(5.0)
    if thread.is_alive():  # blocked in open(): release it before failing
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
    assert errors and errors[0].endswith("c.npz' is not a regular file")


def _npz_bytes(members: dict[str, np.ndarray | bytes]) -> bytes:
    """An npz file's bytes: arrays as .npy members, bytes as they are."""
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as zf:
        for name, value in members.items():
            if isinstance(value, np.ndarray):
                npy = io.BytesIO()
                np.lib.format.write_array(npy, value)
                value = npy.getvalue()
            zf.writestr(f"{name}.npy", value)
    return out.getvalue()


def _flip_last_byte_of(raw: bytes, member: str) -> bytes:
    info = zipfile.ZipFile(io.BytesIO(raw)).getinfo(member)
    start = info.header_offset + 30 + len(info.filename) + len(info.extra)
    out = bytearray(raw)
    out[start + info.compress_size - 1] ^= 0x01
    return bytes(out)


def _huge_v(raw: bytes) -> bytes:
    """v.npy's header claims 1e10 float64 values (80 GB) over 64 bytes."""
    with np.load(io.BytesIO(raw)) as data:
        members = dict(data)
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f8", "fortran_order": False, "shape": (10**10,)}
    )
    return _npz_bytes(members | {"v": header.getvalue() + bytes(64)})


def _deep_settings(raw: bytes) -> bytes:
    with np.load(io.BytesIO(raw)) as data:
        members = dict(data)
    deep = json.dumps({"format": campaign.FORMAT})[:-1] + ', "x": ' + "[" * 10**5 + "]" * 10**5
    return _npz_bytes(members | {"settings": np.array(deep + "}")})


def _plain_npy(raw: bytes) -> bytes:
    out = io.BytesIO()
    np.save(out, np.arange(3.0))
    return out.getvalue()


@pytest.mark.parametrize(
    ("damage", "match"),
    [
        (lambda raw: raw[: len(raw) // 2], "damaged or not a campaign"),
        (lambda raw: _flip_last_byte_of(raw, "f_full.npy"), "damaged.*Bad CRC-32"),
        (_plain_npy, "damaged or not a campaign: File is not a zip file"),
        (_huge_v, r"v.npy declares a float64 array of shape \(10000000000,\)"),
        (_deep_settings, "settings are not JSON"),
    ],
    ids=["truncated", "bad CRC", "plain npy", "huge shape", "deep settings"],
)
def test_damaged_or_hostile_files_are_campaign_file_errors(table, tmp_path, damage, match):
    camp, _ = table
    path = tmp_path / "c.npz"
    camp.save(path)
    path.write_bytes(damage(path.read_bytes()))
    with pytest.raises(vehicle.CampaignFileError, match=match):
        vehicle.load_campaign(path)


def _fake_drive(calls: list):
    """A stand-in for one drive (no simulation): f = v, traces of ones; records each run."""

    def drive(spec):
        calls.append(spec.seed)
        keep = spec.keep_samples
        return np.full(4, spec.v), np.ones(keep), np.ones(keep)

    return drive


def _run(cache, **kwargs):
    with ThreadPoolExecutor(1) as ex:
        return vehicle.run_campaign(DESIGN, cache_dir=cache, executor=ex, **(SHORT | kwargs))


def test_failed_runs_are_not_cached_and_run_again(tmp_path, monkeypatch):
    def out_of_memory(spec):
        raise vehicle.VehicleError("a drive needs about 5 GiB of memory")

    monkeypatch.setattr(campaign, "_drive", out_of_memory)
    failed = _run(tmp_path)
    assert not failed.ok.any() and list(tmp_path.iterdir()) == []
    calls = []
    monkeypatch.setattr(campaign, "_drive", _fake_drive(calls))
    again = _run(tmp_path)
    assert again.ok.all() and len(calls) == len(DESIGN)
    np.testing.assert_array_equal(again.f_full, DESIGN[:, 0])


def test_a_cache_written_by_other_code_is_not_reused(tmp_path, monkeypatch):
    """A cache entry's name covers the code that computed it: entries from another version of
    roadgen, vehicle, numpy, scipy or exudyn (a road drawn differently) run again."""
    calls = []
    monkeypatch.setattr(campaign, "_drive", _fake_drive(calls))
    _run(tmp_path)
    _run(tmp_path)
    assert len(calls) == len(DESIGN)  # the same code: every run taken from the cache
    monkeypatch.setattr(campaign, "code_fingerprint", lambda: "another version of the code")
    _run(tmp_path)
    assert len(calls) == 2 * len(DESIGN)
    assert len(list(tmp_path.glob("run-*.npz"))) == 2 * len(DESIGN)


def test_the_code_fingerprint_follows_the_versions(monkeypatch):
    fp = campaign.code_fingerprint()
    campaign.code_fingerprint.cache_clear()
    assert len(fp) == 64 and campaign.code_fingerprint() == fp  # the same files: the same
    monkeypatch.setattr(np, "__version__", "0.0.1")
    campaign.code_fingerprint.cache_clear()
    try:
        assert campaign.code_fingerprint() != fp
    finally:
        monkeypatch.undo()
        campaign.code_fingerprint.cache_clear()
    assert campaign.code_fingerprint() == fp


def test_damaged_or_failed_cache_entries_are_run_again(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(campaign, "_drive", _fake_drive(calls))
    first = _run(tmp_path, keep_s=0.05)
    entries = sorted(tmp_path.glob("run-*.npz"))
    assert len(calls) == len(entries) == 3 and first.accel.shape == (3, 6)
    raw = entries[0].read_bytes()
    entries[0].write_bytes(raw[: len(raw) // 2])  # truncated
    with np.load(entries[1]) as data:
        members = dict(data)
    np.savez(entries[1], **(members | {"accel": np.ones(7)}))  # traces of the wrong length
    nan = np.full(4, np.nan)
    np.savez(entries[2], **(members | {"f": nan, "status": np.array("VehicleError: memory")}))
    again = _run(tmp_path, keep_s=0.05)
    assert len(calls) == 6 and again.ok.all()
    np.testing.assert_array_equal(again.accel, first.accel)
    np.testing.assert_array_equal(again.f_window, first.f_window)


def test_a_cache_entry_that_is_a_folder_is_a_clear_error_before_any_run(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(campaign, "_drive", _fake_drive(calls))
    _run(tmp_path)
    entry = sorted(tmp_path.glob("run-*.npz"))[0]
    entry.unlink()
    entry.mkdir()
    with pytest.raises(
        vehicle.CampaignFileError, match=f"cache entry .*{entry.name}.* not a regular"
    ):
        _run(tmp_path)
    assert len(calls) == 3


def test_a_cache_dir_that_cannot_be_a_folder_is_refused(tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("x")
    for cache in (afile, afile / "sub"):
        with pytest.raises(vehicle.VehicleError, match=r"^cache_dir=.*afile.* cannot be used"):
            _run(cache)
    assert afile.read_text() == "x"


@pytest.mark.parametrize("own_pool", [True, False], ids=["own pool", "given executor"])
def test_an_error_cancels_the_queued_runs(monkeypatch, own_pool):
    """A run that raises (not a failure the campaign records) ends the campaign at once: the
    runs still queued are cancelled, not waited for (in the campaign's own pool, a thread pool
    here so that the stand-in drive reaches it, or in a given executor)."""

    class Boom(Exception):
        pass

    calls = []

    def drive(spec):
        calls.append(spec.seed)
        if len(calls) == 1:
            raise Boom("worker lost")
        time.sleep(0.2)
        return np.ones(4), np.zeros(0), np.zeros(0)

    monkeypatch.setattr(campaign, "_drive", drive)
    monkeypatch.setattr(
        campaign, "ProcessPoolExecutor", lambda max_workers, **kw: ThreadPoolExecutor(1)
    )
    design = np.column_stack([np.linspace(0.5, 1.5, 8), np.full(8, 300.0)])
    with ThreadPoolExecutor(1) as ex, pytest.raises(Boom):
        vehicle.run_campaign(design, executor=None if own_pool else ex, **SHORT)
    assert len(calls) <= 2


def test_cache_write_failures_traces_and_folder_paths_are_named(tmp_path):
    design = vehicle.lhs_design(3, seed=1)
    locked = tmp_path / "locked"
    locked.mkdir()
    os.chmod(locked, 0o500)
    try:
        if os.access(locked, os.W_OK):  # root writes anywhere: a folder no one may write
            locked = Path("/proc/self")
        with pytest.raises(vehicle.VehicleError, match="cannot be used as a folder"):
            vehicle.run_campaign(design, progress=False, cache_dir=locked)
    finally:
        os.chmod(tmp_path / "locked", 0o700)
    campaign = vehicle.run_campaign(design, progress=False, keep_s=0.5)
    with pytest.raises(vehicle.VehicleError, match="names a folder .* not a file"):
        campaign.save(str(tmp_path) + "/")
    broken = campaign.accel.copy()
    broken[0, 0] = np.nan  # a finished run's trace
    with pytest.raises(vehicle.VehicleError, match=r"Campaign.accel\[0\] is not finite but"):
        dataclasses.replace(campaign, accel=broken)
    path = tmp_path / "c.npz"
    campaign.save(path)
    arrays = dict(np.load(path, allow_pickle=False))
    del arrays["accel"], arrays["accel_measured"]  # traces lost, settings say they were kept
    np.savez(tmp_path / "lost.npz", **arrays)
    with pytest.raises(vehicle.CampaignFileError, match="keep 0.5 s of traces .* holds no"):
        vehicle.load_campaign(tmp_path / "lost.npz")


def _hand_built(seed):
    ones = np.ones(2)
    return vehicle.Campaign(v=ones, gd=ones, seed=seed, f_full=ones, f_window=ones,
                            f_full_noisy=ones, f_window_noisy=ones, status=np.array(["ok", "ok"]),
                            settings={})  # fmt: skip


@pytest.mark.parametrize(
    "seed, shown",
    [
        ([1, 2**63], "9223372036854775808"),  # numpy would hold these as floats
        ([1, 2**64], "18446744073709551616"),  # or as objects
        ([1, 2**127], str(2**127)),
        (np.array([1, 2**63], dtype=np.uint64), "9223372036854775808"),
        (np.array([1, 2**70], dtype=object), str(2**70)),
    ],
)
def test_seeds_beyond_the_int64_column_are_named_with_its_range(seed, shown):
    with pytest.raises(
        vehicle.VehicleError,
        match=rf"^Campaign.seed\[1\]={shown} is out of range: allowed integers in \[0, 2\*\*63\)",
    ):
        _hand_built(seed)


def test_a_hand_built_campaign_holds_its_seeds_as_int64_like_a_run_one(tmp_path):
    """run_campaign's seeds are SeedSequence words (< 2**32) held as int64; any integer column
    in [0, 2**63) is held the same way, and round trips."""
    seeds = np.random.SeedSequence(0).generate_state(2)
    assert seeds.dtype == np.uint32
    for given in (seeds, seeds.tolist(), np.array([0, 2**63 - 1], dtype=np.uint64),
                  [0, 2**63 - 1], np.array([3, 4], dtype=object)):  # fmt: skip
        camp = _hand_built(given)
        assert camp.seed.dtype == np.int64
        np.testing.assert_array_equal(camp.seed, np.asarray(given).astype(np.int64))
    camp.save(tmp_path / "c.npz")
    assert vehicle.load_campaign(tmp_path / "c.npz").seed.tolist() == [3, 4]
    with pytest.raises(vehicle.VehicleError, match=r"^Campaign.seed must hold integers"):
        _hand_built(np.array([1, "a"], dtype=object))
