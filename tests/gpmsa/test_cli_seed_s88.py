"""`gpmsa calibrate --seed` with an integer of more digits than ``int()`` reads (4,300 by
default, ``sys.get_int_max_str_digits``): before, "'999...' is not an integer", echoing all its
digits (a 5,000-digit seed gave a 5,020-character line); it is an integer out of range."""

import pytest

from gpmsa.cli.main import main


@pytest.mark.parametrize(
    "seed", ["9" * 5000, "-" + "9" * 5000, " +" + "1_0" * 2000 + " "], ids=["big", "neg", "form"]
)
def test_a_seed_beyond_ints_digit_limit_is_out_of_range_not_no_integer(tmp_path, capsys, seed):
    with pytest.raises(SystemExit) as exit_:
        main(["calibrate", str(tmp_path / "absent.gpmsa"), "--x", "v=1", "--y", "f=1",
              "--seed", seed])  # fmt: skip
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "argument --seed: " in err and "is out of range: allowed integers in [0, 2**128)" in err
    assert "not an integer" not in err
    assert f"({len(seed)} characters)" in err and len(err) < 1000  # not every digit echoed


@pytest.mark.parametrize(
    ("seed", "why"),
    [("9" * 39, f"'{'9' * 39}' is out of range"), ("1e5" + "0" * 4400, "is not an integer")],
    ids=["39-digits", "no-integer"],
)
def test_a_seed_within_the_limit_or_no_integer_reads_as_before(tmp_path, capsys, seed, why):
    with pytest.raises(SystemExit):
        main(["calibrate", str(tmp_path / "absent.gpmsa"), "--x", "v=1", "--y", "f=1",
              "--seed", seed])  # fmt: skip
    assert why in capsys.readouterr().err
