"""The torch and pyro backends under torch's global state as a caller left it (session 86).

Users of torch set, before calling us, a default dtype or device, grad or inference mode,
anomaly detection, deterministic algorithms, thread counts and torch's global seed. The draws
depend only on our own ``seed``, ``dtype`` and ``device`` arguments (bit for bit the draws of
the default state), and our calls leave these settings, and torch's global RNG, as they were,
when they raise too. Before this session the pyro backend failed under the caller's
``torch.no_grad()`` / ``inference_mode()`` ("element 0 of tensors does not require grad"), and
both backends under a default device other than the CPU ("can't convert meta device type
tensor to numpy"; "Tensor on device meta is not on the expected device cpu").
"""

import random
import warnings
from contextlib import contextmanager

import numpy as np
import pytest
from _backend_cases import multi_problem
from _level_cases import level_function, level_sim

import gpmsa
from gpmsa.model.problem import prepare

torch = pytest.importorskip("torch")
tb = pytest.importorskip("gpmsa.backends.torch_backend")


@pytest.fixture(scope="module")
def problem():
    """The torch backend's case: 24 runs, output on a 15-point grid, two experiments."""
    return multi_problem().problem


@pytest.fixture(scope="module")
def small():
    """The pyro backend's case (NUTS is slow under anomaly detection): 10 runs, scalar output,
    one observation."""
    rng = np.random.default_rng(0)
    x, t = rng.random((10, 1)), rng.random((10, 1))
    obs = gpmsa.ObsData(x=np.array([[0.5]]), y=np.array([[np.sin(2.3)]]))
    return prepare(gpmsa.SimData(x=x, t=t, y=np.sin(3 * x + 2 * t)), obs).problem


def _torch(problem, **kw):
    return tb.sample(problem, n_iter=20, n_chains=2, seed=3, warmup=5, tune_stages=1,
                     tune_rounds=2, tune_levels=3, **kw)  # fmt: skip


def _pyro(problem):
    pb = pytest.importorskip("gpmsa.backends.pyro_backend")
    return pb.sample(problem, n_iter=10, seed=3, n_warmup=5, max_tree_depth=2, jit=False)


@pytest.fixture(scope="module")
def torch_ref(problem):
    return _torch(problem)


@pytest.fixture(scope="module")
def pyro_ref(small):
    return _pyro(small)


def _assert_same(a, b):
    for k in a.draws:
        np.testing.assert_array_equal(a.draws[k], b.draws[k], err_msg=k)
    np.testing.assert_array_equal(a.log_post, b.log_post)


def _globals() -> dict:
    return {"dtype": torch.get_default_dtype(), "grad": torch.is_grad_enabled(),
            "inference": torch.is_inference_mode_enabled(), "threads": torch.get_num_threads(),
            "deterministic": torch.are_deterministic_algorithms_enabled(),
            "anomaly": torch.is_anomaly_enabled(), "device": torch.empty(0).device,
            "rng": torch.get_rng_state(), "numpy": np.random.get_state()[1],  # noqa: NPY002
            "random": random.getstate()}  # fmt: skip


def _assert_kept(before: dict) -> None:
    after = _globals()
    for key, was in before.items():
        now = after[key]
        if isinstance(was, torch.Tensor):
            same = torch.equal(now, was)
        else:
            same = np.array_equal(now, was) if isinstance(was, np.ndarray) else now == was
        assert same, f"the call changed the caller's {key}"


@contextmanager
def _default_dtype(dtype):
    old = torch.get_default_dtype()
    torch.set_default_dtype(dtype)
    try:
        yield
    finally:
        torch.set_default_dtype(old)


@contextmanager
def _default_device(device):
    old = torch.empty(0).device  # (torch.get_default_device: torch >= 2.3)
    torch.set_default_device(device)
    try:
        yield
    finally:
        torch.set_default_device(None if old.type == "cpu" else old)


@contextmanager
def _flag(setter, getter, value):
    old = getter()
    setter(value)
    try:
        yield
    finally:
        setter(old)


