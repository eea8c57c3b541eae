"""Review of session 74's commits: defects found and their fixes (gpmsa.mcmc.parallel's fork
hook)."""

import gc
import importlib.util
import multiprocessing.context
import os
import sys
import threading
import warnings

import pytest

from gpmsa.mcmc import parallel

_fork = pytest.mark.skipif(sys.platform != "linux", reason="gpmsa's own workers fork on Linux")


def test_the_module_imports_where_there_is_no_fork(monkeypatch):
    """Windows has no ForkProcess nor ForkContext (nor os.register_at_fork): ``import gpmsa``
    raised AttributeError there."""
    monkeypatch.setattr(sys, "platform", "win32")
    for name in ("ForkProcess", "ForkContext"):
        monkeypatch.delattr(multiprocessing.context, name, raising=False)
    monkeypatch.delattr(os, "register_at_fork", raising=False)
    spec = importlib.util.spec_from_file_location("_parallel_win32", parallel.__file__)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # before: AttributeError: ... 'ForkProcess'
    assert callable(module._own_pool)


def _frozen_in_a_fork() -> tuple[int, int]:
    """(this process's gc.get_freeze_count() at a fork, its child's, which freezes the 101
    tracked lists ``keep`` too if it freezes what it inherits)."""
    keep = [[i] for i in range(100)]  # tracked objects of this process, not yet frozen
    r, w = os.pipe()
    frozen = gc.get_freeze_count()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # 3.12+: fork with threads
        pid = os.fork()
    if pid == 0:
        os.write(w, str(gc.get_freeze_count()).encode())
        os._exit(0)
    os.close(w)
    os.waitpid(pid, 0)
    with os.fdopen(r) as f:
        child = int(f.read())
    del keep
    return frozen, child


def _forks_in_the_worker(x, progress=False, desc=""):
    return _frozen_in_a_fork()


@_fork
@pytest.mark.skipif(parallel.available_cpus() < 2, reason="needs two CPUs for a pool")
def test_a_workers_own_forks_are_not_frozen():
    """The worker inherited the flag set while it was forked: a process it forked froze too."""
    runs = parallel.run_chains(_forks_in_the_worker, [{"x": 0}, {"x": 1}], n_jobs=2)
    for worker, child in runs:
        assert worker > 0  # the worker froze what it inherited
        assert child - worker < 101  # before: the child froze the worker's objects too


@_fork
def test_another_threads_fork_meanwhile_is_not_frozen(monkeypatch):
    """While one thread forks a pool worker, a fork by another thread is not gpmsa's."""
    seen = []

    def popen(process_obj):  # another thread forks while this one forks "a worker"
        other = threading.Thread(target=lambda: seen.append(_frozen_in_a_fork()))
        other.start()
        other.join()

    monkeypatch.setattr(multiprocessing.context.ForkProcess, "_Popen", staticmethod(popen))
    parallel._WorkerProcess._Popen(None)
    ((parent, child),) = seen
    assert child - parent < 101  # before: the other thread's child froze everything it inherited


class _StillNUTS:
    """NUTS's part in `LevelJumps`: a chain that stays where it is (sites unconstrained as
    themselves)."""

    def __init__(self, sites):
        from torch.distributions.transforms import identity_transform

        self.transforms = {k: identity_transform for k in sites}

    def setup(self, warmup_steps, *args, **kwargs):
        pass

    def sample(self, params):
        return params

    def clear_cache(self):
        pass


def test_pyro_level_move_offsets_are_frozen_before_the_first_kept_draw(monkeypatch):
    """The offsets are found from the state at the end of the warm-up, so that the move of
    every kept draw has frozen offsets (exact). They were found at the first kept draw and its
    move used offsets that depend on its own state (the reverse move would have others)."""
    import numpy as np
    from _level_cases import level_function, level_sim

    import gpmsa
    from gpmsa.mcmc import level_moves
    from gpmsa.model.problem import prepare

    pb = pytest.importorskip("gpmsa.backends.pyro_backend")
    xo = np.linspace(0.2, 0.8, 4)[:, None]  # a joint fit's problem: kind 1 at k = 0.4
    yo = level_function(xo, np.column_stack([np.full(4, 0.4), np.ones(4)]))
    sim = level_sim(np.random.default_rng(3), 24)
    model = pb.PyroModel(prepare(sim, gpmsa.ObsData(x=xo, y=yo[:, None])).problem)
    found = []  # the offsets' search (a grid search; here none: no shift)
    monkeypatch.setattr(
        level_moves,
        "level_offsets",
        lambda f, th, k, levels, cont: found.append(th) or np.zeros((len(levels), len(cont))),
    )
    params = {k: v for k, v in model.init_values().items()}
    jumps = pb.LevelJumps(_StillNUTS(params), model, np.random.default_rng(0))
    jumps.setup(2)
    for _ in range(2):
        params = jumps.sample(params)
    assert len(found) == 1 and jumps.moves == 0  # before: not yet (found at draw 1, then moved)
    jumps.sample(params)
    assert len(found) == 1 and jumps.moves == 1
