"""A warm start for a campaign's runs: one fork server per Dask worker thread, which has imported everything a run
imports (rclpy, the messages, NumPy/SciPy, heyoka, the nodes) and computed what is identical in every run of the
campaign (the planner's start-up Monte Carlo, :func:`roe_sep.core.montecarlo.sweep.p_best`), then forks one child per
run. A run so starts in a few milliseconds instead of paying about 1.5 CPU-s of imports and 0.7 CPU-s of sweep.

Nothing leaks between runs: every run is still a process of its own, forked from a server that never ran a node and
never initialised rclpy (no DDS participant, no Python thread, no context exists in it when it forks), so each run
starts from the same state, the one a fresh ``python -m roe_sep.campaign.child`` reaches after its imports. The
memoised sweep and truth integrator are pure functions of frozen inputs (the same floats whether computed here or in
the run). Two native thread pools exist in the server when it forks, and a run does not depend on them: OpenBLAS's
(NumPy's import; it re-creates its pool in a child, ``pthread_atfork``) and TBB's worker, left by heyoka's parallel
compilation of the integrator template. A run deep-copies that template; a run that compiles another integrator
does it on its own thread (TBB's caller runs the tasks: a forked child compiled one in 0.7 s, checked).
The run is the same code path (:func:`roe_sep.campaign.child.main`), in a process group of its own with its output
in its log file; the worker kills that group on a timeout. The kernel ends a run when its fork server dies and the
fork server when its worker dies (``PR_SET_PDEATHSIG``, :mod:`roe_sep.children`).

Protocol (JSON lines; the server is single-threaded and polls, so forking is safe):

* worker -> server: ``{"argv": [...], "log": PATH}``; server -> worker: ``{"pid": N}`` once forked, then
  ``{"exit": N, "code": C}`` when that child is reaped (C: its exit status, or -signal).
* ``{"warm": {"config": PATH|null, "params": PATH}}``: compute the start-up sweep the planner of a run with these
  settings will ask for (memoised in the server, inherited by every later fork); answered ``{"warm": true}``.
* End of input (the worker closed the pipe): the server exits, and the kernel ends a run still in progress.
"""

import gc
import json
import os
import select
import signal
import subprocess
import sys
import threading
import time

from ..children import die_with, spawn
from ..process_exit import end_now

POLL = 0.05  # s between checks of the request pipe and of exited children (a child's SIGCHLD wakes it sooner)


# ----------------------------------------------------------------------------------------------------- server side
def _warm(spec):
    """Fill the sweep memo with the planner's start-up sweep of a run with ``spec``'s config and node parameter
    overrides (a run whose planner asks for another sweep computes it itself: the memo only saves time)."""
    import yaml

    from ..core.config import load_scenario
    from ..nodes.parameters import table
    from ..nodes.planner import startup_p

    params = {}
    if spec.get("params"):
        with open(spec["params"], encoding="utf-8") as fh:
            params = ((yaml.safe_load(fh) or {}).get("planner") or {}).get("ros__parameters") or {}
    scenario = load_scenario(params.get("scenario_file") or spec.get("config") or None)
    defaults = table("planner")
    startup_p(scenario, *(params.get(k, defaults[k].default) for k in ("mc_samples", "mc_seed")))


def _warm_node_startup():
    """What every run's node start-up computed for itself (caches only: a run's nodes, messages and numbers are the
    same): the package of rclpy's message type supports (imported at the first publisher), the map of module files
    of :mod:`inspect` (rclpy's logging scans every loaded module at its first log call, to name the caller) and the
    simulator's compiled truth integrator (:func:`~roe_sep.core.truth.nonlinear.pair_integrator`, memoised: a run
    deep-copies the template) and the compiled CDR decoders of the inputs read raw
    (:func:`~roe_sep.nodes.serialized.decoder_for`). About 0.1 CPU-s per run."""
    import inspect

    import rosidl_generator_py  # noqa: F401
    from roe_sep_msgs.msg import LockstepAck, LockstepStep, RelativeOrbitalElements

    from ..core.truth.nonlinear import DEFAULT_TOL, Atmosphere, NonlinearTruth, pair_integrator
    from ..nodes.serialized import decoder_for

    for msg_type in (LockstepStep, LockstepAck, RelativeOrbitalElements):  # the raw inputs' compiled decoders
        decoder_for(msg_type)
    inspect.getframeinfo(inspect.currentframe())
    zonals = inspect.signature(NonlinearTruth).parameters["zonals"].default
    pair_integrator(zonals, None, DEFAULT_TOL, Atmosphere.kind)