@contextmanager
def _seeded():
    """The global torch, numpy and Python generators seeded, as users seed them; their states
    restored after."""
    states = torch.get_rng_state(), np.random.get_state(), random.getstate()  # noqa: NPY002
    torch.manual_seed(12345)
    np.random.seed(5)  # noqa: NPY002
    random.seed(7)
    try:
        yield
    finally:
        torch.set_rng_state(states[0])
        np.random.set_state(states[1])  # noqa: NPY002
        random.setstate(states[2])


SETTINGS = {
    "default_float64": lambda: _default_dtype(torch.float64),
    "default_float32": lambda: _default_dtype(torch.float32),
    "set_default_device_cpu": lambda: _default_device("cpu"),
    "set_default_device_meta": lambda: _default_device("meta"),
    "with_device_meta": lambda: torch.device("meta"),
    "no_grad": torch.no_grad,
    "set_grad_enabled_false": lambda: torch.set_grad_enabled(False),
    "inference_mode": torch.inference_mode,
    "detect_anomaly": lambda: _flag(
        torch.autograd.set_detect_anomaly, torch.is_anomaly_enabled, True
    ),  # fmt: skip
    "deterministic": lambda: _flag(
        torch.use_deterministic_algorithms, torch.are_deterministic_algorithms_enabled, True
    ),  # fmt: skip
    "num_threads_2": lambda: _flag(torch.set_num_threads, torch.get_num_threads, 2),
    "global_seeds": _seeded,
}


CASES = [("torch", k) for k in SETTINGS] + [
    ("pyro", k)
    for k in SETTINGS
    if k != "detect_anomaly"  # anomaly mode: NUTS ~5x slower
]


@pytest.mark.parametrize(("backend", "setting"), CASES)
def test_draws_and_the_callers_state(request, backend, setting):
    """Each backend's draws under the caller's setting equal its draws in the default state,
    and the call leaves the setting (and the global generators) as the caller had them."""
    run, data = (_torch, "problem") if backend == "torch" else (_pyro, "small")
    problem, ref = request.getfixturevalue(data), request.getfixturevalue(f"{backend}_ref")
    with SETTINGS[setting]():
        before = _globals()
        got = run(problem)
        _assert_kept(before)
    _assert_same(got, ref)


def test_float32_option_whatever_the_default_dtype(problem, torch_ref):
    """dtype="float32" computes in float32 and the default "float64" in float64, whatever
    torch's default dtype."""
    ref32, ref64 = _torch(problem, dtype="float32"), torch_ref
    for default in (torch.float64, torch.float32):
        with _default_dtype(default):
            _assert_same(_torch(problem, dtype="float32"), ref32)
            _assert_same(_torch(problem), ref64)
    assert not np.array_equal(ref32.draws["theta"], ref64.draws["theta"])


def test_in_process_chain_groups_with_level_moves_on_a_meta_default_device():
    """Chain groups run here (n_jobs=1) carry the joint level move's offsets: on the CPU,
    whatever the caller's default device."""
    rng = np.random.default_rng(3)
    xo = np.linspace(0.2, 0.8, 4)[:, None]
    yo = level_function(xo, np.column_stack([np.full(4, 0.4), np.ones(4)]))
    prob = prepare(level_sim(rng, 24), gpmsa.ObsData(x=xo, y=yo[:, None])).problem
    kw = dict(n_iter=10, n_chains=2, seed=0, tune=False, warmup=0, chain_groups=2, n_jobs=1)
    ref = tb.sample(prob, **kw)
    assert ref.info.get("level_offsets")
    with torch.device("meta"):
        got = tb.sample(prob, **kw)
    _assert_same(got, ref)


@pytest.mark.parametrize("backend", ["torch", "pyro"])
def test_settings_restored_when_the_call_raises(problem, backend):
    """A start whose likelihood is NaN raises inside the thread and RNG settings."""
    if backend == "pyro":
        pytest.importorskip("gpmsa.backends.pyro_backend")
    start = {k: np.repeat(np.asarray(v, dtype=float)[None], 1, axis=0)
             for k, v in problem.init.items()}  # fmt: skip
    start["lamWs"] = np.full_like(start["lamWs"], np.nan)
    sample = gpmsa.backends.get(backend).sample
    with _flag(torch.set_num_threads, torch.get_num_threads, 2), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        before = _globals()
        with pytest.raises(gpmsa.GPMSAError):
            sample(problem, n_iter=10, seed=0, init=start, num_threads=1)
        _assert_kept(before)
