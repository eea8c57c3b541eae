"""The dask worker check (`gpmsa.mcmc.parallel`) reads every worker on distributed releases
before 2025.4, whose ``Client.scheduler_info`` takes no ``n_workers`` (it listed all)."""

import pytest

from gpmsa.mcmc import parallel

WORKERS = {f"tcp://127.0.0.1:{4000 + i}": {"name": i} for i in range(7)}


class _OldClient:
    """``scheduler_info`` as distributed 2025.3 and earlier have it: no arguments."""

    def scheduler_info(self):
        return {"workers": dict(WORKERS)}


class _NewClient:
    """distributed 2025.4 and later: 5 workers unless asked n_workers=-1."""

    def scheduler_info(self, n_workers=5):
        keys = list(WORKERS) if n_workers == -1 else list(WORKERS)[:n_workers]
        return {"workers": {k: WORKERS[k] for k in keys}}


@pytest.mark.parametrize("client", [_OldClient(), _NewClient()], ids=["before-2025.4", "2025.4"])
def test_every_worker_is_read_on_old_and_new_distributed(client):
    assert parallel._all_workers(client) == WORKERS


def test_another_type_error_is_not_hidden():
    class _Broken:
        def scheduler_info(self, n_workers=5):
            raise TypeError("unsupported operand")

    with pytest.raises(TypeError, match="unsupported operand"):
        parallel._all_workers(_Broken())
