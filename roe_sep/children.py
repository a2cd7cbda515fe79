"""Child processes that never outlive their parent, whatever ends it (SIGTERM, SIGINT, SIGHUP, even SIGKILL).

Every process roe_sep starts (the node processes of ``roe-sep run``, the Foxglove view of ``roe-sep replay
--foxglove``, the run processes of ``roe-sep campaign``) is started by :func:`spawn`:

* in a process group of its own (pgid = pid; the session, hence the scheduler's autogroup, stays the parent's): a
  terminal's Ctrl-C or hang-up reaches the parent alone, which stops its children in its own order (``roe-sep run``:
  the recorder last, so that the bag is closed) instead of every process being hit at once;
* with ``PR_SET_PDEATHSIG`` (prctl(2), Linux) set in the child before it runs its program: when the parent dies,
  however it dies, the kernel sends the child ``death_signal`` (SIGTERM by default: a node stops as on a Ctrl-C).
  The kernel ties it to the parent *thread* that started the child, which must therefore outlive it (the parents
  here wait for their children in that thread).

The parent runs under :func:`guarded` (``roe-sep run``, ``replay``, ``campaign``): SIGTERM, SIGHUP and SIGINT
raise :class:`Interrupted`, a KeyboardInterrupt, so that the parent's own Ctrl-C path stops its children (in order)
whatever the signal; on leaving the block, a child of :func:`spawn` still running has its process group sent SIGTERM,
and SIGKILL :data:`GRACE` s later (further signals are then ignored: the cleanup is not cut short).
"""

import contextlib
import ctypes
import os
import signal
import subprocess
import sys
import time

from .errors import Interrupted  # noqa: F401  (re-exported: a stop signal, raised by guarded())

SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)  # what stops a parent under guarded()
GRACE = 20.0  # s from SIGTERM to SIGKILL for a child left running when the parent leaves guarded()
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>

_prctl = ctypes.CDLL(None, use_errno=True).prctl if sys.platform.startswith("linux") else None
_started = []  # the children spawn() started in this process (Popen), the finished ones dropped on the next spawn


def die_with(parent, death_signal):
    """In a just-forked child: the kernel sends ``death_signal`` when the parent (pid ``parent``) ends. Only a call
    of the already loaded libc function and two system calls: nothing that could wait for a lock another thread of
    the parent held at the fork."""
    if _prctl is not None:
        _prctl(PR_SET_PDEATHSIG, int(death_signal), 0, 0, 0)
    if os.getppid() != parent:  # the parent ended before prctl: the signal it would have sent, now
        os.kill(os.getpid(), int(death_signal))


def _die_with(parent, death_signal):
    """:func:`die_with` as a ``preexec_fn`` (run between fork and exec)."""
    return lambda: die_with(parent, death_signal)


def spawn(cmd, death_signal=signal.SIGTERM, **popen_kwargs) -> subprocess.Popen:
    """``subprocess.Popen(cmd, **popen_kwargs)`` in a process group of its own (pgid = pid) that receives
    ``death_signal`` when this process (the calling thread) ends. Its stdin is /dev/null unless given: a background
    group that read the terminal would be stopped (SIGTTIN)."""
    _started[:] = [p for p in _started if p.poll() is None]
    popen_kwargs.setdefault("stdin", subprocess.DEVNULL)
    proc = subprocess.Popen(cmd, process_group=0, preexec_fn=_die_with(os.getpid(), death_signal),
                            **popen_kwargs)
    _started.append(proc)
    return proc


def running():
    """The children :func:`spawn` started that are still running."""
    return [p for p in _started if p.poll() is None]


def stop_group(proc, grace=GRACE):
    """SIGTERM to ``proc``'s process group, SIGKILL after ``grace`` s; returns its exit status."""
    for sig, wait in ((signal.SIGTERM, grace), (signal.SIGKILL, None)):
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(proc.pid, sig)
        try:
            return proc.wait(timeout=wait)
        except subprocess.TimeoutExpired:
            continue
    return proc.returncode


@contextlib.contextmanager
def guarded(grace=GRACE):
    """The block of a parent of :func:`spawn` children: SIGINT/SIGTERM/SIGHUP raise :class:`Interrupted`; on leaving
    (normally, by an exception or by a signal) the children still running are stopped (:func:`stop_group`). The
    signal handlers in place before are restored."""
    def interrupt(signum, frame):  # noqa: ARG001
        raise Interrupted(signum)

    before = {sig: signal.getsignal(sig) for sig in SIGNALS}
    for sig in SIGNALS:
        signal.signal(sig, interrupt)
    try:
        yield
    finally:
        for sig in SIGNALS:  # the cleanup runs to its end
            signal.signal(sig, signal.SIG_IGN)
        try:
            deadline = time.monotonic() + grace
            for proc in running():
                stop_group(proc, max(0.0, deadline - time.monotonic()))
        finally:
            for sig, handler in before.items():
                signal.signal(sig, handler)


def exit_status(exc: KeyboardInterrupt) -> int:
    """The exit status of a process stopped by ``exc``: ``128 + signum`` (130 for a Ctrl-C)."""
    return 128 + getattr(exc, "signum", signal.SIGINT)
