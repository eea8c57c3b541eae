"""The emulator file: exact round trip, and every kind of damage refused with EmulatorFileError."""

import io
import json
import zipfile

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import gpmsa
from gpmsa.cli.main import main
from gpmsa.io import container


@pytest.fixture(scope="module")
def emu():
    rng = np.random.default_rng(0)
    x, t = rng.random((25, 1)) * 2, 200 + 400 * rng.random((25, 1))
    sim = gpmsa.SimData(x=x, t=t, y=0.02 * t * x**1.6, x_names=["v"], t_names=["GD"],
                        x_units=["m/s"], t_units=["1e-6 m^3"], y_units=["m/s^2"])  # fmt: skip
    return gpmsa.fit(sim, n_iter=120, seed=1, tune=False,
                     metadata={"vehicle": "jackal", "noise": 0.05, "tags": ["a", 1]})  # fmt: skip


@pytest.fixture(scope="module")
def saved(emu, tmp_path_factory):
    path = tmp_path_factory.mktemp("emu") / "model.gpmsa"
    emu.save(path)
    return path


def test_save_into_a_missing_folder_or_to_no_path_names_the_problem(emu, tmp_path):
    target = tmp_path / "missing" / "model.gpmsa"
    with pytest.raises(gpmsa.GPMSAError, match=r"model.gpmsa: cannot write \(No such file"):
        emu.save(target)
    assert not target.parent.exists()
    for bad in (None, 5, ""):
        with pytest.raises(gpmsa.GPMSAError, match="path must be a file name"):
            emu.save(bad)
    folder = f"{tmp_path / 'out'}/"  # Path("out/") is "out": a file named out was written
    with pytest.raises(gpmsa.GPMSAError, match="ends with a separator: it names a folder"):
        emu.save(folder)
    assert not (tmp_path / "out").exists()


def test_round_trip_is_exact(emu, saved):
    back = gpmsa.load(saved)
    x, t = np.array([[0.3], [1.1], [1.9]]), np.array([[250.0], [420.0], [590.0]])
    for kw in ({}, {"draws": True, "n_draws": 10}, {"resid": False}):
        with pytest.warns(UserWarning, match="extrapolates"):  # v = 0.3 is below the design
            m1, v1 = emu.predict(x, t, **kw)
        with pytest.warns(UserWarning, match="extrapolates"):
            m2, v2 = back.predict(x, t, **kw)
        assert np.array_equal(m1, m2) and np.array_equal(v1, v2)
    assert back.metadata == {"vehicle": "jackal", "noise": 0.05, "tags": ["a", 1]}
    assert back.x_names == ("v",) and back.t_units == ("1e-6 m^3",)
    assert back.domain == emu.domain and back.priors == emu.priors
    assert back.settings["n_iter"] == 120 and back.settings["seed"] == 1
    for k in emu.draws:
        assert np.array_equal(back.draws[k], emu.draws[k])
    assert np.array_equal(back.loo().z, emu.loo().z)


def test_manifest_contents(saved):
    with zipfile.ZipFile(saved) as zf:
        manifest = json.loads(zf.read("manifest.json"))
    assert manifest["format"] == "gpmsa-emulator" and manifest["schema_version"] == 1
    assert manifest["library_version"] == gpmsa.__version__
    assert manifest["arrays"]["x_unit"] == {"shape": [25, 1], "dtype": "<f8"}
    assert manifest["domain"]["GD"][0] >= 200 and len(manifest["content_sha256"]) == 64
    assert manifest["priors"]["lamWs"]["lower"] == 60.0
    assert sorted(manifest) == sorted(
        ["format", "schema_version", "library_version", "created_utc", "names", "units", "domain",
         "model", "priors", "settings", "metadata", "diagnostics", "arrays", "content_sha256",
         "convergence"]  # one chain judged too since session 76
    )  # fmt: skip
    assert manifest["convergence"]["n_chains"] == 1


