"""Keep freed memory in the process: the vectorized Monte Carlo's temporaries cost page faults, not arithmetic.

Every numpy temporary above glibc's mmap threshold (128 kB at start; a (20000, 6) float array is 960 kB) is a
fresh ``mmap`` returned to the kernel on ``free``, and heap memory above the trim threshold is given back as well,
so the next temporary faults every one of its pages in again. On this machine (a VM, page faults of about 5 us)
that made a ``1e-6 * t + 1.0`` on 120,000 elements take 1.3 ms instead of 0.17 ms, and the streamed sweep spend
more time in the kernel than in numpy.

:func:`keep_freed_memory` raises glibc's mmap threshold to its maximum (32 MiB: larger arrays, e.g. chunks of 10^6
samples, still come from mmap and are returned) and the trim threshold to 1 GiB, so freed temporaries are reused
from the heap. The resident size then stays at the high-water mark of one chunk's working set, which is bounded
by the chunk size as before; the numbers computed are unchanged (allocation only). A no-op where the C library
is not glibc. Idempotent; called by every chunk evaluation, so it also acts inside Dask worker processes.
"""

import ctypes
import ctypes.util

M_TRIM_THRESHOLD = -1
M_MMAP_THRESHOLD = -3
MMAP_THRESHOLD = 32 * 1024 * 1024  # glibc's largest accepted value on 64-bit (HEAP_MAX_SIZE / 2)
TRIM_THRESHOLD = 1024 * 1024 * 1024
CLOSED_LOOP_TRIM_THRESHOLD = 64 * 1024 * 1024  # a closed-loop run's: see keep_freed_memory

_state = {"done": False, "active": False}


def keep_freed_memory(trim_threshold: int = TRIM_THRESHOLD) -> bool:
    """Tune glibc's allocator as described in the module docstring (once per process: the first call's
    ``trim_threshold`` [bytes] holds); True if it took effect.

    A campaign's closed-loop runs (forked from :mod:`roe_sep.campaign.forkserver`) take
    :data:`CLOSED_LOOP_TRIM_THRESHOLD`: without the tuning a run took about 260,000 page faults (0.7 CPU-s of system
    time, 20 runs of seeds 1000-1019), with it 73,000 and 0.35 CPU-s, at the same peak memory of the campaign's
    process tree (proportional set 823 against 804 MB); a 1 GiB threshold saved a little more (54,000 faults) for
    60 MB more per run."""
    if _state["done"]:
        return _state["active"]
    _state["done"] = True
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    _state["active"] = bool(mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(mallopt(M_TRIM_THRESHOLD,
                                                                                        int(trim_threshold)))
    return _state["active"]
