"""examples/_cli.run with stdout closed (``python examples/closed_loop.py >&-``, a service
started without one): Python's sys.stdout is then None, and print writes nothing.

Before: ``run`` wrapped None in its reader-has-gone guard, so that the first print raised
AttributeError ('NoneType' object has no attribute 'write'), and Python's flush of the wrapper
at exit printed "Exception ignored ... AttributeError" and set exit status 120 (seen with
``examples/roadgen_psd_check.py --out DIR >&-``, and with every script's ``--help >&-``)."""

import sys

from tests._examples import load_example

cli = load_example("_cli")


def test_a_script_runs_with_stdout_closed(monkeypatch):
    monkeypatch.setattr(sys, "stdout", None)
    done = []

    def main():
        print("a table the script prints")
        done.append(True)

    cli.run(main)
    assert done == [True]
    assert sys.stdout is None  # nothing for Python to flush at exit


def test_a_script_still_guards_an_open_stdout(monkeypatch, capsys):
    monkeypatch.setattr(sys, "stdout", sys.stdout)  # restored after the test
    cli.run(lambda: print("printed"))
    assert isinstance(sys.stdout, cli._UntilTheReaderLeaves)
    assert capsys.readouterr().out == "printed\n"
