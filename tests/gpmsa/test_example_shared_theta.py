"""examples/shared_theta.py: its physics, and the worked example end to end."""

import json

import numpy as np

from tests._examples import load_example


def load_script():
    return load_example("shared_theta")


def test_physics():
    st = load_script()
    # deflection: linear in P, inverse in E; aluminium beam, 20 N: about 4.8 mm
    assert np.isclose(st.deflection(20.0, 69.0), 20 * 0.5**3 / (3 * 69e9 * st.INERTIA) * 1e3)
    assert np.isclose(st.deflection(40.0, 69.0), 2 * st.deflection(20.0, 69.0))
    # frequency depends on E / rho only
    assert np.isclose(st.frequency(0.5, 69.0, 2700.0), st.frequency(0.5, 138.0, 5400.0))
    static, modal = st.simulations(24, 40, 0)
    assert static.t.min() == modal.t[:, 0].min() == 50.0  # the shared E spans one range
    assert np.isclose(static.t.max(), 90.0) and np.isclose(modal.t[:, 0].max(), 90.0)


def test_the_example_runs_and_sharing_pins_the_density(tmp_path, capsys):
    st = load_script()
    summary = st.main(["--out", str(tmp_path), "--n-iter", "800"])
    assert "shared (emulators fixed)" in capsys.readouterr().out
    for name in (
        "posterior_E_rho.png",
        "pairs_E_rho.png",
        "traces.png",
        "summary.json",
        "beam_study.gpmsa",
        "beam_study.static.gpmsa",
        "beam_study.modal.gpmsa",
    ):
        assert (tmp_path / name).stat().st_size > 0, name
    post = json.loads((tmp_path / "summary.json").read_text())["posterior"]
    assert post == json.loads(json.dumps(summary["posterior"]))
    for label in ("shared (emulators fixed)", "shared (joint fit)"):
        for name, truth in st.TRUTH.items():
            rec = post[label][name]
            assert rec["q05"] - rec["sd"] < truth < rec["q95"] + rec["sd"], (label, name)
        # the modal test alone cannot separate rho from E; with E shared it can
        assert post[label]["rho"]["sd"] < 0.5 * post["modal alone"]["rho"]["sd"]
