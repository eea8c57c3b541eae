"""A study file's manifest describes its content (names, units, kind, settings):
``gpmsa.load_study`` and ``gpmsa info`` refuse a file whose manifest claims something its draws
and models do not hold, rather than report the claim; convergence is computed from the draws."""

from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main
from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw
from tests.gpmsa._study_cases import emulator, observations


@cache
def _study() -> gpmsa.Study:
    """Two models sharing t, two chains (so the file has a convergence record)."""
    rng = np.random.default_rng(3)
    data = [observations(0.4, 4, 0.05, rng) for _ in range(2)]
    return gpmsa.calibrate_study(
        [emulator(None)] * 2, [d[0] for d in data], [d[1] for d in data], labels=["a", "b"],
        shared=["t"], n_samples=120, n_burn=20, n_chains=2, seed=2, tune_rounds=5,
    )  # fmt: skip


def _rewrite(path, edit) -> None:
    """Rewrite a study file with an edited manifest (a consistent rewrite: hash recomputed)."""
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    edit(manifest)
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)


def _claim_converged(m: dict) -> None:
    m["convergence"].update(flagged={}, converged=True, max_rhat=["t", 1.0])


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda m: m["names"].update(models=["b", "a"]), "names.models"),
        (lambda m: m["names"]["t"].update(a=["E"]), "names.t"),
        (lambda m: m["names"].update(t={"a": ["t"]}), "names.t"),
        (lambda m: m["units"].update(b=["GPa"]), "units"),
        (lambda m: m["study"].update(kind="fit"), "study.kind"),
        (lambda m: m["settings"].update(n_chains=7), "settings.n_chains"),
        (lambda m: m["settings"].update(n_iter=10**6, n_samples=10**6), "settings"),
    ],
)
def test_a_manifest_claim_its_content_does_not_hold_is_refused(tmp_path, edit, field):
    path = _study().save(tmp_path / "run.gpmsa")
    _rewrite(path, edit)
    with pytest.raises(gpmsa.EmulatorFileError, match=field):
        gpmsa.load_study(path)


def test_gpmsa_info_never_reports_a_convergence_the_draws_do_not_have(tmp_path, capsys):
    """The draws (2 chains x 100) are not converged: info says so from the draws, also when the
    manifest's convergence record claims they are (info printed the record)."""
    study = _study()
    assert study.convergence["flagged"], "the case needs draws that are not converged"
    path = study.save(tmp_path / "run.gpmsa")
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "NOT converged" in out and "2 chains x 100 draws" in out
    _rewrite(path, _claim_converged)
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "NOT converged" in out and "2 chains x 100 draws" in out
    assert gpmsa.load_study(path).convergence == study.convergence


def test_genuine_studies_of_both_kinds_still_load(tmp_path):
    """The checks hold for what calibrate_study and fit_study write (one chain and several)."""
    from tests.gpmsa._study_cases import sim_data

    path = _study().save(tmp_path / "cal.gpmsa")
    assert gpmsa.load_study(path).convergence == _study().convergence
    x, y = observations(0.4, 3, 0.03, np.random.default_rng(1))
    obs = gpmsa.ObsData(x=x, y=y)
    for n_chains in (1, 2):
        fit = gpmsa.fit_study([sim_data(), sim_data()], [obs, obs], shared=["t"], n_iter=120,
                              n_keep=50, n_chains=n_chains, seed=1, tune_rounds=3)  # fmt: skip
        back = gpmsa.load_study(fit.save(tmp_path / f"fit{n_chains}.gpmsa"))
        assert back.kind == "fit" and back.convergence == fit.convergence


def test_a_fit_studys_kind_and_members_are_checked(tmp_path):
    """kind "fit" if and only if each model file is that study's fitted member, its theta draws
    the study's."""
    from tests.gpmsa._study_cases import sim_data

    x, y = observations(0.4, 3, 0.03, np.random.default_rng(1))
    obs = gpmsa.ObsData(x=x, y=y)
    fit = gpmsa.fit_study([sim_data(), sim_data()], [obs, obs], labels=["a", "b"], n_iter=120,
                          seed=1, tune_rounds=3)  # fmt: skip
    path = fit.save(tmp_path / "fit.gpmsa")
    _rewrite(path, lambda m: None)  # untouched: loads
    gpmsa.load_study(path)
    _rewrite(path, lambda m: m["study"].update(kind="calibration"))  # emulators fixed: no
    with pytest.raises(gpmsa.EmulatorFileError, match="study.kind: 'calibration'"):
        gpmsa.load_study(path)
    _rewrite(path, lambda m: m["study"].update(kind="fit"))

    # the same study's files with the models' labels swapped in the study file
    def swap(m):
        a, b = m["study"]["models"]
        m["study"]["models"] = [{**a, "file": b["file"], "sha256": b["sha256"]},
                                {**b, "file": a["file"], "sha256": a["sha256"]}]  # fmt: skip

    _rewrite(path, swap)
    with pytest.raises(gpmsa.EmulatorFileError, match="study.kind"):
        gpmsa.load_study(path)
