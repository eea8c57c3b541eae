"""``terrain-replay`` given each argument in equivalent forms (session 88): the order of the
arguments, ``--opt=value`` or ``--opt value``, an abbreviated option, paths relative, absolute,
through ``..`` or from ``~``, the emulator by name or by its file, defaults given or left out,
numbers written ``2``, ``2.0`` or ``2e0``: the same CSV and estimates bag, byte for byte, and
the same replay.json but for its timings (and the paths as given); the command writes what
`control.replay_bag` with the same settings writes.

Before: ``--sign 1.0`` (or ``-1.0``, ``1e0``) was a usage error ("invalid int value") where
every other number took any form; a BAG given with a leading ``~`` that the shell had not
expanded (quoted, or from a script) was read from the home folder but checked against
``--out`` as a folder named "~", so ``--out ~/rec/out`` was written inside the recording, and
replay.json recorded "~/rec"; a topic without its leading "/" was refused naming the field
(imu_topic), not the option, with no hint of the name to give."""

import json
import shutil

import numpy as np
import pytest
from control_doubles import stream

import control
from control.shipped import shipped_emulator_path

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from control.robot import ReplaySettings, cli, write_sensor_bag  # noqa: E402

BLANKED = ("timing_s", "real_time_factor")


def _quick(mp, *models) -> None:
    """The command's shipped emulators with their likelihoods (``models``) prepared once for
    the session (0.3 s a run less; the same estimates, bit for bit); others load as ever."""
    shipped = {"AB"[m.emulator.metadata["noise_std"] > 0]: m.emulator for m in models}
    load, replay = cli.load_emulator, cli.replay_bag

    def loaded(emulator, name):
        return shipped[emulator] if emulator in shipped else load(emulator, name)

    def replayed(bag, emulator, *args, **kwargs):
        model = next((m for m in models if m.emulator is emulator), None)
        return replay(bag, emulator, *args, likelihood=model, **kwargs)

    mp.setattr(cli, "load_emulator", loaded)
    mp.setattr(cli, "replay_bag", replayed)


@pytest.fixture
def quick(monkeypatch, likelihood_a):
    _quick(monkeypatch, likelihood_a)


@pytest.fixture(scope="module")
def recording(tmp_path_factory, likelihood_a):
    """A 6 s drive (720 IMU messages), GD 300 then 500, from 3 s; and the outputs of
    ``terrain-replay rec --emulator A --out ref`` (and ``--sign -1 --out ref-1``) beside it."""
    where = tmp_path_factory.mktemp("recording")
    t, p, a, v = stream(lambda s: np.where(s < 3.6, 300.0, 500.0), 1.2, 6.0, seed=1, t0=3.0)
    write_sensor_bag(where / "rec", t, a, t, p, v)
    with pytest.MonkeyPatch.context() as mp:
        _quick(mp, likelihood_a)
        mp.chdir(where)
        assert cli.main(["rec", "--emulator", "A", "--out", "ref"]) == 0
        assert cli.main(["rec", "--emulator", "A", "--out", "ref-1", "--sign", "-1"]) == 0
    return where


def _outputs(out, blank=("bag", "emulator")):
    """(CSV bytes, {file: bytes} of the estimates bag, replay.json less its timings and
    ``blank``)."""
    report = json.loads((out / "replay.json").read_text())
    for key in (*BLANKED, *blank):
        report.pop(key)
    files = {f.name: f.read_bytes() for f in sorted((out / "estimates").iterdir())}
    return (out / "estimates.csv").read_bytes(), files, report


def _here(recording, tmp_path, monkeypatch):
    """The recording copied into ``tmp_path``, the current folder and the home folder."""
    shutil.copytree(recording / "rec", tmp_path / "rec")
    (tmp_path / "sub").mkdir()
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("HOME", str(tmp_path))
    return tmp_path


DEFAULTS = ["--imu-topic", "/imu/data", "--odom-topic", "/odometry/filtered", "--axis", "z",
            "--sign", "1", "--time-base", "header", "--position", "path", "--gravity", "keep",
            "--resample", "sample", "--reorder-periods", "3", "--storage", "mcap", "--v-max", "2",
            "--v-safe", "1", "--release-m", "0"]  # fmt: skip
FORMS = {
    "emulator first": ["--emulator", "A", "rec", "--out", "out"],
    "out first": ["--out", "out", "--emulator", "A", "rec"],
    "--opt=value": ["rec", "--emulator=A", "--out=out"],
    "abbreviated options": ["rec", "--emu", "A", "--out", "out", "--imu", "/imu/data"],
    "bag ./rec/": ["./rec/", "--emulator", "A", "--out", "out"],
    "bag through ..": ["sub/../rec", "--emulator", "A", "--out", "out"],
    "bag ~/rec": ["~/rec", "--emulator", "A", "--out", "out"],
    "out through ..": ["rec", "--emulator", "A", "--out", "sub/../out"],
    "out ~/out": ["rec", "--emulator", "A", "--out", "~/out"],
    "--out=~/out": ["rec", "--emulator", "A", "--out=~/out"],
    "emulator ~/A.gpmsa": ["rec", "--emulator", "~/A.gpmsa", "--out", "out"],
    "defaults given": ["rec", "--emulator", "A", "--out", "out", *DEFAULTS],
    "--v-max 2.0": ["rec", "--emulator", "A", "--out", "out", "--v-max", "2.0"],
    "--v-max 2e0": ["rec", "--emulator", "A", "--out", "out", "--v-max", "2e0"],
    "--v-max +2": ["rec", "--emulator", "A", "--out", "out", "--v-max", "+2"],
    "--v-safe 1e0": ["rec", "--emulator", "A", "--out", "out", "--v-safe", "1e0"],
    "--reorder-periods 3e0": ["rec", "--emulator", "A", "--out", "out", "--reorder-periods", "3e0"],
    "--release-m 0e0": ["rec", "--emulator", "A", "--out", "out", "--release-m", "0e0"],
    "--sign 1.0": ["rec", "--emulator", "A", "--out", "out", "--sign", "1.0"],
    "--sign 1e0": ["rec", "--emulator", "A", "--out", "out", "--sign", "1e0"],
    "--sign +1": ["rec", "--emulator", "A", "--out", "out", "--sign", "+1"],
}