def test_record_round_trip_through_the_container(emu, tmp_path):
    """The container moves the Emulator's record untouched and adds only its envelope."""
    manifest, arrays = emu.to_record()
    path = container.write_raw(tmp_path / "raw.gpmsa", manifest, arrays)
    back_manifest, back_arrays = container.read_raw(path)
    assert set(back_manifest) == set(manifest) | set(container.ENVELOPE)
    assert {k: back_manifest[k] for k in manifest} == manifest
    assert sorted(back_arrays) == sorted(arrays)
    back = gpmsa.Emulator.from_record(back_manifest, back_arrays)
    x, t = np.array([[1.0]]), np.array([[400.0]])
    assert np.array_equal(back.predict(x, t)[0], emu.predict(x, t)[0])
    with pytest.raises(gpmsa.GPMSAError, match=r"\['format'\] are written by the container"):
        container.write_raw(tmp_path / "bad.gpmsa", {**manifest, "format": "x"}, arrays)
    with pytest.raises(gpmsa.GPMSAError, match="array 'a b'"):
        container.write_raw(tmp_path / "bad.gpmsa", manifest, {"a b": np.zeros(1)})


def rewrite(src, dst, *, manifest=None, rehash=True, extra=None, drop=()):
    """Copy a file changing its manifest (recomputing the hash) or members."""
    with zipfile.ZipFile(src) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    man = json.loads(members["manifest.json"])
    if manifest:
        manifest(man)
    if rehash:
        arrays = {n[7:-4]: np.load(io.BytesIO(b), allow_pickle=True) for n, b in members.items()
                  if n.endswith(".npy") and n not in drop}  # fmt: skip
        for name, raw in (extra or {}).items():
            if name.endswith(".npy"):
                arrays[name[7:-4]] = np.load(io.BytesIO(raw), allow_pickle=True)
        man["content_sha256"] = container.content_hash(arrays, man)
    members["manifest.json"] = json.dumps(man).encode()
    members.update(extra or {})
    with zipfile.ZipFile(dst, "w") as zf:
        for n, b in members.items():
            if n not in drop:
                zf.writestr(n, b)
    return dst


def test_newer_schema_refused(saved, tmp_path):
    def bump(m):
        m["schema_version"] = 2

    path = rewrite(saved, tmp_path / "new.gpmsa", manifest=bump)
    with pytest.raises(gpmsa.EmulatorFileError, match="schema_version 2 is newer"):
        gpmsa.load(path)


def test_foreign_files_refused(tmp_path):
    plain = tmp_path / "notes.gpmsa"
    plain.write_text("hello")
    with pytest.raises(gpmsa.EmulatorFileError, match="not a readable zip"):
        gpmsa.load(plain)
    other = tmp_path / "other.gpmsa"
    with zipfile.ZipFile(other, "w") as zf:
        zf.writestr("manifest.json", json.dumps({"format": "something-else"}))
    with pytest.raises(gpmsa.EmulatorFileError, match="foreign file"):
        gpmsa.load(other)
    with pytest.raises(gpmsa.EmulatorFileError, match="cannot read"):
        gpmsa.load(tmp_path / "missing.gpmsa")


def test_edited_array_or_manifest_detected_by_hash(saved, tmp_path):
    def meta(m):
        m["metadata"]["vehicle"] = "husky"

    path = rewrite(saved, tmp_path / "edit.gpmsa", manifest=meta, rehash=False)
    with pytest.raises(gpmsa.EmulatorFileError, match="content hash mismatch"):
        gpmsa.load(path)
    buf = io.BytesIO()
    np.save(buf, np.full(1, 2.0))
    path = rewrite(
        saved, tmp_path / "arr.gpmsa", rehash=False, extra={"arrays/y_sd.npy": buf.getvalue()}
    )
    with pytest.raises(gpmsa.EmulatorFileError, match="content hash mismatch"):
        gpmsa.load(path)


