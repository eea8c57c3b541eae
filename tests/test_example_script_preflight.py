"""The example scripts check what they are given before the long work, and use what an emulator
records: posterior_check drives the vehicle and noise of the shipped window emulator and
refuses one whose domain misses the table's cells; train_emulator refuses, before the campaign,
runs whose fit would exceed gpmsa's memory limit, turns a block scatter that its runs cannot
estimate into a usage error naming the options, and titles its design figure with the Latin
hypercube's and the anchor runs' counts apart."""

import argparse
import os
import sys
from types import SimpleNamespace

import numpy as np
import pytest

import control
import gpmsa
import vehicle
from tests._examples import load_example


class _Stop(Exception):
    """Raised by a spy to end a script at its first drive."""


def _window_emulator(v_range, mass_kg: float, noise_std: float):
    """A small emulator of log f over v (m/s) in ``v_range`` and GD in [200, 600], with the
    shipped window emulator's metadata but the given vehicle mass and training noise."""
    rng = np.random.default_rng(0)
    v = rng.uniform(*v_range, 12)
    gd = rng.uniform(200.0, 600.0, 12)
    v[:2], gd[2:4] = v_range, (200.0, 600.0)
    meta = dict(control.shipped_emulator("A", "window").metadata)
    meta["vehicle"] = vehicle.Jackal(mass_kg=mass_kg).describe()
    meta["noise_std"] = noise_std
    data = gpmsa.SimData(
        x=v[:, None], t=gd[:, None], y=(np.log(gd) + 2 * np.log(v))[:, None],
        x_names=["v"], t_names=["GD"], y_names=["log_f"],
    )  # fmt: skip
    return gpmsa.fit(data, n_iter=20, seed=0, metadata=meta)


def _posterior_check(monkeypatch, emu):
    """posterior_check with ``emu`` as the shipped window emulator and a spy on its drives
    (the first ends the script): returns the module and the drives' (model, noise_std)."""
    script = load_example("posterior_check")
    monkeypatch.setattr(script.control, "shipped_emulator", lambda case, kind: emu)
    drives = []

    def spy(model, road, speed, **kw):
        drives.append((model, kw["noise_std"]))
        raise _Stop

    monkeypatch.setattr(script.vehicle, "simulate", spy)
    return script, drives


def test_posterior_check_drives_the_vehicle_and_noise_its_emulator_records(monkeypatch, tmp_path):
    script, drives = _posterior_check(monkeypatch, _window_emulator((0.5, 2.0), 21.5, 0.3))
    with pytest.raises(_Stop):
        script.main(["--roads", "1", "--out", str(tmp_path)])
    ((model, noise),) = drives
    assert model.mass_kg == pytest.approx(21.5, rel=1e-12)
    assert noise == pytest.approx(0.3, rel=1e-12)


def test_posterior_check_refuses_an_emulator_that_misses_its_cells(monkeypatch, tmp_path, capsys):
    script, drives = _posterior_check(monkeypatch, _window_emulator((1.0, 2.0), 18.431, 0.0))
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exc:
        script.main(["--roads", "1", "--out", str(out)])
    assert exc.value.code == 2
    error = capsys.readouterr().err.strip().splitlines()[-1]
    assert "--case A: the shipped window emulator covers v [1, 2] m/s" in error
    assert "Table 2's cells need v [0.75, 1.75] m/s" in error
    assert drives == [] and not out.exists()  # refused before any drive or folder


@pytest.mark.parametrize(
    "argv, message",
    [
        (
            ["--n-runs", "4000", "--keep-s", "17"],
            "the band emulators' covariances of 5332 runs and gpmsa.fit's draws needs about",
        ),
        (
            ["--n-runs", "9000", "--keep-s", "9", "--features", "window"],
            "the window emulators' covariances of 9000 runs and gpmsa.fit's draws needs about",
        ),
    ],
)
def test_train_emulator_refuses_a_fit_beyond_memory_before_the_campaign(
    monkeypatch, tmp_path, capsys, argv, message
):
    script = load_example("train_emulator")

    def campaign(*args, **kwargs):
        raise AssertionError("the campaign ran")

    monkeypatch.setattr(script.vehicle, "run_campaign", campaign)
    with pytest.raises(SystemExit) as exc:
        script.main([*argv, "--out", str(tmp_path / "out")])
    assert exc.value.code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_train_emulator_names_the_options_when_its_runs_cannot_give_the_scatter(tmp_path, capsys):
    script = load_example("train_emulator")
    out = tmp_path / "out"
    # 13 runs of rank 1 pass the design's check (check_scatter_rank), not the covariance's
    argv = ["--n-runs", "11", "--keep-s", "16.7", "--n-iter", "2", "--anchor-runs", "1"]
    with pytest.raises(SystemExit) as exc:  # two batches a run: one covariance dof each
        script.main([*argv, "--cases", "A", "--features", "band", "--out", str(out)])
    assert exc.value.code == 2
    error = capsys.readouterr().err.strip().splitlines()[-1]
    assert "case A, band emulator: the runs' block covariance at 0.5 m/s is singular" in error
    assert error.endswith("raise --n-runs or --keep-s")
    assert (out / "campaign.npz").is_file()  # the campaign is kept for another try


