"""Shared pieces of the stateful random-interleaving tests (hypothesis state machines, session
83): the ways an online object is copied, and one run of a machine, derandomized for CI."""

import copy
import pickle

from hypothesis import HealthCheck, settings
from hypothesis.stateful import run_state_machine_as_test

COPIES = {
    "copy": copy.copy,
    "deepcopy": copy.deepcopy,
    "pickle": lambda obj: pickle.loads(pickle.dumps(obj)),
}


def run_machine(machine, max_examples: int, steps: int, derandomize: bool = True) -> None:
    """Run the state machine class ``machine`` over ``max_examples`` sequences of up to
    ``steps`` steps (derandomized: the same sequences in every CI run; no deadline)."""
    run_state_machine_as_test(
        machine,
        settings=settings(
            max_examples=max_examples,
            stateful_step_count=steps,
            deadline=None,
            derandomize=derandomize,
            suppress_health_check=list(HealthCheck),
        ),
    )
