"""``gpmsa info STUDY`` names each model's output index as an emulator file's info does: the
line for a person (several columns always, one column where labelled) and ``--json``'s
``output_index`` record per model."""

from __future__ import annotations

import json

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main

pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")

T = np.linspace(0.1, 0.9, 12)[:, None]
X = np.tile([[0.0], [1.0]], (6, 1))
S = np.linspace(0.0, 1.0, 4)


def _study(tmp_path, **labels):
    sim = gpmsa.SimData(x=X, t=T, y=X + 2 * T * S, t_names=["E"], index=S, **labels)
    plain = gpmsa.SimData(x=X, t=T, y=X + 2 * T, t_names=["E"])  # a scalar output: no index
    obs = [gpmsa.ObsData(x=[[0.5]], y=[0.5 + 0.6 * S]), gpmsa.ObsData(x=[[0.2]], y=[[0.4]])]
    study = gpmsa.fit_study([sim, plain], obs, shared=["E"], n_iter=40, seed=2, tune_rounds=2)
    return str(study.save(tmp_path / "st.gpmsa"))


def test_a_study_names_its_members_output_index(tmp_path, capsys):
    path = _study(tmp_path, index_names="time", index_units="s")
    assert main(["info", path]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    first = next(i for i, line in enumerate(lines) if line.startswith("model "))
    assert lines[first + 1] == "  output index 4 points (time [s]), [0, 1]"
    assert out.count("output index") == 1  # the scalar member has none
    assert main(["info", path, "--json"]) == 0
    models = json.loads(capsys.readouterr().out)["models"]
    assert models[0]["output_index"] == {"points": 4, "columns": 1, "ranges": [[0.0, 1.0]],
                                         "names": ["time"], "units": ["s"]}  # fmt: skip
    assert models[1]["output_index"] is None


def test_an_unlabelled_one_column_index_is_left_out_of_the_lines(tmp_path, capsys):
    path = _study(tmp_path)
    assert main(["info", path]) == 0
    assert "output index" not in capsys.readouterr().out
    assert main(["info", path, "--json"]) == 0
    index = json.loads(capsys.readouterr().out)["models"][0]["output_index"]
    assert index["points"] == 4 and index["names"] is None
