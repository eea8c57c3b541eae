"""The emulator file against hostile and edited content (issue 15, section 3).

The content hash is no signature: an attacker edits a file and recomputes it. Such files must
either load as a valid emulator or raise EmulatorFileError naming the field, never another
exception; the writer never writes what the reader refuses; non-regular files and oversized
content are refused before anything is decompressed; ``gpmsa info`` never crashes and prints
no terminal escape codes from the file.
"""

import io
import json
import os
import re
import signal
import stat
import sys
import warnings
import zipfile
from contextlib import contextmanager

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import gpmsa
from gpmsa.cli.main import main
from gpmsa.cli.text import safe
from gpmsa.io import container
from gpmsa.model.data import RESERVED_NAMES
from tests.gpmsa._emulator_edit import replaced

FIELD = re.compile(
    r"(arrays/\w+|arrays:|array '\w+'|priors|names|units|domain|settings|model|metadata|"
    r"diagnostics|content hash|manifest|member|schema_version|format)"
)
"""An error names the field (or the member) it is about."""


@pytest.fixture(scope="module")
def emu():
    rng = np.random.default_rng(0)
    x, t = 0.5 + 1.5 * rng.random((16, 1)), 200 + 400 * rng.random((16, 1))
    sim = gpmsa.SimData(x=x, t=t, y=0.02 * t * x**1.6, x_names=["v"], t_names=["GD"])
    return gpmsa.fit(sim, n_iter=60, seed=1, tune=False, metadata={"vehicle": "jackal"})


@pytest.fixture(scope="module")
def vec_emu():
    rng = np.random.default_rng(1)
    x, t = rng.random((14, 1)), rng.random((14, 1))
    grid = np.linspace(0, 1, 6)
    y = (1 + t) * np.sin(np.pi * grid * (0.5 + x)) + 0.3 * t
    sim = gpmsa.SimData(x=x, t=t, y=y, index=grid)
    params = {"betaU": [[1.0, 1.0], [1.0, 1.0]], "lamUz": [1.0, 1.0], "lamWs": [5000.0, 5000.0],
              "lamWOs": [5000.0]}  # fmt: skip
    return gpmsa.Emulator.from_params(sim, params, n_pc=2)


@pytest.fixture(scope="module")
def saved(emu, vec_emu, tmp_path_factory):
    folder = tmp_path_factory.mktemp("hostile")
    return {"scalar": emu.save(folder / "s.gpmsa"), "vector": vec_emu.save(folder / "v.gpmsa")}


def read_members(path):
    with zipfile.ZipFile(path) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    manifest = json.loads(members.pop("manifest.json"))
    arrays = {n[7:-4]: np.load(io.BytesIO(b), allow_pickle=False) for n, b in members.items()}
    return manifest, arrays


def write_members(path, manifest, arrays, rehash=True):
    """Write a file as an attacker would: any manifest, any arrays, the hash recomputed."""
    manifest = dict(manifest)
    manifest["arrays"] = {k: {"shape": list(v.shape), "dtype": v.dtype.str}
                          for k, v in arrays.items()}  # fmt: skip
    if rehash:
        manifest["content_sha256"] = container.content_hash(arrays, manifest)
    return write_zip(path, manifest, arrays)


