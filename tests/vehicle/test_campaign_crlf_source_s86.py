"""A campaign cache's key names the code that computed its runs (`code_fingerprint`, the
source of roadgen and vehicle): a checkout whose line ends are CRLF (git's autocrlf, the
default of git for Windows) is the same code as an LF one.

Before: its fingerprint differed, so a campaign cache written on Linux or macOS and shared
with a Windows checkout was never read there (every run simulated again), and back."""

from pathlib import Path

import roadgen
from vehicle import campaign


def _copy(src, dst, crlf: bool) -> None:
    dst.mkdir(parents=True)
    for source in src.glob("*.py"):  # the files `code_fingerprint` reads
        raw = source.read_bytes()
        (dst / source.name).write_bytes(raw.replace(b"\n", b"\r\n") if crlf else raw)


def test_crlf_line_ends_give_the_lf_fingerprint(tmp_path, monkeypatch):
    fingerprints = []
    for crlf in (False, True):
        root = tmp_path / ("crlf" if crlf else "lf")
        for module in (roadgen, campaign):
            folder = root / module.__name__.split(".")[0]
            _copy(Path(module.__file__).parent, folder, crlf)
            monkeypatch.setattr(module, "__file__", str(folder / "x.py"))
        fingerprints.append(campaign.code_fingerprint.__wrapped__())
        monkeypatch.undo()
    assert fingerprints[0] == fingerprints[1] == campaign.code_fingerprint()
