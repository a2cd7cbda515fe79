"""The end of a roe_sep process that used ROS, without the 0.1 s Fast DDS sleeps there.

Fast DDS 2.14 (the RMW of ROS 2 Jazzy) deletes its ``DomainParticipantFactory`` singleton in a C++ static
destructor when the process exits, and that destructor sleeps 100 ms before it stops its log thread
(``std::this_thread::sleep_for(std::chrono::milliseconds(100))`` in
``src/cpp/fastdds/domain/DomainParticipantFactory.cpp``; seen in gdb at the ``exit`` of every rclpy process here).
``roe-sep run`` waits for three such exits one after the other: the closed loop's process, the listeners', then its
own, about 0.4 s of wall time spent sleeping.

:func:`exit_process` ends the process as Python's exit does, up to that C-level teardown: a garbage collection
(the nodes left in reference cycles go, and with the last one rmw deletes the process's DDS participant: the other
participants see it leave at once, and its shared-memory segment in /dev/shm goes), the exit handlers (``atexit``:
logging, temporary directories, weak-reference finalizers), Python's and C's standard streams flushed, then
``os._exit``. Only a process's last line calls it (``python -m roe_sep.nodes...``, the ``roe-sep`` command), and it
skips the teardown only when nothing needs it: ROS used and every context shut down, no thread left but the main
thread and daemon threads (Python would wait for the others). Otherwise it is ``sys.exit``.
"""

import atexit
import ctypes
import gc
import os
import sys
import threading


def can_skip_teardown() -> bool:
    """True when ROS was used here, every context is shut down, and only daemon threads run beside the main one."""
    rclpy = sys.modules.get("rclpy")
    if rclpy is None:  # no ROS here: nothing to gain
        return False
    try:
        if rclpy.ok():
            return False
    except Exception:  # noqa: BLE001 -- an rclpy half torn down: leave it to the normal exit
        return False
    main = threading.main_thread()
    return all(t is main or t.daemon for t in threading.enumerate())


def exit_process(code):
    """End this process with exit status ``code`` (``sys.exit``'s meaning), skipping Python's and C's teardown when
    :func:`can_skip_teardown` (module docstring). Never returns."""
    if not isinstance(code, int) or isinstance(code, bool) or not can_skip_teardown():
        sys.exit(code)
    end_now(code, exit_handlers=True, c_stdio=True)


def end_now(code: int, *, exit_handlers: bool, c_stdio: bool):
    """``os._exit(code)`` after a garbage collection, the ``atexit`` handlers if ``exit_handlers``, Python's standard
    streams flushed, and C's if ``c_stdio``. The one end of a process that skips the interpreter's teardown:
    :func:`exit_process`, and a forked campaign run (:mod:`roe_sep.campaign.forkserver`, without the handlers and
    C buffers it inherited from the fork server). Never returns."""
    # the nodes, executors and entities of the process are garbage in reference cycles (a node's callbacks are its
    # bound methods): collected, their rcl handles go, and with the last node rmw deletes the DDS participant (its
    # shared-memory segment in /dev/shm with it; skipped, a suite of managed nodes, and every forked run, left its
    # segment behind)
    gc.collect()
    if exit_handlers:
        atexit._run_exitfuncs()  # noqa: SLF001 -- the handlers Python's own exit runs first
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except Exception:  # noqa: BLE001 -- a closed stream (a reader that went away): nothing to flush to
            pass
    if c_stdio:
        ctypes.CDLL(None).fflush(None)  # C's stdio: what a library printed through it
    os._exit(code & 0xFF)
