"""A recording this package writes from a simulation records the simulated vehicle and noise sd
(`control.record_run`'s MCAP metadata record, `write_sensor_bag`'s custom_data), and the replay
refuses an emulator made for another vehicle: a bag of a 17 % heavier Jackal replayed with the
shipped emulator A without a word (this file's 10 m run: 19 % safety mode on GD 300, below
GD_max). Bags without the record (a robot's,
an older one) replay as before; a damaged record is a BagError naming the field."""

import functools
import json
import warnings

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

import control  # noqa: E402
import roadgen  # noqa: E402
import vehicle  # noqa: E402
from control.errors import BagError, ControlWarning, EmulatorMismatchError  # noqa: E402
from control.robot import bags, cli, read_recording, replay_bag, write_run_bag  # noqa: E402
from control.robot.bags import SIMULATION_KEYS  # noqa: E402

HEAVY = vehicle.Jackal(mass_kg=18.431 * 1.17)
REFUSED = r"another vehicle .*\(mass_kg: recording 21\.56427 vs emulator 18\.431\)"


@pytest.fixture(scope="module")
def heavy(emulator_a, likelihood_a, tmp_path_factory):
    """A 10 m closed-loop run of a 17 % heavier Jackal (emulator A, unchecked), recorded as
    MCAP on the way."""
    path = tmp_path_factory.mktemp("heavy") / "run.mcap"
    result = control.run_closed_loop(
        roadgen.track([(10, 300)], seed=3), emulator_a, model=HEAVY, check=False, seed=3,
        likelihood=likelihood_a, record=path,
    )  # fmt: skip
    return result, path


def _same(a, b) -> None:
    for name in ("stamp_ns", "gd_mean", "gd_sd", "gd_lo", "gd_hi", "prob_above", "command"):
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name
    assert a.status.tolist() == b.status.tolist() and a.mode.tolist() == b.mode.tolist()


def test_a_heavier_simulated_vehicle_is_refused_naming_mass_kg(
    heavy, emulator_a, likelihood_a, tmp_path
):
    result, mcap = heavy
    folder = write_run_bag(result, tmp_path / "bag")
    for path in (mcap, folder):
        rec = read_recording(path)
        assert rec.vehicle == HEAVY and rec.noise_std == 0.0
        with pytest.raises(EmulatorMismatchError, match=REFUSED):
            replay_bag(path, emulator_a, likelihood=likelihood_a)
    # replayed anyway on request: as a bag without the record, with a note
    anyway = replay_bag(folder, emulator_a, likelihood=likelihood_a, check_vehicle=False)
    bare = write_run_bag(result, tmp_path / "bare", model=None, noise_std=None)
    plain = replay_bag(bare, emulator_a, likelihood=likelihood_a)
    _same(anyway, plain)
    assert anyway.notes[1:] == plain.notes and "replayed anyway" in anyway.notes[0]


def test_terrain_replay_refuses_it_and_goes_on_with_ignore_vehicle(
    heavy, likelihood_a, tmp_path, capsys, monkeypatch
):
    _, mcap = heavy
    # the session's prepared likelihood saves the ~1 s of preparing one per replay
    monkeypatch.setattr(cli, "replay_bag", functools.partial(replay_bag, likelihood=likelihood_a))
    assert cli.main([str(mcap), "--emulator", "A", "--out", str(tmp_path / "no")]) == 2
    assert "mass_kg: recording 21.56427 vs emulator 18.431" in capsys.readouterr().err
    assert not (tmp_path / "no").exists()
    out = tmp_path / "yes"
    assert cli.main([str(mcap), "--emulator", "A", "--out", str(out), "--ignore-vehicle"]) == 0
    notes = json.loads((out / "replay.json").read_text())["notes"]
    assert "mass_kg: recording 21.56427" in notes[0]


def test_the_emulators_vehicle_replays_as_before_and_a_bag_without_the_record_too(
    heavy, emulator_a, likelihood_a, tmp_path
):
    """The same samples with the emulator's vehicle recorded, and with nothing recorded (as a
    robot's bag or an older one): the same estimates, bit for bit, and no warning."""
    result, _ = heavy
    same = write_run_bag(result, tmp_path / "same", model=vehicle.Jackal(), storage="sqlite3")
    bare = write_run_bag(result, tmp_path / "bare", model=None, noise_std=None)
    assert "terrain_gpmsa.vehicle" not in (bare / "metadata.yaml").read_text()
    rec = read_recording(bare)
    assert rec.vehicle is None and rec.noise_std is None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        a = replay_bag(same, emulator_a, likelihood=likelihood_a)
        b = replay_bag(bare, emulator_a, likelihood=likelihood_a)
    _same(a, b)
    assert a.notes == b.notes


