"""The distributed engine: Dask for any embarrassingly parallel campaign of roe_sep (the streamed Monte Carlo of
``roe-sep mc``/``roe-sep collision``; closed-loop run campaigns reuse it).

Two calls::

    with cluster(workers=W, scheduler=ADDRESS) as client:     # client is None: in-process, no Dask
        for result in ordered_map(client, fn, items, *args):  # fn(item, *args), yielded in the order of items
            total.merge(result)                               # ordered reduction: deterministic

* :func:`cluster`: ``workers=W`` starts an embedded ``distributed.LocalCluster`` of W single-threaded worker
  *processes* bound to 127.0.0.1 with the dashboard off; ``scheduler="tcp://host:port"`` connects to an existing
  scheduler; neither runs everything in this process.
* :func:`ordered_map`: submits at most ``max_in_flight`` tasks at a time (default twice the cluster's threads),
  so neither the scheduler nor this process ever holds more than that many results, whatever the number of items;
  results are yielded strictly in item order (out-of-order completions wait in a bounded buffer). With the items
  chosen so that each result depends on its item alone (e.g. a block index that seeds its own random numbers), the
  reduction is identical for every worker count. ``batch=B`` packs B consecutive items into one task (the
  scheduler's per-task cost, a few ms in this process, matters for thousands of short items; :func:`auto_batch`);
  the results are still yielded one per item. ``ordered=False`` yields ``(index, result)`` as completed, for
  consumers that store each result at once (a resumable campaign).

A task that raises re-raises here with the worker's exception; the cluster is closed on exit in every case.
"""

import contextlib
import logging

from ..errors import show

__all__ = ["cluster", "ordered_map", "client_threads", "auto_batch"]


#: Dask settings of the embedded cluster: off, what only the dashboard (off too) shows. Each worker's statistical
#: profiler samples its threads' stacks 100 times a second and the system monitors poll psutil (disk counters
#: included) twice a second: 0.8 CPU-s per worker per 30 s of an idle worker, 0.45 without them.
QUIET = {"distributed.worker.profile.enabled": False, "distributed.admin.system-monitor.interval": "5s",
         "distributed.admin.system-monitor.disk": False}


@contextlib.contextmanager
def cluster(workers=None, scheduler=None, connect_timeout=10.0):
    """A Dask client (``workers`` local processes or the scheduler at ``scheduler``), or ``None`` for in-process."""
    if workers is not None and scheduler is not None:
        raise ValueError("--workers and --scheduler exclude each other: give one of them")
    if workers is None and scheduler is None:
        yield None
        return
    import dask
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout=connect_timeout)
        except (OSError, TimeoutError, ValueError) as exc:
            raise ValueError(f"--scheduler {scheduler!r}: cannot connect ({exc.__class__.__name__}: {exc})") from None
        with client:
            yield client
        return
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"--workers must be a positive integer, got {show(workers)}")
    # dashboard off; the scheduler's plain HTTP routes (health, metrics) on a free port of 127.0.0.1, not 8787
    with dask.config.set(QUIET), LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None, scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                      silence_logs=logging.CRITICAL) as lc, Client(lc) as client:
        yield client


def client_threads(client):
    """Total worker threads of ``client`` (1 in-process)."""
    return 1 if client is None else max(1, sum(client.nthreads().values()))


def _apply_batch(batch, fn, *args):
    """One task of :func:`ordered_map` with ``batch > 1``: ``fn`` on consecutive items, the results in order."""
    return [fn(item, *args) for item in batch]


def auto_batch(client, n_items, tasks_per_thread=32):
    """Items per task for ``n_items`` short items: about ``tasks_per_thread`` tasks per worker thread (1 in-process).
    Each Dask task costs the scheduler in this process a few ms; with 5,000 chunks of a 10^8-sample Monte Carlo
    that overhead was a quarter of the workers' CPU time."""
    if client is None:
        return 1
    return max(1, n_items // (tasks_per_thread * client_threads(client)))


def ordered_map(client, fn, items, *args, max_in_flight=None, ordered=True, batch=1):
    """Yield ``fn(item, *args)`` for every item, in item order (``ordered=False``: ``(index, result)`` as they
    complete), computed on ``client`` (or here when it is ``None``) with at most ``max_in_flight`` tasks pending.

    ``batch > 1`` sends ``batch`` consecutive items per task (fewer, longer tasks); the results are yielded one by
    one exactly as without it."""
    items = list(items)
    if client is None:
        for i, item in enumerate(items):
            yield fn(item, *args) if ordered else (i, fn(item, *args))
        return
    if isinstance(batch, bool) or not isinstance(batch, int) or batch < 1:
        raise ValueError(f"batch must be a positive integer, got {show(batch)}")
    if batch > 1:
        groups = [items[i:i + batch] for i in range(0, len(items), batch)]
        for res in ordered_map(client, _apply_batch, groups, fn, *args, max_in_flight=max_in_flight,
                               ordered=ordered):
            if ordered:
                yield from res
            else:
                g, results = res
                yield from ((g * batch + j, r) for j, r in enumerate(results))
        return
    from distributed import as_completed

    limit = max_in_flight or 2 * client_threads(client)
    index_of, buffer = {}, {}
    pending = as_completed()
    next_submit = next_yield = 0

    def submit():
        nonlocal next_submit
        fut = client.submit(fn, items[next_submit], *args, pure=False)
        index_of[fut.key] = next_submit
        pending.add(fut)
        next_submit += 1

    try:
        while next_submit < len(items) and next_submit - next_yield < limit:
            submit()
        for fut in pending:
            i = index_of.pop(fut.key)
            result = fut.result()
            fut.release()
            if not ordered:
                next_yield += 1
                yield i, result
            else:
                buffer[i] = result
                while next_yield in buffer:
                    yield buffer.pop(next_yield)
                    next_yield += 1
            while next_submit < len(items) and next_submit - next_yield < limit:
                submit()
    finally:
        for fut in list(pending.futures):
            fut.cancel()