def test_design_figure_title_counts_the_hypercube_and_the_anchor_runs_apart():
    script = load_example("train_emulator")
    args = SimpleNamespace(n_runs=10, anchor_speeds=[1.0, 2.0], anchor_runs=2)
    assert script.design_title(args) == (
        "Latin hypercube design, 10 runs\n+ 2 anchor runs at each of 1, 2 m/s"
    )
    args.anchor_speeds = []
    assert script.design_title(args) == "Latin hypercube design, 10 runs"


@pytest.mark.parametrize(
    "script, seed, message",
    [
        ("ball_drop", 2**128, "--seed must be <= 2**128 - 1 (the seeds' range)"),
        ("posterior_check", 2**128, "--seed must be <= 2**128 - 1 (the seeds' range)"),
        ("train_emulator", 2**128, "--seed must be <= 2**128 - 1 (the seeds' range)"),
        ("shared_theta", 2**128 - 1, "--seed must be <= 2**128 - 2 (the seeds' range)"),
    ],
)
def test_a_seed_beyond_the_libraries_range_is_a_usage_error(
    tmp_path, capsys, script, seed, message
):
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exc:
        load_example(script).main(["--seed", str(seed), "--out", str(out)])
    assert exc.value.code == 2
    assert f"{message}, got {seed}" in capsys.readouterr().err
    assert not out.exists()


def test_an_output_folder_with_a_leading_tilde_is_in_the_home_folder(monkeypatch, tmp_path):
    """`--out=~/runs` (the shell leaves a ~ after = alone) made a folder named "~" in the
    working directory; it is the home folder, as gpmsa's and control's paths read it, and the
    emulators' folder too."""
    home, work = tmp_path / "home", tmp_path / "work"
    home.mkdir(), work.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(work)
    cli = load_example("_cli")
    assert cli.output_folder(argparse.ArgumentParser(), "--out", "~/runs") == home / "runs"
    assert (home / "runs").is_dir() and not (work / "~").exists()
    with pytest.raises(control.ControlError, match="emulator .*home/runs/jackal_A.gpmsa is miss"):
        control.shipped_emulator_path("A", folder="~/runs")


def test_an_output_folder_that_only_starts_with_a_tilde_is_a_folder_of_that_name(
    monkeypatch, tmp_path
):
    """`--out=~runs` raised RuntimeError (Path.expanduser reads "~runs" as user runs's home):
    only "~" and "~/..." are the home folder."""
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.chdir(tmp_path)
    cli = load_example("_cli")
    folder = cli.output_folder(argparse.ArgumentParser(), "--out", "~nosuchuser")
    assert folder.resolve() == tmp_path / "~nosuchuser" and folder.is_dir()
    with pytest.raises(control.ControlError, match="emulator .*~nosuchuser/jackal_A.gpmsa is miss"):
        control.shipped_emulator_path("A", folder="~nosuchuser")


class _ClosedPipe:
    """A stdout whose reader has gone: every write raises BrokenPipeError."""

    def __init__(self, fd: int) -> None:
        self.fd, self.writes = fd, 0

    def write(self, text: str) -> int:
        self.writes += 1
        raise BrokenPipeError(32, "Broken pipe")

    def flush(self) -> None:
        raise BrokenPipeError(32, "Broken pipe")

    def fileno(self) -> int:
        return self.fd


def test_a_script_run_as_a_command_ends_ctrl_c_in_one_line_and_outlives_its_reader(
    monkeypatch, tmp_path, capsys
):
    """Ctrl-C printed a traceback, and a reader that stopped reading (`| head`) ended a script
    at its next print, part-way through its files (train_emulator prints between them)."""
    cli = load_example("_cli")

    def interrupted():
        raise KeyboardInterrupt

    monkeypatch.setattr(sys, "argv", ["closed_loop.py"])
    with pytest.raises(SystemExit) as stop:
        cli.run(interrupted)
    assert stop.value.code == 130
    assert capsys.readouterr().err == "closed_loop.py: interrupted (Ctrl-C)\n"

    done = []

    def prints_then_writes():
        print("a table the reader leaves after")
        print("and more")
        done.append(True)

    fd = os.open(tmp_path / "stdout", os.O_WRONLY | os.O_CREAT)
    pipe = _ClosedPipe(fd)
    monkeypatch.setattr(sys, "stdout", pipe)
    cli.run(prints_then_writes)
    sys.stdout.flush()
    assert done == [True] and pipe.writes == 1  # the first print found the reader gone
    os.close(fd)