def _child(argv, log, parent):
    """In the forked child: a process group of its own that dies with the server, output to ``log``, default signal
    dispositions; never returns."""
    code = 1
    try:
        os.setpgid(0, 0)
        die_with(parent, signal.SIGKILL)
        fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
        null = os.open(os.devnull, os.O_RDONLY)
        os.dup2(null, 0)
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        os.close(fd)
        os.close(null)
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGPIPE):
            signal.signal(sig, signal.SIG_DFL)
        sys.stdin = open(0, closefd=False)  # noqa: SIM115
        sys.stdout = open(1, "w", buffering=1, closefd=False)  # noqa: SIM115
        sys.stderr = open(2, "w", buffering=1, closefd=False)  # noqa: SIM115
        from .child import main

        code = main(argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    except BaseException as exc:  # noqa: BLE001  (the child's last word goes to its log, never up into the server)
        print(f"{type(exc).__name__}: {exc}", file=sys.stderr)
    finally:
        # never back into the server's loop: the run's garbage collected (its DDS participant and shared-memory
        # segment go), its output flushed, os._exit (not the server's atexit handlers; docs/developers.md)
        end_now(int(code) if isinstance(code, int) else 1, exit_handlers=False, c_stdio=False)


def preload():
    """What the server does once for all its runs: the heap setting, the imports of a run and its caches
    (:func:`_warm_node_startup`). A process that does this and then runs a scenario in process is a forked run's
    twin (``bench/profile_run.py --campaign-layout`` profiles one)."""
    # freed NumPy temporaries stay in the heap, inherited by every fork (allocation only, the numbers unchanged;
    # first, so that the warm sweep's streaming does not set the Monte Carlo's threshold)
    from ..core.montecarlo.allocator import CLOSED_LOOP_TRIM_THRESHOLD, keep_freed_memory

    keep_freed_memory(CLOSED_LOOP_TRIM_THRESHOLD)
    # What a run imports, imported once here (never initialised: rclpy.init happens in the forked run).
    import rclpy  # noqa: F401

    from .. import run  # noqa: F401
    from ..graph import NODES
    from ..nodes import suite

    for name in NODES:
        suite.node_class(name)
    # what a run loads on first use (the core imports them lazily: the ic_planner's LP, the OD consistency test)
    import scipy.optimize  # noqa: F401
    import scipy.sparse  # noqa: F401
    import scipy.special  # noqa: F401

    from .. import report  # noqa: F401
    from . import child  # noqa: F401

    _warm_node_startup()


def serve():
    """The server loop (``python -m roe_sep.campaign.forkserver``): read requests from stdin, answer on stdout."""
    preload()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the worker decides; a terminal's Ctrl-C goes to the worker
    # a child's exit wakes the loop at once (Python's wakeup fd), not at the next poll: the worker starts its next
    # run sooner
    wake_r, wake_w = os.pipe()
    os.set_blocking(wake_r, False)
    os.set_blocking(wake_w, False)
    signal.set_wakeup_fd(wake_w, warn_on_full_buffer=False)
    signal.signal(signal.SIGCHLD, lambda signum, frame: None)
    out = sys.stdout
    server_pid = os.getpid()
    children = set()
    buf = b""
    print(json.dumps({"ready": os.getpid()}), file=out, flush=True)
    while True:
        ready, _, _ = select.select([0, wake_r], [], [], POLL)
        if wake_r in ready:
            ready.remove(wake_r)
            while True:
                try:
                    if not os.read(wake_r, 512):
                        break
                except BlockingIOError:
                    break
        while children:
            pid, status = os.waitpid(-1, os.WNOHANG)
            if pid == 0:
                break
            children.discard(pid)
            code = os.waitstatus_to_exitcode(status)
            print(json.dumps({"exit": pid, "code": code}), file=out, flush=True)
        if not ready:
            continue
        chunk = os.read(0, 65536)
        if not chunk:  # the worker closed the pipe or died
            return 0
        buf += chunk
        while b"\n" in buf:
            line, buf = buf.split(b"\n", 1)
            req = json.loads(line)
            if "warm" in req:
                _warm(req["warm"])
                print(json.dumps({"warm": True}), file=out, flush=True)
                continue
            out.flush()
            # the server's objects out of the collector's sight in the child (gc.freeze's use): its collections, the
            # last one before its os._exit too (process_exit.end_now), walk the run's objects only, and write to no
            # inherited page
            gc.freeze()
            pid = os.fork()
            if pid == 0:
                signal.set_wakeup_fd(-1)
                signal.signal(signal.SIGCHLD, signal.SIG_DFL)
                os.close(wake_r)
                os.close(wake_w)
                _child(req["argv"], req["log"], server_pid)
            children.add(pid)
            print(json.dumps({"pid": pid}), file=out, flush=True)


# ----------------------------------------------------------------------------------------------------- worker side
class ForkServer:
    """The worker's handle on its fork server (started on first use; one per worker thread, see :func:`server`)."""

    def __init__(self):
        self.proc = spawn([sys.executable, "-m", "roe_sep.campaign.forkserver"], death_signal=signal.SIGKILL,
                          stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        self.buf = b""
        self.exits = {}
        self._expect("ready")

    def _line(self, timeout=None):
        deadline = None if timeout is None else time.monotonic() + timeout
        while b"\n" not in self.buf:
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            ready, _, _ = select.select([self.proc.stdout], [], [], left)
            if not ready:
                return None
            chunk = os.read(self.proc.stdout.fileno(), 65536)
            if not chunk:
                raise RuntimeError(f"the fork server exited (status {self.proc.wait()})")
            self.buf += chunk
        line, self.buf = self.buf.split(b"\n", 1)
        return json.loads(line)

    def _send(self, req):
        try:
            self.proc.stdin.write(json.dumps(req).encode("utf-8") + b"\n")
            self.proc.stdin.flush()
        except (BrokenPipeError, OSError) as exc:
            raise RuntimeError(f"the fork server is gone ({exc})") from None

    def _expect(self, key, timeout=None):
        while True:
            msg = self._line(timeout)
            if msg is None:
                raise RuntimeError(f"no '{key}' from the fork server within {timeout} s")
            if "exit" in msg and key != "exit":
                self.exits[msg["exit"]] = msg["code"]
                continue
            if key not in msg:
                raise RuntimeError(f"the fork server answered {msg}")
            return msg

    def warm(self, config, params):
        """Have the server compute the start-up sweep of runs with this config and params file (a memo hit, a few
        milliseconds, once it has)."""
        self._send({"warm": {"config": config, "params": params}})
        self._expect("warm")

    def spawn(self, argv, log):
        """Fork a run (``roe_sep.campaign.child`` arguments ``argv``, output appended to ``log``): its handle."""
        self._send({"argv": list(argv), "log": str(log)})
        return Run(self, self._expect("pid")["pid"])

    def close(self):
        if self.proc.poll() is None:
            self.proc.stdin.close()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()


class Run:
    """A forked run, with the ``pid``/``poll``/``wait`` of a :class:`subprocess.Popen` (its pid is its group's)."""

    def __init__(self, srv: ForkServer, pid: int):
        self.srv, self.pid, self.returncode = srv, pid, None

    def poll(self):
        if self.returncode is None:
            try:
                self.wait(timeout=0.0)
            except subprocess.TimeoutExpired:
                pass
        return self.returncode

    def wait(self, timeout=None):
        deadline = None if timeout is None else time.monotonic() + timeout
        while self.pid not in self.srv.exits:
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                raise subprocess.TimeoutExpired(f"run {self.pid}", timeout)
            msg = self.srv._line(left)
            if msg is None:
                continue
            if "exit" not in msg:
                raise RuntimeError(f"the fork server answered {msg} while a run was under way")
            self.srv.exits[msg["exit"]] = msg["code"]
        self.returncode = self.srv.exits.pop(self.pid)
        return self.returncode


_local = threading.local()


def server() -> ForkServer:
    """This worker thread's fork server, started on first use and again if it died."""
    srv = getattr(_local, "server", None)
    if srv is None or srv.proc.poll() is not None:
        srv = _local.server = ForkServer()
    return srv


if __name__ == "__main__":
    raise SystemExit(serve())