def test_a_recorded_noise_sd_other_than_the_emulators_warns(
    heavy, emulator_a, likelihood_a, tmp_path
):
    result, _ = heavy
    bag = write_run_bag(result, tmp_path / "noisy", model=vehicle.Jackal(), noise_std=1.0)
    with pytest.warns(ControlWarning, match="noise_std = 1 m/s.2 but the emulator .* 0"):
        replay_bag(bag, emulator_a, likelihood=likelihood_a)


def _set_custom(folder, key, value) -> None:
    from ruamel.yaml import YAML

    yaml = YAML(typ="safe")
    meta = yaml.load((folder / "metadata.yaml").read_text())
    meta["rosbag2_bagfile_information"]["custom_data"][key] = value
    with (folder / "metadata.yaml").open("w") as f:
        yaml.dump(meta, f)


def test_a_damaged_record_in_a_bag_folder_is_a_bag_error_naming_the_field(heavy, tmp_path):
    result = heavy[0]
    bag = write_run_bag(result, tmp_path / "bag", storage="sqlite3")
    vehicle_key, noise_key = SIMULATION_KEYS["vehicle"], SIMULATION_KEYS["noise_std"]
    jackal = '{"model": "Jackal", '
    written = bags.simulation_record(HEAVY, 0.0)
    written = {SIMULATION_KEYS[name]: text for name, text in written.items()}
    cases = [
        (vehicle_key, "not json", "is not JSON"),
        (vehicle_key, "[1, 2]", "not a vehicle description: .* is a dict, got list"),
        (vehicle_key, jackal + '"wings": 2}', r"no parameter\(s\) \['wings'\]"),
        (vehicle_key, jackal + '"mass_kg": NaN}', "Jackal.mass_kg=nan must be finite"),
        (vehicle_key, jackal + '"mass_kg": 1e999}', "Jackal.mass_kg=inf must be finite"),
        # too deep for Python <= 3.12's json (RecursionError); 3.13's reads 3000 levels and
        # then finds the text cut short (JSONDecodeError): either way not JSON, named
        (vehicle_key, "[" * 3000, r"is not JSON \((RecursionError|JSONDecodeError)"),
        (vehicle_key, "x" * 5000, "5000 characters long, more than 4096"),
        (vehicle_key, {"model": "Jackal"}, "is a dict, not the JSON text"),
        (noise_key, "-1", "not a noise sd: noise_std=-1 is out of range"),
        (noise_key, "true", "not a noise sd: noise_std=True must be a real number"),
    ]
    for key, value, why in cases:
        _set_custom(bag, key, value)
        with pytest.raises(BagError, match=f"custom_data '{key}' .*{why}"):
            read_recording(bag)
        _set_custom(bag, key, written[key])  # as written: its SHA-256 matches
    assert read_recording(bag).vehicle == HEAVY


def test_a_damaged_record_in_an_mcap_file_is_a_bag_error_naming_the_field(
    heavy, tmp_path, monkeypatch
):
    from control.robot import record

    result = heavy[0]
    cases = [
        (
            {"vehicle": '{"model": "Jackal", "mass_kg": Infinity}'},
            "field 'vehicle' is not a vehicle description: Jackal.mass_kg=inf must be finite",
        ),
        ({"noise_std": "1e999"}, "field 'noise_std' is not a noise sd: noise_std=inf"),
        ({"wings": "2"}, r"holds unknown field\(s\) \['wings'\]"),
        ({"vehicle": "x" * 100_000}, "bytes long, more than"),
    ]
    for k, (fields, why) in enumerate(cases):
        monkeypatch.setattr(record, "simulation_record", lambda *_, f=fields: f)
        path = control.record_run(result, tmp_path / f"bad{k}.mcap")
        with pytest.raises(BagError, match=f"'terrain_gpmsa.simulation' metadata record.*{why}"):
            read_recording(path)
