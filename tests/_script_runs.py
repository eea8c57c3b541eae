"""Run benchmark and example scripts as ``python SCRIPT ARGS...`` would, several in one fresh
interpreter: the command-line tests pay its start and the packages' import (~1.5 s) once, not
once a script.

Each script runs as ``__main__`` (`runpy`), with its own ``sys.argv``, its folder first on
``sys.path``, and its stdout and stderr captured; an uncaught exception is reported as the
interpreter would (a traceback on stderr, exit status 1).
"""

import contextlib
import functools
import io
import json
import os
import runpy
import subprocess
import sys
import tempfile
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run_scripts(runs: list[tuple[str, list[str]]], timeout_s: float = 900.0) -> list[dict]:
    """``[{"returncode", "stdout", "stderr"}]`` of each (script path relative to the repository
    root, its arguments), run in order in one interpreter started from the repository root."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    with tempfile.TemporaryDirectory() as folder:
        order, report = Path(folder) / "runs.json", Path(folder) / "report.json"
        order.write_text(json.dumps([[script, list(args)] for script, args in runs]))
        done = subprocess.run(
            [sys.executable, __file__, str(order), str(report)],
            capture_output=True, text=True, cwd=ROOT, env=env, timeout=timeout_s,
        )  # fmt: skip
        if done.returncode != 0 or not report.exists():
            raise RuntimeError(f"the script runner failed:\n{done.stderr[-3000:]}")
        return json.loads(report.read_text())


@functools.cache
def _all_helps() -> dict[str, dict]:
    """`script_helps` of every script, made once a session."""
    scripts = [
        path.relative_to(ROOT).as_posix()
        for folder in ("benchmarks", "examples")
        for path in sorted((ROOT / folder).glob("*.py"))
        if not path.name.startswith("_")  # a helper the scripts import (examples/_cli.py)
    ]
    return dict(zip(scripts, run_scripts([(s, ["--help"]) for s in scripts]), strict=True))


def script_helps() -> dict[str, dict]:
    """Each benchmark and example script's run with ``--help`` (`run_scripts`' record, by its
    path relative to the repository root, as benchmarks/backends.py), all in one interpreter
    once a session for the tests that read them (a copy: none changes another's)."""
    return {script: dict(done) for script, done in _all_helps().items()}


def _run_one(script: str, args: list[str]) -> dict:
    """One script run in this interpreter, as ``python script *args`` would run it."""
    path = str(ROOT / script)
    out, err = io.StringIO(), io.StringIO()
    saved_argv, saved_path = sys.argv, list(sys.path)
    sys.argv = [path, *args]
    sys.path.insert(0, str(Path(path).parent))
    code = 0
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                runpy.run_path(path, run_name="__main__")
            except SystemExit as exc:  # as the interpreter ends on it
                if exc.code is None or isinstance(exc.code, int):
                    code = exc.code or 0
                else:
                    print(exc.code, file=sys.stderr)
                    code = 1
            except BaseException:
                traceback.print_exc()
                code = 1
    finally:
        sys.argv, sys.path[:] = saved_argv, saved_path
    return {"returncode": code, "stdout": out.getvalue(), "stderr": err.getvalue()}


if __name__ == "__main__":
    if sys.path and Path(sys.path[0]).resolve() == Path(__file__).resolve().parent:
        del sys.path[0]  # tests/ (its control/ folder is not the package), as for a script
    order, report = sys.argv[1], sys.argv[2]
    runs = json.loads(Path(order).read_text())
    Path(report).write_text(json.dumps([_run_one(script, args) for script, args in runs]))
