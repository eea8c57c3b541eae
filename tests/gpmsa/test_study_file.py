"""Study files: the study file plus one emulator file per model, listed with their sha256."""

from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main
from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw
from tests.gpmsa._study_cases import emulator, observations


@cache
def _study() -> gpmsa.Study:
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5, 0.6)]
    emu = emulator(None)
    return gpmsa.calibrate_study(
        [emu] * 3, [d[0] for d in data], [d[1] for d in data], labels=["a", "b", "c"],
        hierarchical=["t"], n_samples=300, n_burn=100, seed=5, tune_rounds=5,
        metadata={"what": "test \x1b[31mred\x1b[0m"},
    )  # fmt: skip


def _rewrite(path, edit) -> None:
    """Rewrite a study file with an edited manifest (a consistent rewrite: hash recomputed)."""
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    edit(manifest)
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)


def test_a_study_round_trips(tmp_path):
    study = _study()
    path = study.save(tmp_path / "run.gpmsa")
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "run.a.gpmsa", "run.b.gpmsa", "run.c.gpmsa", "run.gpmsa"]  # fmt: skip
    back = gpmsa.load_study(path)
    assert back.kind == "calibration" and back.labels == ("a", "b", "c")
    assert back.layout == study.layout and back.hyper == study.hyper
    for k, v in study.draws.items():
        assert np.array_equal(back.draws[k], v), k
    assert back.posterior.names == study.posterior.names
    assert back.posterior.mean("t.mu") == study.posterior.mean("t.mu")
    assert back.metadata == study.metadata
    for a, b in zip(back.members, study.members, strict=True):
        assert np.array_equal(a.params["betaU"], b.params["betaU"])
    with pytest.raises(gpmsa.EmulatorFileError, match="format is 'gpmsa-study'"):
        gpmsa.load(path)  # a study is not an emulator


def test_a_joint_fit_study_round_trips(tmp_path):
    rng = np.random.default_rng(1)
    from tests.gpmsa._study_cases import sim_data

    x, y = observations(0.4, 3, 0.03, rng)
    obs = gpmsa.ObsData(x=x, y=y)
    study = gpmsa.fit_study([sim_data(), sim_data()], [obs, obs], shared=["t"], n_iter=200,
                            seed=1, tune_rounds=3)  # fmt: skip
    back = gpmsa.load_study(study.save(tmp_path / "fit.gpmsa"))
    assert back.kind == "fit"
    cal = back.members[1].calibration["theta"]
    assert np.array_equal(cal, study.members[1].calibration["theta"])
    assert np.array_equal(back.posterior.samples["t"], study.posterior.samples["t"])


def test_an_edited_member_is_refused(tmp_path):
    path = _study().save(tmp_path / "run.gpmsa")
    other = emulator(None)
    edited = gpmsa.Emulator.from_params(  # same data, another point estimate
        gpmsa.SimData(x=other.x_unit, t=other.t_unit, y=other.y, t_names=["t"]),
        {**other.params, "lamUz": [2.0]},
    )  # fmt: skip
    edited.save(tmp_path / "run.b.gpmsa")
    with pytest.raises(gpmsa.EmulatorFileError, match=r"study.models\[1\] \(b\).*sha256"):
        gpmsa.load_study(path)
    (tmp_path / "run.c.gpmsa").unlink()
    with pytest.raises(gpmsa.EmulatorFileError, match=r"study.models\[1\]"):
        gpmsa.load_study(path)


def test_a_missing_member_is_refused(tmp_path):
    path = _study().save(tmp_path / "run.gpmsa")
    (tmp_path / "run.c.gpmsa").unlink()
    with pytest.raises(gpmsa.EmulatorFileError, match=r"study.models\[2\] \(c\)"):
        gpmsa.load_study(path)


FILE0 = r"study.models\[0\].file"


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda m: m["study"]["models"][0].update(file="../run.a.gpmsa"), FILE0),
        (lambda m: m["study"]["models"][0].update(file="/etc/run.gpmsa"), FILE0),
        (lambda m: m["study"]["models"][2].update(sha256="0" * 63), r"study.models\[2\].sha256"),
        (lambda m: m["study"]["models"][1].update(label="a"), "labels repeat"),
        (lambda m: m["study"].update(kind="magic"), "study.kind"),
        (lambda m: m["study"].update(hierarchical=[]), "arrays/mu"),
        (lambda m: m["study"].update(shared=["t"], hierarchical=[]), "arrays/mu"),
        (lambda m: m["names"].update(elements=["x", "y", "z"]), "names.elements"),
        (lambda m: m["priors"]["hyper"].update(lam_b=-1), "priors.hyper.lam_b"),
        (lambda m: m["priors"]["hyper"].update(sd_prior="flat"), "priors.hyper.sd_prior"),
        (lambda m: m["priors"]["hyper"].update(sd_max=0.1), "HyperPriors.lam_start"),
        (lambda m: m["priors"]["hyper"].update(__class__=1), "priors.hyper: unknown keys"),
        (lambda m: m.pop("study"), "study: must be an object"),
    ],
)
def test_an_edited_study_manifest_is_refused_naming_the_field(tmp_path, edit, field):
    path = _study().save(tmp_path / "run.gpmsa")
    _rewrite(path, edit)
    with pytest.raises(gpmsa.EmulatorFileError, match=field):
        gpmsa.load_study(path)


