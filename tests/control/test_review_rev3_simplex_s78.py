"""Review of `control.compat.check_simplex` (session 78): the public check of a Simplex alone
names an argument of the wrong kind, as `check_emulator` does (it raised AttributeError: 'str'
object has no attribute 'v_safe' / 'method' / 'domain')."""

import pytest

import control
from control.compat import check_simplex
from control.shipped import shipped_emulator


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (("emu", None), r"simplex must be a control\.Simplex, got None"),
        (("emu", "Simplex()"), r"simplex must be a control\.Simplex, got 'Simplex\(\)' \(str\)"),
        (("emu", "simplex", "window"), r"bcr must be a control\.BCRSettings, got 'window'"),
        (("A", "simplex"), r"emulator must be a gpmsa\.Emulator .* got 'A' \(str\)"),
        ((None, "simplex"), r"emulator must be a gpmsa\.Emulator .* got None"),
    ],
)
def test_check_simplex_names_an_argument_of_the_wrong_kind(args, match):
    given = {"emu": shipped_emulator("A", "window"), "simplex": control.Simplex()}
    with pytest.raises(control.ControlError, match=match):
        check_simplex(*(given.get(a, a) if isinstance(a, str) else a for a in args))


def test_check_simplex_still_checks_a_good_simplex():
    emu = shipped_emulator("A", "window")
    check_simplex(emu, control.Simplex())  # the paper's band: inside the domain, no warning
    with pytest.raises(control.EmulatorMismatchError, match="gd_max = 700 is not below"):
        check_simplex(emu, control.Simplex(gd_max=700.0))