@pytest.mark.parametrize("form", list(FORMS))
def test_an_argument_in_an_equivalent_form_writes_the_same_outputs(
    recording, quick, tmp_path, monkeypatch, form
):
    here = _here(recording, tmp_path, monkeypatch)
    shutil.copy(shipped_emulator_path("A"), here / "A.gpmsa")
    assert cli.main(FORMS[form]) == 0
    assert _outputs(here / "out") == _outputs(recording / "ref")


@pytest.mark.parametrize("form", [["--sign", "-1.0"], ["--sign=-1e0"], ["--sign=-1."]])
def test_a_sign_of_minus_one_in_any_form_is_minus_one(
    recording, quick, tmp_path, monkeypatch, form
):
    """(``--sign -1e0``, apart, is argparse's: a word that starts with '-' and is no plain
    negative number reads as an option; ``--sign=-1e0`` serves.)"""
    _here(recording, tmp_path, monkeypatch)
    assert cli.main(["rec", "--emulator", "A", "--out", "out", *form]) == 0
    assert _outputs(tmp_path / "out") == _outputs(recording / "ref-1")
    assert json.loads((tmp_path / "out" / "replay.json").read_text())["settings"]["imu_sign"] == -1


@pytest.mark.parametrize("value", ["2", "0", "nan", "-2.0"])
def test_a_sign_other_than_one_or_minus_one_is_still_a_usage_error(value, capsys):
    with pytest.raises(SystemExit) as done:
        cli.main(["rec", "--emulator", "A", f"--sign={value}"])
    assert done.value.code == 2
    assert "argument --sign: invalid" in capsys.readouterr().err  # (before: "invalid int value")


def test_a_bag_from_a_leading_tilde_is_read_and_checked_in_the_home_folder(
    recording, quick, tmp_path, monkeypatch, capsys
):
    here = _here(recording, tmp_path, monkeypatch)
    monkeypatch.chdir(here / "sub")
    files = sorted((here / "rec").iterdir())
    assert cli.main(["~/rec", "--emulator", "A", "--out", "~/rec/out"]) == 2
    assert f"--out '{here}/rec/out' lies inside the recording" in capsys.readouterr().err
    assert sorted((here / "rec").iterdir()) == files  # before: rec/out written
    # as the shell expands it: the same outputs, replay.json's "bag" and "emulator" included
    shutil.copy(shipped_emulator_path("A"), here / "A.gpmsa")
    assert cli.main(["~/rec", "--emulator", "~/A.gpmsa", "--out", "a"]) == 0
    assert cli.main([f"{here}/rec", "--emulator", f"{here}/A.gpmsa", "--out", "b"]) == 0
    assert _outputs(here / "sub" / "a", ()) == _outputs(here / "sub" / "b", ())


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_the_command_writes_what_replay_bag_writes(
    recording, likelihood_b, tmp_path, monkeypatch, storage
):
    _quick(monkeypatch, likelihood_b)
    _here(recording, tmp_path, monkeypatch)
    argv = ["rec", "--emulator", "B", "--out", "cli", "--storage", storage, "--gravity",
            "highpass", "--sign", "-1", "--position", "speed", "--reorder-periods", "1.5",
            "--no-restamp", "--v-max", "1.8", "--v-safe", "0.9", "--release-m", "2"]  # fmt: skip
    assert cli.main(argv) == 0
    settings = ReplaySettings(storage=storage, gravity="highpass", imu_sign=-1,
                              position="speed", reorder_periods=1.5, restamp=False)  # fmt: skip
    simplex = control.Simplex(v_max=1.8, v_safe=0.9, release_m=2.0)
    (tmp_path / "api").mkdir()
    control.replay_bag("rec", "B", settings, simplex=simplex, likelihood=likelihood_b,
                       csv="api/estimates.csv", out_bag="api/estimates")  # fmt: skip
    csv, files, report = _outputs(tmp_path / "cli")
    assert csv == (tmp_path / "api" / "estimates.csv").read_bytes()
    api_files = {f.name: f.read_bytes() for f in sorted((tmp_path / "api/estimates").iterdir())}
    assert files == api_files
    assert report["settings"]["storage"] == storage and report["simplex"]["release_m"] == 2.0


@pytest.mark.parametrize("option", ["--imu-topic", "--odom-topic"])
def test_a_topic_without_its_leading_slash_is_refused_with_the_name_to_give(
    option, tmp_path, capsys
):
    """By design (docs/robot.md): a bag records absolute topic names; ``ros2 topic echo
    imu/data`` resolves a relative one, the replay does not."""
    topic = "imu/data" if option == "--imu-topic" else "odometry/filtered"
    argv = ["rec", "--emulator", "A", "--out", str(tmp_path / "o"), option, topic]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert f"{option} must start with '/'" in err and f"got '{topic}': give '/{topic}'" in err