def test_a_study_saved_before_the_spread_prior_key_reads_as_sepias(tmp_path):
    """Study files written before ``sd_prior`` existed had SEPIA's Gamma prior on lam."""
    path = _study().save(tmp_path / "run.gpmsa")
    _rewrite(path, lambda m: [m["priors"]["hyper"].pop(k) for k in ("sd_prior", "sd_max")])
    assert gpmsa.load_study(path).hyper == gpmsa.HyperPriors.sepia()


def test_edited_bytes_are_refused(tmp_path):
    path = _study().save(tmp_path / "run.gpmsa")
    raw = bytearray(path.read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    path.write_bytes(bytes(raw))
    with pytest.raises(gpmsa.EmulatorFileError):
        gpmsa.load_study(path)


def test_gpmsa_info_describes_a_study(tmp_path, capsys):
    path = _study().save(tmp_path / "run.gpmsa")
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "study:           calibration of 3 models; shared [], hierarchical [t]" in out
    assert "model b: file run.b.gpmsa sha256" in out and "(verified)" in out
    assert "posterior t.mu: mean" in out and "posterior lamOs[c]" in out
    assert "sd = 1/sqrt(lam) ~ Uniform(0, 1)" in out and "\x1b" not in out and "\\u001b[31m" in out
    assert main(["info", "--json", str(path)]) == 0
    assert '"gpmsa-study"' in capsys.readouterr().out
    emulator(None).save(tmp_path / "run.a.gpmsa")  # not the file the study lists
    gpmsa.Emulator.from_params(
        gpmsa.SimData(x=emulator(None).x_unit, t=emulator(None).t_unit, y=emulator(None).y,
                      t_names=["t"]), {**emulator(None).params, "lamUz": [3.0]},
    ).save(tmp_path / "run.a.gpmsa")  # fmt: skip
    assert main(["info", str(path)]) == 2
    assert "sha256" in capsys.readouterr().err


def test_a_study_saved_and_loaded_through_a_link_keeps_its_members_beside_the_file(tmp_path):
    """A symbolic link to a study file: the models' files lie beside the file it points to (a
    save through the link writes them there, named after it; a load reads them there)."""
    store, elsewhere = tmp_path / "store", tmp_path / "elsewhere"
    store.mkdir(), elsewhere.mkdir()
    study = _study()
    study.save(store / "run.gpmsa")
    link = elsewhere / "link.gpmsa"
    link.symlink_to(store / "run.gpmsa")
    assert gpmsa.load_study(link).labels == ("a", "b", "c")
    assert study.save(link) == link
    assert sorted(p.name for p in elsewhere.iterdir()) == ["link.gpmsa"]
    assert sorted(p.name for p in store.iterdir()) == [
        "run.a.gpmsa", "run.b.gpmsa", "run.c.gpmsa", "run.gpmsa"]  # fmt: skip
    assert gpmsa.load_study(store / "run.gpmsa").labels == ("a", "b", "c")


def test_gpmsa_info_says_a_held_parameter_is_held(tmp_path, capsys):
    """A study with fixed={"lamOs": 1.0} printed "lamOs[a]: mean 1 sd 0 ... ESS nan R-hat nan";
    it says the value is held. A hostile "held" list does not make a sampled name read so."""
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5)]
    study = gpmsa.calibrate_study(
        [emulator(None)] * 2, [d[0] for d in data], [d[1] for d in data], labels=["a", "b"],
        n_samples=60, n_burn=20, tune=False, seed=0, fixed={"lamOs": 1.0},
    )  # fmt: skip
    path = study.save(tmp_path / "held.gpmsa")
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "posterior lamOs[a]: held at 1 (fixed=)" in out and "nan" not in out
    _rewrite(path, lambda m: m["settings"].update(held=["t[a]", 5]))
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "posterior t[a]: mean" in out and "lamOs[a]: mean 1 sd 0" in out


def test_load_study_checks_the_expected_sha256_as_load_does(tmp_path):
    """gpmsa.load(path, sha256=) refuses a file other than the one its author vouched for;
    load_study had no such argument. The study file lists its models' digests, so its own
    vouches for all of them."""
    path = _study().save(tmp_path / "run.gpmsa")
    digest = read_raw(path, lambda m: None, formats=(STUDY_FORMAT,))[0]["content_sha256"]
    assert gpmsa.load_study(path, sha256=" " + digest.upper()).labels == ("a", "b", "c")
    with pytest.raises(gpmsa.EmulatorFileError, match="differs from the expected"):
        gpmsa.load_study(path, sha256="0" * 64)
    with pytest.raises(gpmsa.GPMSAError, match="sha256 must be 64 hexadecimal digits"):
        gpmsa.load_study(path, sha256="abc")
