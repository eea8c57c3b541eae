"""Review of session 76's one-chain convergence check, grid Calibrator draw pairing and dask
worker check: calibrate's private ``_online`` is not a Calibrator mcmc_options keyword; the
workers a ``get_executor(workers=...)`` may use are read as dask reads a tuple or a number;
``gpmsa info`` of a ``from_params`` file does not say it predates the check; one chain's
constant-draws note speaks of one chain."""

import warnings

import numpy as np
import pytest
from _calib_cases import one_t_emulator

import gpmsa
from gpmsa.mcmc import parallel
from gpmsa.mcmc.diagnostics import convergence, warn_unconverged
from tests._extras import DISTRIBUTED


def test_calibrator_mcmc_options_neither_list_nor_take_calibrates_private_online():
    emu, _, _ = one_t_emulator()
    with pytest.raises(gpmsa.GPMSAError, match="unknown keyword") as err:
        gpmsa.Calibrator(emu, method="mcmc", mcmc_options={"bogus": 1})
    assert "_online" not in str(err.value)  # before: listed among calibrate's keywords
    # before: accepted here, then a TypeError (multiple values for '_online') at update()
    with pytest.raises(gpmsa.GPMSAError, match=r"unknown keyword\(s\) \['_online'\]"):
        gpmsa.Calibrator(emu, method="mcmc", mcmc_options={"_online": False})


INFOS = {
    "tcp://10.0.0.1:1": {"name": 0, "host": "10.0.0.1"},
    "tcp://10.0.0.1:2": {"name": 1, "host": "10.0.0.1"},
    "tcp://10.0.0.2:1": {"name": "c", "host": "10.0.0.2"},
}


@DISTRIBUTED  # dask's own reading of an address
def test_task_workers_read_a_tuple_of_workers_and_a_bare_number_as_dask_does():
    workers = parallel._task_workers
    # Client.submit passes a tuple on as a collection (the scheduler iterates it): before, it
    # was read as one (host, port) pair, matched no worker, and the check was skipped
    both = ("tcp://10.0.0.1:2", "tcp://10.0.0.2:1")
    assert workers(INFOS, {"workers": both}) == ["tcp://10.0.0.1:2", "tcp://10.0.0.2:1"]
    assert workers(INFOS, {"workers": (1, "c")}) == ["tcp://10.0.0.1:2", "tcp://10.0.0.2:1"]
    # a bare number is one worker name (Client.submit wraps str and Number); before: TypeError
    assert workers(INFOS, {"workers": 1}) == ["tcp://10.0.0.1:2"]
    assert workers(INFOS, {"workers": [("10.0.0.1", 2)]}) == ["tcp://10.0.0.1:2"]  # unchanged
    assert workers(INFOS, {"workers": [5]}) == []  # no such name: no worker, not a TypeError


def _older_on_1(module, dask_worker):
    return None, "0.0.9" if dask_worker.name == 1 else gpmsa.__version__


def _double(x, progress=False, desc=""):
    return 2 * x


def test_a_tuple_restricted_executor_has_its_workers_checked(dask_client, monkeypatch):
    one = next(a for a, i in dask_client.scheduler_info(n_workers=-1)["workers"].items()
               if i["name"] == 1)  # fmt: skip
    monkeypatch.setattr(parallel, "_worker_report", _older_on_1)
    executor = dask_client.get_executor(workers=(one,))  # before: ran on gpmsa 0.0.9
    with pytest.raises(gpmsa.GPMSAError, match=f"gpmsa 0.0.9 on {one}"):
        parallel.run_chains(_double, [{"x": 1}, {"x": 2}], executor=executor)
    with pytest.raises(gpmsa.GPMSAError, match=f"gpmsa 0.0.9 on {one}"):
        parallel.as_executor(dask_client.get_executor(workers=1), _double)  # before: TypeError


def test_info_of_a_from_params_file_does_not_say_it_predates_the_check(tmp_path, capsys):
    from gpmsa.cli.main import main

    emu, _, _ = one_t_emulator()
    path = emu.save(tmp_path / "fp.gpmsa")
    capsys.readouterr()
    assert main(["info", str(path)]) == 0
    line = next(ln for ln in capsys.readouterr().out.splitlines()
                if ln.startswith("convergence:"))  # fmt: skip
    assert "from before the check" not in line and "from_params" in line


def test_one_chains_constant_draws_note_speaks_of_one_chain():
    draws = np.full((1, 50), 2.0)
    diag = {"t0": {"rhat": [float("nan")], "ess": [float("nan")]}}
    rec = convergence(diag, {"t0": ()}, 1, draws.shape[1])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warn_unconverged(rec, "gpmsa.calibrate", length="n_samples")
    (text,) = [str(w.message) for w in caught]
    assert "constant draws" in text and "1 chain x 50 draws" in text
    assert "every chain" not in text and "Constant draws in the chain" in text
    rec = convergence(diag, {"t0": ()}, 2, draws.shape[1])  # several chains: as before
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warn_unconverged(rec, "gpmsa.calibrate", length="n_samples")
    assert "Constant draws in every chain" in str(caught[0].message)
