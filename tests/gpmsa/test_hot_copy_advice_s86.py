"""A tempered continuation's hot copies (``sample``'s ``hot_copies``) come from a fit's record
(or the library's own code), never from a CSV table: text there is named without the CSV
advice ("Read the file with pd.read_csv(..., na_values=...)") that a user's table gets."""

import copy

import pytest
from _tempering_cases import fit_two_mode

from gpmsa.errors import GPMSAError

pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")
SMALL = {"tune_rounds": 1, "tune_levels": 2}


def test_text_in_a_hot_copy_record_edited_in_memory_gets_no_csv_advice():
    src = fit_two_mode(n_iter=20, n_chains=2, seed=3, temperatures=3, n_jobs=1, **SMALL)
    name = next(iter(src.settings["hot_states"]))
    bad = copy.deepcopy(src)
    bad.settings["hot_states"][name] = "abc"
    with pytest.raises(GPMSAError, match=r"hot_copies\['starts'\]\[.*must be a numeric") as err:
        fit_two_mode(init=bad, n_iter=10, n_chains=2, seed=4, n_jobs=1, **SMALL)
    assert "read_csv" not in str(err.value) and "na_values" not in str(err.value)
