"""Review (session 76, rev3): a zip without manifest.json is guessed to be a numpy .npz (a
vehicle campaign file) only where its first member is a .npy; an empty zip, or another kind of
zip (an office document), was called "a numpy .npz such as a vehicle campaign file?"."""

import zipfile

import pytest

from gpmsa.cli.main import main


@pytest.mark.parametrize(
    ("members", "said", "not_said"),
    [
        ([], "not a gpmsa emulator file (an empty zip: no manifest.json)", "npz"),
        ([("[Content_Types].xml", b"<x/>")],
         "a zip without manifest.json; its first member '[Content_Types].xml')", "npz"),
        ([("dir/", b""), ("dir/manifest.json", b"{}")],
         "a zip without manifest.json; its first member 'dir/')", "npz"),
        ([("settings.npy", b"x")], "its first member 'settings.npy': a numpy .npz such as a "
                                   "vehicle campaign file?)", None),
    ],
)  # fmt: skip
def test_a_zip_without_a_manifest_is_named_for_what_it_holds(tmp_path, capsys, members, said,
                                                              not_said):  # fmt: skip
    path = tmp_path / "f.gpmsa"
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in members:
            zf.writestr(name, data)
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err
    assert said in err and err.count("\n") == 1
    assert not_said is None or not_said not in err


def test_a_hostile_member_beside_a_manifest_is_still_named(tmp_path):
    from gpmsa.errors import EmulatorFileError
    from gpmsa.io.container import read_raw

    path = tmp_path / "f.gpmsa"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("manifest.json", b"{}")
        zf.writestr("../evil.npy", b"x")
    with pytest.raises(EmulatorFileError, match=r"unexpected member '\.\./evil\.npy'"):
        read_raw(path)