def test_pickled_object_array_is_refused_without_unpickling(saved, tmp_path):
    buf = io.BytesIO()
    np.save(buf, np.array([{"evil": 1}], dtype=object), allow_pickle=True)

    def declare(m):
        m["arrays"]["payload"] = {"shape": [1], "dtype": "|O"}

    path = rewrite(saved, tmp_path / "pickle.gpmsa", manifest=declare,
                   extra={"arrays/payload.npy": buf.getvalue()})  # fmt: skip
    with pytest.raises(gpmsa.EmulatorFileError, match=r"array 'payload' has dtype \|O"):
        gpmsa.load(path)


def test_path_tricks_and_unlisted_members_refused(saved, tmp_path):
    for name in ("../evil.npy", "arrays/../../x.npy", "/abs.npy", "arrays/a b.npy", "run.py"):
        path = rewrite(saved, tmp_path / "trick.gpmsa", rehash=False, extra={name: b"x"})
        with pytest.raises(gpmsa.EmulatorFileError, match="unexpected member"):
            gpmsa.load(path)
    path = rewrite(saved, tmp_path / "drop.gpmsa", drop=("arrays/w.npy",))
    with pytest.raises(gpmsa.EmulatorFileError, match=r"missing \['w'\]"):
        gpmsa.load(path)


def test_zip_bomb_refused(saved, tmp_path):
    path = tmp_path / "bomb.gpmsa"
    with zipfile.ZipFile(saved) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for n, b in members.items():
            zf.writestr(n, b)
        zf.writestr("arrays/zeros.npy", b"\0" * 50_000_000)
    with pytest.raises(gpmsa.EmulatorFileError, match="zip bomb"):
        gpmsa.load(path)


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(frac=st.floats(0.0, 0.999))
def test_truncated_file_refused(saved, tmp_path, frac):
    data = saved.read_bytes()
    path = tmp_path / "cut.gpmsa"
    path.write_bytes(data[: int(len(data) * frac)])
    with pytest.raises(gpmsa.EmulatorFileError):
        gpmsa.load(path)


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(pos=st.floats(0.0, 0.9999), flip=st.integers(1, 255))
def test_flipped_byte_refused_or_identical(emu, saved, tmp_path, pos, flip):
    data = bytearray(saved.read_bytes())
    i = int(len(data) * pos)
    data[i] ^= flip
    path = tmp_path / "flip.gpmsa"
    path.write_bytes(bytes(data))
    try:
        back = gpmsa.load(path)
    except gpmsa.EmulatorFileError:
        return
    # a flip in bytes no reader looks at (zip comments, padding, timestamps) changes nothing
    x, t = np.array([[1.0]]), np.array([[400.0]])
    assert np.array_equal(back.predict(x, t)[0], emu.predict(x, t)[0])


KEYS = ["format", "schema_version", "arrays", "names", "priors", "settings", "metadata",
        "content_sha256", "domain", "units"]  # fmt: skip
VALUES = st.one_of(
    st.none(),
    st.integers(-3, 3),
    st.text(max_size=5),
    st.lists(st.integers(), max_size=2),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
)


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(key=st.sampled_from(KEYS), value=VALUES, rehash=st.booleans())
def test_edited_manifest_refused(emu, saved, tmp_path, key, value, rehash):
    """Without a matching hash any edit is refused; with a recomputed hash (the hash is no
    signature) the reader still refuses inconsistent content and otherwise predicts as before."""

    def edit(m):
        assume(m[key] != value)  # a no-op edit is no damage
        m[key] = value

    rehash = rehash and key != "content_sha256"
    path = rewrite(saved, tmp_path / "man.gpmsa", manifest=edit, rehash=rehash)
    if not rehash:
        with pytest.raises(gpmsa.EmulatorFileError):
            gpmsa.load(path)
        return
    try:
        back = gpmsa.load(path)
    except gpmsa.EmulatorFileError:
        return
    assert key in ("settings", "metadata")
    x, t = np.array([[1.0]]), np.array([[400.0]])
    assert np.array_equal(back.predict(x, t)[0], emu.predict(x, t)[0])


