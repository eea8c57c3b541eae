"""A refused list of probabilities is named by its first bad entry, not printed whole."""

import numpy as np
import pytest

from gpmsa import GPMSAError
from gpmsa.model.data import check_probabilities


def test_a_long_list_names_its_first_bad_entry_and_stays_short():
    q = np.linspace(0.0, 1.0, 100_001)
    q[4_321] = 1.5
    q[9_000] = np.nan
    with pytest.raises(GPMSAError) as caught:
        check_probabilities(q)
    message = str(caught.value)
    assert message == (
        "q must lie in [0, 1], got 1.5 at index (4321,) (the first of 2 of 100001 values "
        "outside it)"
    )


def test_a_2d_array_names_the_position_of_its_first_bad_entry():
    q = np.full((30, 40), 0.5)
    q[7, 3] = -0.25
    with pytest.raises(
        GPMSAError,
        match=r"^q must lie in \[0, 1\], got -0.25 at index \(7, 3\) "
        r"\(the first of 1 of 1200 values outside it\)$",
    ):
        check_probabilities(q, "q")


def test_a_long_list_of_inf_is_named_by_its_first_inf():
    q = [0.5] * 20 + [float("-inf")]
    with pytest.raises(GPMSAError, match=r"got -inf at index \(20,\) \(the first of 1 of 21 "):
        check_probabilities(q, "probabilities")


@pytest.mark.parametrize(
    ("q", "shown"),
    [(1.5, "1.5"), ([0.2, 1.01], r"\[0.2, 1.01\]"), (list(np.full(10, 2.0)), r"\[np.float64")],
)
def test_ten_values_or_fewer_are_shown_as_given(q, shown):
    with pytest.raises(GPMSAError, match=rf"^q must lie in \[0, 1\], got {shown}"):
        check_probabilities(q)


def test_eleven_values_are_named_by_their_first_bad_entry():
    with pytest.raises(GPMSAError, match=r"got 2.0 at index \(0,\) \(the first of 11 of 11 "):
        check_probabilities([2.0] * 11)
