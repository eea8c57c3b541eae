"""Every text file the library opens names its encoding (session 85): Python's default is the
locale's (cp1252 on a Windows host, latin-1 under an ISO-8859-1 locale), so a file read
without one is decoded differently by host. Before: a ROS 2 bag folder's metadata.yaml was read
with the locale's encoding (a non-ASCII storage file name came back garbled)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("gpmsa", "control", "vehicle", "roadgen")


def _text_calls_without_encoding(tree: ast.AST) -> list[int]:
    """Lines of ``open(...)`` in a text mode, ``os.fdopen`` in a text mode, and
    ``.read_text()`` / ``.write_text()`` calls that give no ``encoding=``."""
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call) or any(k.arg == "encoding" for k in node.keywords):
            continue
        func = node.func
        name = func.id if isinstance(func, ast.Name) else getattr(func, "attr", "")
        if name in ("read_text", "write_text") and isinstance(func, ast.Attribute):
            found.append(node.lineno)
        elif (name == "open" and isinstance(func, ast.Name)) or name == "fdopen":
            mode = node.args[1] if len(node.args) > 1 else None
            mode = next((k.value for k in node.keywords if k.arg == "mode"), mode)
            literal = isinstance(mode, ast.Constant) and isinstance(mode.value, str)
            if mode is None or (literal and "b" not in mode.value):
                found.append(node.lineno)
    return found


@pytest.mark.parametrize("package", PACKAGES)
def test_the_library_names_the_encoding_of_every_text_file(package):
    offenders = [
        f"{path.relative_to(REPO)}:{line}"
        for path in sorted((REPO / package).rglob("*.py"))
        for line in _text_calls_without_encoding(ast.parse(path.read_text(encoding="utf-8")))
    ]
    assert offenders == []


def test_the_check_sees_each_form():
    source = (
        "open(p)\nopen(p, 'w')\nopen(p, mode='r')\nopen(p, 'rb')\nopen(p, encoding='utf-8')\n"
        "p.read_text()\np.write_text(s)\np.read_text(encoding='utf-8')\nos.fdopen(fd, 'w+')\n"
        "zf.open(name)\n"
    )
    assert _text_calls_without_encoding(ast.parse(source)) == [1, 2, 3, 6, 7, 9]


def test_a_bag_folder_s_metadata_is_read_as_utf8_whatever_the_locale(tmp_path, monkeypatch):
    from control.robot import bags

    pytest.importorskip("ruamel.yaml")
    (tmp_path / "metadata.yaml").write_text(
        "rosbag2_bagfile_information:\n  relative_file_paths: [données_0.mcap]\n"
        "  storage_identifier: mcap\n",
        encoding="utf-8",
    )

    def latin1_host(self, encoding=None, errors=None):  # the locale's default, ISO-8859-1
        return self.read_bytes().decode(encoding or "latin-1", errors or "strict")

    monkeypatch.setattr(Path, "read_text", latin1_host)
    info = bags._bag_information(tmp_path)
    assert info["relative_file_paths"] == ["données_0.mcap"]