def test_metadata_must_be_jsonable(emu, tmp_path):
    emu2 = gpmsa.load(emu.save(tmp_path / "a.gpmsa"))
    emu2.metadata["bad"] = object()
    with pytest.raises(gpmsa.GPMSAError, match="metadata must be JSON-able"):
        emu2.save(tmp_path / "b.gpmsa")


def test_long_double_metadata_is_refused_by_name_not_by_recursion(emu, tmp_path):
    """A np.longdouble passed the metadata check and then recursed without end in the writer
    (RecursionError): its .item() is itself, not a Python float."""
    value = np.longdouble(1.5)
    if value.dtype.itemsize <= 8:  # where long double is float64 it is a plain float64
        pytest.skip("long double is float64 here")
    with pytest.raises(gpmsa.GPMSAError, match=r"metadata\['a'\]\[0\]: a float.* float\(\)"):
        gpmsa.Emulator.from_params(
            gpmsa.SimData(x=emu.x_unit, t=emu.t_unit, y=emu.y), emu.params, metadata={"a": [value]}
        )
    emu2 = gpmsa.load(emu.save(tmp_path / "a.gpmsa"))
    emu2.metadata["a"] = value
    with pytest.raises(gpmsa.GPMSAError, match=r"metadata\['a'\]: a float"):
        emu2.save(tmp_path / "b.gpmsa")
    assert not (tmp_path / "b.gpmsa").exists()


def test_cli_info_prints_manifest(saved, capsys, tmp_path):
    assert main(["info", str(saved)]) == 0
    out = capsys.readouterr().out
    assert "gpmsa-emulator schema 1" in out and "GD [1e-6 m^3]" in out and '"jackal"' in out
    assert "(verified)" in out and "n_iter=120" in out
    assert main(["info", "--json", str(saved)]) == 0
    assert json.loads(capsys.readouterr().out)["metadata"]["vehicle"] == "jackal"
    bad = tmp_path / "bad.gpmsa"
    bad.write_bytes(b"PK\x03\x04junk")
    assert main(["info", str(bad)]) == 2
    assert "not a readable zip" in capsys.readouterr().err


def test_a_path_that_starts_with_a_tilde_is_the_home_folder(tmp_path, monkeypatch):
    """save("~/a.gpmsa") raised "No such file or directory" (a folder named "~" in the working
    directory); a leading ~ is the home folder, as the shell reads it, for load and info too."""
    monkeypatch.setenv("HOME", str(tmp_path))
    monkeypatch.chdir(tmp_path)
    emu = gpmsa.Emulator.from_params(
        gpmsa.SimData(x=np.linspace(0, 1, 6), t=np.linspace(1, 0, 6) ** 2, y=np.arange(6.0)),
        {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]},
    )
    assert emu.save("~/a.gpmsa") == tmp_path / "a.gpmsa"
    assert gpmsa.load("~/a.gpmsa").model_sha256 == emu.model_sha256
    assert main(["info", "~/a.gpmsa"]) == 0


def test_a_name_that_only_starts_with_a_tilde_is_a_file_of_that_name(tmp_path, monkeypatch):
    """save("~x.gpmsa") raised RuntimeError "Could not determine home directory" (Path.expanduser
    reads "~x" as user x's home) and gpmsa info called it an internal error; only "~" and
    "~/..." are the home folder, as the shell reads them."""
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.chdir(tmp_path)
    emu = gpmsa.Emulator.from_params(
        gpmsa.SimData(x=np.linspace(0, 1, 6), t=np.linspace(1, 0, 6) ** 2, y=np.arange(6.0)),
        {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]},
    )
    assert emu.save("~nosuchuser.gpmsa").resolve() == tmp_path / "~nosuchuser.gpmsa"
    assert gpmsa.load("~nosuchuser.gpmsa").model_sha256 == emu.model_sha256
    assert main(["info", "~nosuchuser.gpmsa"]) == 0
