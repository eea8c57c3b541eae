"""Equality and hashing of gpmsa's records of arrays (session 82): ``LooResult`` and ``Chains``
compared with ``==`` raised "truth value of an array is ambiguous" (a pickled or deep-copied
one against its original) and hashing them raised; as the package's other results of arrays
(Posterior, CrossValidation, the predictions), they compare by identity."""

import copy
import pickle

import numpy as np

from gpmsa import Chains, LooResult


def _loo() -> LooResult:
    return LooResult(np.ones((3, 2)), np.ones((3, 2)), np.zeros((3, 2)), np.ones(2), 0.95)


def _chains() -> Chains:
    draws = {"theta": np.arange(6.0).reshape(2, 3, 1)}
    return Chains(draws, np.zeros((2, 3)), {"theta": np.ones((2, 1))}, {"theta": np.ones((2, 1))})


def test_a_loo_result_and_chains_compare_by_identity_and_hash():
    for record in (_loo(), _chains()):
        for twin in (copy.deepcopy(record), pickle.loads(pickle.dumps(record, 2)),
                     pickle.loads(pickle.dumps(record, pickle.HIGHEST_PROTOCOL))):  # fmt: skip
            assert record == record and record != twin and len({record, twin, record}) == 2
    back = pickle.loads(pickle.dumps(_loo()))
    np.testing.assert_array_equal(back.rmse, np.ones(2))
    assert back.coverage95 == 0.95
