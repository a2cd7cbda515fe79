"""The Dask client of a campaign, in one place (to be switched to the shared :mod:`roe_sep.engine` when it lands).

An embedded :class:`distributed.LocalCluster` by default: ``workers`` worker *processes* with one thread each (a run
is itself a handful of node processes; one run per worker keeps a 2-core machine from thrashing), bound to
127.0.0.1, no dashboard. With ``scheduler`` (``tcp://host:port``) the client joins an existing cluster instead.
"""

import contextlib


@contextlib.contextmanager
def dask_client(workers=None, scheduler=None):
    """Yield a ``distributed.Client``; the embedded cluster (if any) is closed on exit, also on Ctrl-C."""
    from distributed import Client, LocalCluster

    if scheduler:
        with Client(scheduler, timeout="30s") as client:
            yield client
        return
    with LocalCluster(n_workers=int(workers or 1), threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None, silence_logs=40) as cluster, Client(cluster) as client:
        yield client