def write_zip(path, manifest, arrays):
    """A zip of this manifest, as it is, and these arrays (stored, not compressed)."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_STORED) as zf:
        zf.writestr("manifest.json", json.dumps(manifest))
        for name, arr in arrays.items():
            buf = io.BytesIO()
            np.save(buf, arr)
            zf.writestr(f"arrays/{name}.npy", buf.getvalue())
    return path


def check_loaded(emu):
    """A loaded emulator is valid: finite predictions with positive variance, and calibration
    either works or says why (GPMSAError)."""
    x = np.array([[np.mean(emu.domain[n]) for n in emu.x_names]])
    t = np.array([[np.mean(emu.domain[n]) for n in emu.t_names]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            mean, var = emu.predict(x, t)
        except gpmsa.GPMSAError:
            return
        assert np.all(np.isfinite(mean)) and np.all(var > 0)
        try:
            post = gpmsa.Calibrator(emu, n_draws=10).update(x, mean)
        except gpmsa.GPMSAError:
            return
        for name in emu.t_names:
            lo, hi = emu.domain[name]
            assert lo <= post.mean(name) <= hi


def load_or_refuse(path):
    """gpmsa.load either returns a valid emulator or raises EmulatorFileError naming a field."""
    try:
        back = gpmsa.load(path)
    except gpmsa.EmulatorFileError as exc:
        assert FIELD.search(str(exc)), str(exc)
        return None
    check_loaded(back)
    return back


SPECIAL = st.sampled_from([np.nan, np.inf, -np.inf, 0.0, -0.0, -1.0, 1e300, -1e300, 1e-300,
                           5e-324, 2.0, 1e15])  # fmt: skip
JSON = st.recursive(
    st.none() | st.booleans() | st.integers(-(2**70), 2**70)
    | st.floats(allow_nan=False, allow_infinity=False) | st.text(max_size=8),
    lambda kids: st.lists(kids, max_size=3)
    | st.dictionaries(st.text(max_size=4), kids, max_size=3),
    max_leaves=6,
)  # fmt: skip
MANIFEST_PATHS = [
    ("names", "x", 0), ("names", "t"), ("names", "y", 0), ("names",), ("units", "x"),
    ("units", "t", 0), ("domain", "v"), ("domain", "v", 0), ("domain",), ("priors",),
    ("priors", "lamOs", "a"), ("priors", "lamOs"), ("priors", "lamWOs"), ("priors", "lamUz", "b"),
    ("priors", "lamWs", "lower"), ("priors", "lamWs", "upper"), ("priors", "theta_sd"),
    ("priors", "rho_cap"), ("priors", "corrected"), ("priors", "extra"), ("settings", "n_chains"),
    ("settings", "point"), ("settings",), ("metadata",), ("metadata", "vehicle"),
    ("diagnostics",), ("diagnostics", "betaU"), ("diagnostics", "betaU", "mean"), ("model", "m"),
    ("model",),
]  # fmt: skip


def set_path(obj, path, value):
    for key in path[:-1]:
        obj = obj[key]
    if isinstance(obj, list) and path[-1] >= len(obj):
        return
    obj[path[-1]] = value


@st.composite
def array_edit(draw, arrays):
    name = draw(st.sampled_from(sorted(arrays)))
    a = arrays[name].copy()
    kind = draw(st.sampled_from(["value", "scale", "row", "shape", "dtype", "empty", "swap"]))
    if kind == "value" and a.size:
        idx = draw(st.integers(0, a.size - 1))
        a = a.astype(np.float64)  # an earlier edit may have made it integer: NaN, inf need floats
        a.reshape(-1)[idx] = draw(SPECIAL)
    elif kind == "scale":
        a = a * draw(st.sampled_from([0.0, -1.0, 2.0, 1e10, 1 + 1e-6]))
    elif kind == "row" and a.ndim:
        a = a[1:] if draw(st.booleans()) else np.concatenate([a, a[:1]])
    elif kind == "shape":
        a = a.reshape(-1) if a.ndim > 1 else a.reshape(-1, 1)
    elif kind == "dtype":
        a = a.astype(draw(st.sampled_from([np.int64, np.bool_, np.float32])))
        if a.dtype == np.float32:
            a = a.astype(np.float64) + np.float64(1e-7)
    elif kind == "empty":
        a = np.zeros((0,) + a.shape[1:])
    elif kind == "swap":
        other = draw(st.sampled_from(sorted(arrays)))
        a = arrays[other].copy()
    return name, a


def _edit_and_load(saved, tmp_path, data, which, n_edits):
    manifest, arrays = read_members(saved[which])
    for _ in range(n_edits):
        if data.draw(st.booleans()):
            name, new = data.draw(array_edit(arrays))
            arrays[name] = new
        else:
            path = data.draw(st.sampled_from(MANIFEST_PATHS))
            if path[0] == "domain" and which == "vector":
                path = ("domain", "x0") + path[2:]
            try:
                set_path(manifest, path, data.draw(JSON))
            except (KeyError, TypeError, IndexError):
                assume(False)
    path = write_members(tmp_path / "edit.gpmsa", manifest, arrays)
    load_or_refuse(path)
    assert main(["info", str(path)]) in (0, 2)


EDITS = {"data": st.data(), "which": st.sampled_from(["scalar", "vector"]),
         "n_edits": st.integers(1, 3)}  # fmt: skip
HOSTILE = {
    "deadline": None,
    "derandomize": True,
    "suppress_health_check": [HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
}


@settings(max_examples=60, **HOSTILE)
@given(**EDITS)
def test_edited_content_with_recomputed_hash_loads_valid_or_names_the_field(
    saved, tmp_path, data, which, n_edits
):
    _edit_and_load(saved, tmp_path, data, which, n_edits)


@pytest.mark.slow
@settings(max_examples=1500, **HOSTILE)
@given(**EDITS)
def test_edited_content_many_more_examples(saved, tmp_path, data, which, n_edits):
    _edit_and_load(saved, tmp_path, data, which, n_edits)


@pytest.mark.parametrize(
    ("which", "edit", "field"),
    [
        ("scalar", lambda m, a: a.update(y_sd=np.array([np.nan])), "arrays/y_sd"),
        ("scalar", lambda m, a: a.update(y_sd=np.array([0.0])), "arrays/y_sd"),
        ("scalar", lambda m, a: a.update(t_max=a["t_min"].copy()), "arrays/t_min"),
        ("vector", lambda m, a: a["K"].__setitem__((0, 0), np.nan), "arrays/K"),
        ("vector", lambda m, a: a["K"].__setitem__((0, 0), np.inf), "arrays/K"),
        ("scalar", lambda m, a: a["w"].__setitem__((3, 0), np.nan), "arrays/w"),
        ("scalar", lambda m, a: a["x_unit"].__setitem__((2, 0), np.inf), "arrays/x_unit"),
        ("scalar", lambda m, a: a.update(w=a["w"] * 1.3), "arrays/w"),
        ("scalar", lambda m, a: a.update(y_mean=a["y_mean"] + 1.0), "arrays/y_mean"),
        ("scalar", lambda m, a: a.update(param_lamUz=a["param_lamUz"] * 50), "arrays/param_lamUz"),
        ("scalar", lambda m, a: a.update(K=np.array([[2.0]])), "arrays/K"),
        (
            "scalar",
            lambda m, a: m["priors"]["lamOs"].update(a=1e30),
            r"priors.lamOs.a: 1e\+30 is out of range: allowed \(0, 1e\+12\]",
        ),
        ("scalar", lambda m, a: m["priors"].update(lamWOs=[]), "priors.lamWOs: must be an object"),
        ("scalar", lambda m, a: m["priors"]["lamUz"].update(b=-1.0), "priors.lamUz.b"),
        ("scalar", lambda m, a: m["priors"].update(theta_sd=0), "priors.theta_sd"),
        ("scalar", lambda m, a: m["names"].update(x=[]), "names.x"),
        ("scalar", lambda m, a: m["names"].update(t=["v"]), "names: input names must be unique"),
        ("scalar", lambda m, a: m["settings"].update(n_chains="2"), "settings.n_chains"),
        ("scalar", lambda m, a: m["model"].update(m=10**9), "model.m"),
        ("scalar", lambda m, a: a.update(draw_lamWs=-a["draw_lamWs"]), "arrays/draw_lamWs"),
        ("scalar", lambda m, a: a.update(draw_foo=a["draw_lamWs"]), "arrays/draw_foo"),
        # an array no emulator holds: it loaded, and the next save dropped it
        ("scalar", lambda m, a: a.update(zz=a["y_mean"]), "arrays/zz: unknown array"),
        ("vector", lambda m, a: a.update(obs_y=a["grid"]), "arrays/obs_y: unknown array"),
    ],
)
def test_issue_examples_of_edited_files_name_the_field(saved, tmp_path, which, edit, field):
    manifest, arrays = read_members(saved[which])
    edit(manifest, arrays)
    path = write_members(tmp_path / "edit.gpmsa", manifest, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match=field):
        gpmsa.load(path)


def test_expected_sha256_authenticates_the_content(saved, tmp_path):
    with zipfile.ZipFile(saved["scalar"]) as zf:
        digest = json.loads(zf.read("manifest.json"))["content_sha256"]
    assert gpmsa.load(saved["scalar"], sha256=digest.upper()).m == 16
    manifest, arrays = read_members(saved["scalar"])
    manifest["metadata"]["vehicle"] = "husky"  # a consistent edit, hash recomputed: it loads
    path = write_members(tmp_path / "edit.gpmsa", manifest, arrays)
    assert gpmsa.load(path).metadata["vehicle"] == "husky"
    with pytest.raises(gpmsa.EmulatorFileError, match="differs from the expected"):
        gpmsa.load(path, sha256=digest)


# --- files that are not regular, or too big ------------------------------------------------------
@contextmanager
def time_limit(seconds):
    if not hasattr(signal, "SIGALRM"):
        yield
        return

    def fail(*_):
        raise TimeoutError(f"took more than {seconds} s")

    old = signal.signal(signal.SIGALRM, fail)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX special files")
def test_devices_fifos_and_directories_are_refused_at_once(tmp_path):
    fifo = tmp_path / "pipe.gpmsa"
    os.mkfifo(fifo)
    for path in ("/dev/zero", "/dev/urandom", str(fifo), str(tmp_path)):
        with time_limit(5):
            with pytest.raises(gpmsa.EmulatorFileError, match="not a regular file"):
                gpmsa.load(path)
            assert main(["info", path]) == 2
    assert main(["info", ""]) == 2  # no path at all: a message, not a traceback
    link = tmp_path / "zero.gpmsa"
    link.symlink_to("/dev/zero")
    with time_limit(5), pytest.raises(gpmsa.EmulatorFileError, match="not a regular file"):
        gpmsa.load(link)


def test_sizes_are_checked_before_decompressing(saved, tmp_path, monkeypatch):
    """A member whose declared size disagrees with its declared shape, a directory with too
    many entries, and arrays beyond MAX_ARRAY_BYTES are refused without decompressing."""
    manifest, arrays = read_members(saved["scalar"])
    manifest["arrays"] = {k: {"shape": list(v.shape), "dtype": v.dtype.str}
                          for k, v in arrays.items()}  # fmt: skip
    manifest["arrays"]["y"]["shape"] = [10**6, 1000]  # 8 GB declared for a small member
    path = write_zip(tmp_path / "liar.gpmsa", manifest, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match=r"array 'y': its member holds \d+ bytes"):
        gpmsa.load(path)
    opened = []
    monkeypatch.setattr(zipfile.ZipFile, "open", lambda *a, **k: opened.append(a) or 1 / 0)
    with pytest.raises(gpmsa.EmulatorFileError, match="damaged"):
        gpmsa.load(saved["scalar"])  # the manifest is the first member read
    assert len(opened) == 1
    monkeypatch.undo()
    monkeypatch.setattr(gpmsa.limits, "MAX_ARRAY_BYTES", 2000)
    with pytest.raises(gpmsa.EmulatorFileError, match="exceed gpmsa.limits.MAX_ARRAY_BYTES"):
        gpmsa.load(saved["scalar"])
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMBERS", 5)
    with pytest.raises(gpmsa.EmulatorFileError, match=r"members \(limit gpmsa.limits.MAX_MEMBERS"):
        gpmsa.load(saved["scalar"])


def test_zip_bomb_member_refused_from_its_header(saved, tmp_path):
    path = tmp_path / "bomb.gpmsa"
    with zipfile.ZipFile(saved["scalar"]) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for n, b in members.items():
            zf.writestr(n, b)
        zf.writestr("arrays/zeros.npy", b"\0" * 50_000_000)
    with time_limit(5), pytest.raises(gpmsa.EmulatorFileError, match="zip bomb"):
        gpmsa.load(path)


def test_bytes_after_the_zip_end_record_are_refused(saved, tmp_path):
    """zip readers skip what follows the end record, so an appended or concatenated file would
    load as if whole; the reader names it instead, and a zip comment that overruns the file."""
    raw = saved["scalar"].read_bytes()
    appended = tmp_path / "appended.gpmsa"
    appended.write_bytes(raw + b"trailing")
    with pytest.raises(gpmsa.EmulatorFileError, match="8 bytes follow the end record"):
        gpmsa.load(appended)
    overrun = tmp_path / "overrun.gpmsa"
    overrun.write_bytes(raw[:-2] + (40).to_bytes(2, "little"))  # comment length 40, none there
    with pytest.raises(gpmsa.EmulatorFileError, match="a truncated comment ends the end record"):
        gpmsa.load(overrun)
    assert gpmsa.load(saved["scalar"]).metadata == {"vehicle": "jackal"}


# --- the writer ---------------------------------------------------------------------------------
def test_zero_padded_outputs_save_and_load(tmp_path):
    """The issue's 30 runs x 20,000 outputs padded with zeros: written (the zero members stored
    uncompressed) and read back exactly."""
    rng = np.random.default_rng(3)
    x, t = rng.random((30, 1)), rng.random((30, 1))
    y = np.zeros((30, 20_000))
    y[:, :50] = np.sin(np.outer(x[:, 0] + t[:, 0], np.arange(50) / 10.0))
    sim = gpmsa.SimData(x=x, t=t, y=y)
    params = {"betaU": [[1.0] * 3] * 2, "lamUz": [1.0] * 3, "lamWs": [1e4] * 3, "lamWOs": [1e4]}
    emu = gpmsa.Emulator.from_params(sim, params, n_pc=3)
    path = emu.save(tmp_path / "padded.gpmsa")
    back = gpmsa.load(path)
    assert np.array_equal(back.K, emu.K) and np.array_equal(back.y, emu.y)
    m1, v1 = emu.predict([[0.5]], [[0.5]])
    m2, v2 = back.predict([[0.5]], [[0.5]])
    assert np.array_equal(m1, m2) and np.array_equal(v1, v2)


def test_refused_save_writes_nothing_and_keeps_the_old_file(emu, tmp_path, monkeypatch):
    path = emu.save(tmp_path / "model.gpmsa")
    before = path.read_bytes()
    big = gpmsa.load(path)
    big.metadata["notes"] = "x" * (17 * 1024**2)  # the issue's 17 MB metadata string
    with pytest.raises(gpmsa.GPMSAError, match=r"manifest takes \d+ bytes \(field 'metadata'"):
        big.save(path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.gpmsa"]  # no temporary left
    for bad in (np.nan, np.inf):
        big.metadata = {"x": [1, {"y": bad}]}
        with pytest.raises(gpmsa.GPMSAError, match=r"metadata\['x'\]\[1\]\['y'\] = (nan|inf)"):
            big.save(path)
    big.metadata = {1: "a"}
    with pytest.raises(gpmsa.GPMSAError, match="keys must be strings"):
        big.save(path)
    loaded = gpmsa.load(path)
    broken = replaced(loaded, params=dict(loaded.params, lamUz=loaded.params["lamUz"] * 1e3))
    with pytest.raises(gpmsa.GPMSAError, match="refusing to write .*param_lamUz"):
        broken.save(path)
    monkeypatch.setattr(gpmsa.limits, "MAX_ARRAY_BYTES", 5000)
    with pytest.raises(gpmsa.GPMSAError, match="above gpmsa.limits.MAX_ARRAY_BYTES = 5000"):
        emu.save(path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.gpmsa"]
    monkeypatch.setattr(gpmsa.limits, "MAX_ARRAY_BYTES", 1024**3)
    with pytest.raises(gpmsa.GPMSAError, match="not a regular file"):
        emu.save(tmp_path)  # a directory is not replaced
    monkeypatch.setattr(os, "replace", lambda *a: 1 / 0)  # a failure while moving into place
    with pytest.raises(ZeroDivisionError):
        emu.save(path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.gpmsa"]


NAMES = st.text(st.characters(codec="utf-8", exclude_categories=["Cs"]), min_size=1, max_size=6)
META = st.recursive(
    st.none() | st.booleans() | st.integers(-(2**80), 2**80)
    | st.floats(allow_nan=False, allow_infinity=False) | NAMES,
    lambda kids: st.lists(kids, max_size=3) | st.dictionaries(NAMES, kids, max_size=3),
    max_leaves=8,
)  # fmt: skip


@st.composite
def emulators(draw):
    p, q = draw(st.integers(1, 2)), draw(st.integers(1, 2))
    m = draw(st.integers(p + q + 2, 18))
    l_sim = draw(st.sampled_from([1, 1, 3, 7]))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    scale = 10.0 ** draw(st.integers(-6, 6))
    x, t = rng.random((m, p)) * scale, rng.random((m, q)) + draw(st.floats(-1e3, 1e3))
    y = np.sin(x @ rng.random((p, l_sim)) / scale * 3 + t @ rng.random((q, l_sim)))
    y = scale * (y + 0.01 * rng.standard_normal((m, l_sim)))
    if l_sim > 1 and draw(st.booleans()):
        y[:, -1] = 0.0  # zero padding
    # (names are non-blank: SimData refuses a blank one; units may be anything)
    names = draw(st.lists(NAMES.filter(str.strip), min_size=p + q + l_sim, max_size=p + q + l_sim,
                          unique=True))  # fmt: skip
    # (no calibration parameter named as the posterior's others: SimData refuses those names)
    t_names = names[p : p + q]
    assume(not any(n in RESERVED_NAMES or re.fullmatch(r"betaV\[\d+\]", n) for n in t_names))
    units = draw(st.lists(NAMES, min_size=p + q + l_sim, max_size=p + q + l_sim))
    sim = gpmsa.SimData(
        x=x, t=t, y=y, x_names=names[:p], t_names=t_names, y_names=names[p + q :],
        x_units=units[:p], t_units=units[p : p + q], y_units=units[p + q :],
    )  # fmt: skip
    meta = draw(st.dictionaries(NAMES, META, max_size=4))
    if draw(st.booleans()):
        return gpmsa.fit(sim, n_iter=draw(st.integers(2, 15)), tune=False, seed=seed,
                         metadata=meta)  # fmt: skip
    p_u = gpmsa.prepare(sim).problem.p_u
    params = {
        "betaU": rng.uniform(0.01, 10, (p + q, p_u)), "lamUz": rng.uniform(0.3, 10, p_u),
        "lamWs": rng.uniform(60, 1e5, p_u), "lamWOs": rng.uniform(60, 1e5, 1),
    }  # fmt: skip
    return gpmsa.Emulator.from_params(sim, params, metadata=meta)


@settings(
    max_examples=60, deadline=None, derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)  # fmt: skip
@given(emu=emulators())
def test_save_then_load_round_trips_generated_emulators(tmp_path, emu):
    path = tmp_path / "gen.gpmsa"
    if path.exists():
        path.unlink()
    emu.save(path)  # never refused: these emulators are valid and small
    back = gpmsa.load(path)
    assert back.metadata == emu.metadata
    assert back.x_names == tuple(emu.x_names) and back.y_units == tuple(emu.y_units)
    assert back.domain == emu.domain and back.priors == emu.priors
    for k in emu.draws:
        assert np.array_equal(back.draws[k], emu.draws[k])
    x = np.array([[np.mean(emu.domain[n]) for n in emu.x_names]])
    t = np.array([[np.mean(emu.domain[n]) for n in emu.t_names]])
    m1, v1 = emu.predict(x, t)
    m2, v2 = back.predict(x, t)
    assert np.array_equal(m1, m2) and np.array_equal(v1, v2)
    assert main(["info", str(path)]) == 0


# --- gpmsa info -----------------------------------------------------------------------------------
def test_info_escapes_terminal_codes_from_the_file(emu, tmp_path, capsys):
    evil = "\x1b[2J\x1b]0;pwned\x07\r\u202e\x9b31m"
    loaded = gpmsa.load(emu.save(tmp_path / "a.gpmsa"))
    sim_emu = replaced(
        loaded, settings=dict(loaded.settings, note=evil), x_names=(evil,), t_units=(evil,),
        diagnostics={evil: {"mean": [evil, 1.0], "ess": evil}, "x": 5},
    )  # fmt: skip
    sim_emu.metadata = {evil: evil, "versions": {evil: evil}}
    path = sim_emu.save(tmp_path / (evil + ".gpmsa"))
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "\\x1b[2J" in out and "\\u202e" in out and "\\x9b" in out
    assert not re.search(r"[\x00-\x08\x0b-\x1f\x7f-\x9f\u202e]", out)
    assert main(["info", "--json", str(path)]) == 0
    assert not re.search(r"[\x00-\x08\x0b-\x1f\x7f-\x9f\u202e]", capsys.readouterr().out)
    assert main(["calibrate", str(path), "--x", f"{evil}=1.0", "--y", "y0=9"]) in (0, 2)
    captured = capsys.readouterr()
    assert not re.search(r"[\x00-\x08\x0b-\x1f\x7f-\x9f\u202e]", captured.out + captured.err)
    bad = tmp_path / "bad\x1b[31m.gpmsa"
    bad.write_bytes(b"PK\x05\x06" + b"\0" * 18)
    assert main(["info", str(bad)]) == 2
    assert "\x1b" not in capsys.readouterr().err


def test_safe_escapes_every_non_printable_character():
    for code in list(range(0x00, 0x20)) + list(range(0x7F, 0xA0)) + [0x202E, 0x200B, 0x2028]:
        assert chr(code) not in safe(f"a{chr(code)}b")
    assert safe("GD [1e-6 m^3] é ü 語") == "GD [1e-6 m^3] é ü 語"
    assert safe("x" * 500, 10) == "xxxxxxxxxx... (500 characters)"


def test_info_shows_the_recorded_versions(emu, tmp_path, capsys):
    """fit records the versions that computed the emulator (issue 15, section 5); a campaign's
    versions copied into the metadata are shown too."""
    import platform

    import scipy

    v = emu.settings["versions"]
    assert v["numpy"] == np.__version__ and v["scipy"] == scipy.__version__
    assert v["python"] == platform.python_version() and v["gpmsa"] == gpmsa.__version__
    assert "blas" in v and "machine" in v
    copy = gpmsa.load(emu.save(tmp_path / "a.gpmsa"))
    copy.metadata["versions"] = {"exudyn": "1.13.6", "numpy": "2.4.6"}
    path = copy.save(tmp_path / "b.gpmsa")
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("versions (settings): "))
    assert f"python {platform.python_version()}" in line and f"numpy {np.__version__}" in line
    assert f"gpmsa {gpmsa.__version__}" in line and "blas " in line
    assert "versions (metadata): exudyn 1.13.6, numpy 2.4.6" in out


def _with_raw_metadata(path, manifest, arrays, text: str):
    """An emulator file at ``path`` whose manifest JSON gets ``text`` written at the start of
    its metadata object, as raw JSON (what json.dumps cannot write), the rest unchanged."""
    write_members(path, manifest, arrays)
    raw = zipfile.ZipFile(path).read("manifest.json").decode()
    edited = raw.replace('"metadata": {', '"metadata": {' + text, 1)
    assert edited != raw
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("manifest.json", edited)
        for name, arr in arrays.items():
            buf = io.BytesIO()
            np.save(buf, arr)
            zf.writestr(f"arrays/{name}.npy", buf.getvalue())
    return path


def test_a_manifest_number_beyond_float64_or_nested_too_deep_is_a_file_error(saved, tmp_path):
    manifest, arrays = read_members(saved["scalar"])
    # the hash cannot even be computed: refused first
    huge = _with_raw_metadata(tmp_path / "huge.gpmsa", manifest, arrays, '"big": 1e999, ')
    with pytest.raises(gpmsa.EmulatorFileError, match="beyond float64"):
        gpmsa.load(huge)
    assert main(["info", str(huge)]) == 2
    deep: dict = {}
    for _ in range(200):
        deep = {"a": deep}
    nested = write_members(tmp_path / "deep.gpmsa", {**manifest, "metadata": deep}, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match="nests deeper than 72 levels"):
        gpmsa.load(nested)


def test_a_manifest_key_given_twice_is_a_file_error(saved, tmp_path):
    """JSON parsers differ on a repeated key (Python's takes the last): a file that reads one
    way here and another way elsewhere is refused, however its hash was made."""
    manifest, arrays = read_members(saved["scalar"])
    twice = '"note": "a", "note": "b", '
    path = _with_raw_metadata(tmp_path / "twice.gpmsa", manifest, arrays, twice)
    with pytest.raises(gpmsa.EmulatorFileError, match="key 'note' appears twice in one object"):
        gpmsa.load(path)
    assert main(["info", str(path)]) == 2


def test_a_design_width_beyond_float64_and_array_names_with_a_newline_are_refused(saved, tmp_path):
    manifest, arrays = read_members(saved["scalar"])
    wide = {**arrays, "t_min": np.array([-1e308]), "t_max": np.array([1e308])}
    path = write_members(tmp_path / "wide.gpmsa", manifest, wide)
    with pytest.raises(gpmsa.EmulatorFileError, match=r"t_min.*not a finite, normal number"):
        gpmsa.load(path)
    assert not container.NAME_RE.match("x_unit\n") and container.NAME_RE.match("x_unit")


def test_saving_keeps_permissions_writes_through_links_and_takes_long_names(emu, tmp_path):
    path = emu.save(tmp_path / "private.gpmsa")
    os.chmod(path, 0o600)
    emu.save(path)
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o600
    link = tmp_path / "link.gpmsa"
    link.symlink_to(path)
    emu.save(link)
    assert link.is_symlink() and gpmsa.load(link).settings == emu.settings
    long = tmp_path / ("a" * 249 + ".gpmsa")  # a 255-byte name
    assert emu.save(long).exists()
    with pytest.raises(gpmsa.GPMSAError, match="holds no NUL byte"):
        emu.save(tmp_path / "a\0b.gpmsa")


def test_an_observation_too_large_for_the_basis_is_named_and_cli_json_is_strict(vec_emu):
    y = np.full((1, 6), 0.5)
    y[0, 0] = 1e308  # finite, but its projection on the basis overflows
    with pytest.raises(
        gpmsa.GPMSAError,
        match=r"y_obs lies .* standard deviations of the "
        r"simulation outputs .*wrong units",
    ):
        gpmsa.Calibrator(vec_emu).update([[0.5]], y)
    out = container.jsonable({"sd": float("inf"), "q": [np.float64("nan"), 1.0], "n": 3})
    assert json.loads(json.dumps(out, allow_nan=False)) == {"sd": None, "q": [None, 1.0], "n": 3}


@pytest.mark.parametrize("extra", [1, 1000])
def test_a_chain_count_that_does_not_divide_the_draws_is_refused(saved, tmp_path, extra):
    """settings.n_chains was checked only as an integer >= 1: a file saying 3 chains of 320
    draws lost 2 draws in to_arviz, one saying 1000 gave 1000 chains of 0 draws."""
    manifest, arrays = read_members(saved["scalar"])
    n_draws = arrays["log_post"].shape[0]
    manifest["settings"]["n_chains"] = n_draws + extra
    path = write_members(tmp_path / "chains.gpmsa", manifest, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match="settings.n_chains.*cannot hold the"):
        gpmsa.load(path)


@pytest.mark.parametrize(
    ("drop", "match"),
    [(["draw_lamUz"], r"arrays/log_post: \d+ draws, but the draws of \['draw_lamUz'\] are missing"),
     (["draw_betaU", "draw_lamUz", "draw_lamWs", "draw_lamWOs"], "draws of .* are missing")],
)  # fmt: skip
def test_draws_of_some_parameters_only_are_refused(saved, tmp_path, drop, match):
    """A file holding the draws of some emulator parameters only loaded, and predict(draws=True)
    then raised KeyError: 'lamUz'."""
    manifest, arrays = read_members(saved["scalar"])
    for name in drop:
        del arrays[name]
    path = write_members(tmp_path / "partial.gpmsa", manifest, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match=match):
        gpmsa.load(path)


def test_calibration_draws_without_theta_are_refused(saved, tmp_path):
    """cal_lamOs alone loaded; theta_summary then raised KeyError: 'theta_native'."""
    manifest, arrays = read_members(saved["scalar"])
    arrays["cal_lamOs"] = np.ones((arrays["log_post"].shape[0], 1))
    path = write_members(tmp_path / "cal.gpmsa", manifest, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match=r"arrays/cal_: .*'cal_theta'"):
        gpmsa.load(path)


def test_a_manifest_without_its_model_field_names_it(saved, tmp_path):
    """Without "model" the reader failed late, as "inconsistent content (KeyError: 'model')"."""
    manifest, arrays = read_members(saved["scalar"])
    del manifest["model"]
    path = write_members(tmp_path / "nomodel.gpmsa", manifest, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match="model: must be an object, got None"):
        gpmsa.load(path)
