"""``os.fsync`` in tests: make it fail for folders or files, as a disk or file system would."""

from __future__ import annotations

import errno
import os
import stat

_REAL_FSYNC = os.fsync


def fail_fsync(monkeypatch, module, *, of: str = "folder", code: int = errno.EIO) -> None:
    """``module.os.fsync`` raises OSError ``code`` (its errno message) for a descriptor of a
    folder (``of="folder"``) or of a regular file (``of="file"``) and syncs any other."""
    is_kind = stat.S_ISDIR if of == "folder" else stat.S_ISREG

    def fsync(fd):
        if is_kind(os.fstat(fd).st_mode):
            raise OSError(code, os.strerror(code))
        _REAL_FSYNC(fd)

    monkeypatch.setattr(module.os, "fsync", fsync)


def record_folder_fsyncs(monkeypatch, module, *, fail_inode: int | None = None) -> list[int]:
    """The inodes of the folders ``module.os.fsync`` flushes from now on, in order; the fsync
    of folder ``fail_inode`` (None: none) raises OSError EIO after it is recorded."""
    flushed: list[int] = []

    def fsync(fd):
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            flushed.append(st.st_ino)
            if st.st_ino == fail_inode:
                raise OSError(errno.EIO, os.strerror(errno.EIO))
        _REAL_FSYNC(fd)

    monkeypatch.setattr(module.os, "fsync", fsync)
    return flushed
