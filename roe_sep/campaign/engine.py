"""The Dask client of a campaign: the shared engine of :mod:`roe_sep.engine` (the streamed Monte Carlo uses it too).

An embedded :class:`distributed.LocalCluster` by default: ``workers`` worker *processes* with one thread each (a run
is itself a handful of node processes; one run per worker keeps a 2-core machine from thrashing), bound to
127.0.0.1, no dashboard. With ``scheduler`` (``tcp://host:port``) the client joins an existing cluster instead.
"""

import contextlib

from ..engine import cluster


@contextlib.contextmanager
def dask_client(workers=None, scheduler=None):
    """Yield a ``distributed.Client`` (a campaign always runs on Dask: one local worker when nothing is given); the
    embedded cluster (if any) is closed on exit, also on Ctrl-C."""
    with cluster(workers=None if scheduler else int(workers or 1), scheduler=scheduler or None) as client:
        yield client
