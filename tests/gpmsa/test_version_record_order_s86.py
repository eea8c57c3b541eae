"""The BLAS libraries a fit records (``library_versions()["blas"]``) read alike whatever order
threadpoolctl finds them in (numpy's and scipy's own OpenBLAS swapped places from one process
to the next, so two same-seed fits recorded different versions)."""

import threadpoolctl

from gpmsa._version import library_versions

LIBS = [
    {"user_api": "blas", "internal_api": "openblas", "version": "0.3.31", "architecture": "Haswell",
     "num_threads": 2},
    {"user_api": "blas", "internal_api": "openblas", "version": "0.3.30", "architecture": "Zen",
     "num_threads": 2},
    {"user_api": "openmp", "internal_api": "openmp", "version": None, "num_threads": 2},
]  # fmt: skip


def test_the_blas_record_does_not_depend_on_the_order_libraries_are_found(monkeypatch):
    seen = []
    for libs in (LIBS, LIBS[::-1]):
        monkeypatch.setattr(threadpoolctl, "threadpool_info", lambda libs=libs: libs)
        seen.append(library_versions()["blas"])
    assert seen[0] == seen[1]
    assert seen[0] == "openblas 0.3.30 (Zen, 2 threads); openblas 0.3.31 (Haswell, 2 threads)"
