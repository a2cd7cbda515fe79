"""How every roe_sep process spins: init, construct, spin until SIGINT/SIGTERM, drain, clean shutdown, exit code.

One life cycle (:func:`serve`) for a node alone (:func:`run`, the ``main()`` of each node, the lifecycle manager's
too) and for several nodes on one executor (:mod:`roe_sep.nodes.suite`); nothing waits outside the spin:

* rclpy's own signal handler is off. SIGINT/SIGTERM only set a flag that the loop checks between short slices of
  spinning (:data:`SLICE`, ``spin_until_future_complete`` on a future that a wall-clock timer completes once the
  flag is set or ``until()`` is true: the executor runs the callbacks of a slice without returning to this loop
  for each one, and the EventsExecutor's slice outlasts its timeout while its queue never empties, as in a
  lockstep run in one process): a signal never interrupts a callback halfway,
  and the context is never shut down under an executor that is building its wait set (rclpy's handler does that,
  and the executor then raises ``RCLError: the given context is not valid`` instead of exiting cleanly). The
  EventsExecutor's C++ ``spin()`` would not let Python's handlers run at all.
* After the stop request the process **drains**: messages DDS already delivered to it are still handled, so the
  recorder logs the last status a simulator published just before it was stopped, and the ground_bridge's final
  CCSDS set includes it. A node that counts what it receives (an int attribute ``messages_received``) keeps the
  drain going while the count rises, until :data:`DRAIN_IDLE` s pass without a message (at most
  :data:`DRAIN_MAX` s; a second signal ends it at once). When ``until`` ends the spin, every node that publishes is
  in this process, and Fast DDS hands a message to a reader of its own participant within the publisher's
  ``publish()`` call: nothing is then on its way from another process, and :data:`DRAIN_IDLE_LOCAL` s of quiet
  suffice (a run in one process: 0.3 s less idle time per campaign run), over at least :data:`DRAIN_QUIET_SPINS`
  spins (the EventsExecutor runs its queued callbacks in the order of arrival, one per spin, so a quiet measured
  in spins as well as in wall time is not ended by the process being descheduled).
"""

import os
import re
import signal
import sys
import tempfile
import time
import traceback

import rclpy
from rclpy.clock import Clock, ClockType
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future

from ..errors import RosArgumentsError
from .params import ParameterError, help_requested, node_table, print_usage

DRAIN_IDLE = 0.3  # s (wall) without a new message that ends the drain
DRAIN_IDLE_LOCAL = 0.05  # s (wall), the same when every publisher is in this process (``until`` ended the spin)
DRAIN_QUIET_SPINS = 10  # and, then, at least this many spins in a row without a message
DRAIN_MAX = 10.0  # s (wall), at most
SLICE = 0.1  # s (wall) of spinning between two checks of the stop request, the context and ``until``
ACK_WAIT = 2.0  # s (wall), at most, for the readers of a process's reliable publishers to acknowledge everything


def ros_arguments_error(exc, args=None) -> str:
    """One line for rcl's refusal of the ROS arguments (rclpy raises an RCLError with rcl's source locations)."""
    argv = list(sys.argv if args is None else args)
    for k, arg in enumerate(argv[:-1]):
        if arg == "--params-file" and not os.path.isfile(argv[k + 1]):
            return f"--params-file {argv[k + 1]}: no such file"
    text = str(exc).removeprefix("failed to initialize rcl: ")
    return re.sub(r"(, at [^,]+:\d+)+$", "", text)


def init(args=None):
    """``rclpy.init`` without rclpy's signal handler; until :func:`spin` takes over, SIGINT/SIGTERM raise
    KeyboardInterrupt (start-up stops at once, whatever the parent ignored: a background job's SIGINT).
    :class:`RosArgumentsError` (one line) when rcl refuses the ROS arguments; rcl's own log line about it (written
    to the stderr file descriptor) is then dropped, else passed on."""
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as captured:
        os.dup2(captured.fileno(), 2)
        try:
            rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
        except RuntimeError as exc:  # rclpy's RCLError (a RuntimeError)
            raise RosArgumentsError(ros_arguments_error(exc, args)) from None
        else:
            captured.seek(0)
            os.write(saved, captured.read())
        finally:
            os.dup2(saved, 2)
            os.close(saved)
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.default_int_handler)


def received(nodes) -> int:
    """Messages received so far by the nodes that count them (``messages_received``)."""
    return sum(int(getattr(n, "messages_received", 0)) for n in nodes)


def spin(executor, nodes=(), until=None, errors=None, stopped=None) -> int:
    """Spin ``executor`` until SIGINT/SIGTERM, a context shutdown or ``until()`` (optional, checked every
    :data:`SLICE` s of wall time) is true, then drain (module docstring; with ``until``, only when it ended the
    spin: the nodes that publish are then in this process and would keep the drain going). Returns 1 if a callback
    raised (traceback printed, and its last line appended to ``errors`` if given), else 0. The stop signals
    received are appended to ``stopped`` if given."""
    stop = []
    wake = Future()  # completed by a wall-clock timer once the spin is to end (see below)

    def on_signal(signum, frame):  # noqa: ARG001
        stop.append(signum)

    def check():
        if (stop or (until is not None and until())) and not wake.done():
            wake.set_result(True)

    # The EventsExecutor's slice does not end at its timeout while its queue never empties (a lockstep run in one
    # process: each callback publishes what the next one takes), so a signal or ``until`` would wait for the end
    # of the run. A timer is an event in that queue: it completes ``wake`` and the slice ends after the callback
    # in progress. (Not from the signal handler itself: it may run while the main thread holds the future's lock.)
    timer = nodes[0].create_timer(SLICE, check, clock=Clock(clock_type=ClockType.STEADY_TIME)) if nodes else None
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, on_signal)
    try:
        while not stop and rclpy.ok() and not (until is not None and until()):
            executor.spin_until_future_complete(wake, timeout_sec=SLICE)
        counted = [n for n in nodes if hasattr(n, "messages_received")]
        # with ``until`` the closed loop runs in this process and keeps stepping: a signal ends the run at once
        if counted and rclpy.ok() and not (stop and until is not None):
            # local: also DRAIN_QUIET_SPINS spins in a row without a message, so that a process descheduled on a
            # loaded machine cannot end the drain while callbacks are still queued (a spin runs one when one is)
            idle, spins, wait = (DRAIN_IDLE, 0, 0.05) if until is None else (DRAIN_IDLE_LOCAL, DRAIN_QUIET_SPINS,
                                                                              DRAIN_IDLE_LOCAL / DRAIN_QUIET_SPINS)
            start = last_change = time.monotonic()
            last, quiet = received(counted), 0
            while len(stop) < 2 and rclpy.ok():
                now = time.monotonic()
                if (now - last_change >= idle and quiet >= spins) or now - start >= DRAIN_MAX:
                    break
                executor.spin_once(timeout_sec=wait)
                count = received(counted)
                quiet += 1
                if count != last:
                    last, last_change, quiet = count, time.monotonic(), 0
    except ExternalShutdownException:
        pass
    except Exception:  # noqa: BLE001 -- a callback raised: the traceback, and the process stops with code 1
        traceback.print_exc()
        if errors is not None:
            errors.append(traceback.format_exc().strip().splitlines()[-1])
        return 1
    finally:
        if timer is not None:
            nodes[0].destroy_timer(timer)
        if stopped is not None:
            stopped.extend(stop)
    return 0


def wait_for_acknowledgments(nodes, budget=ACK_WAIT) -> bool:
    """Before a process destroys its publishers: wait (at most ``budget`` s of wall time in all) until every
    reliable reader has acknowledged every message of the reliable publishers of ``nodes``. A reader in another
    process that fell behind (a descheduled listeners' process) gets its missed messages repaired only while their
    writer exists; without this wait the loop's process could end first and the bag would lose them. The readers
    in this process acknowledge at once; a reader whose process was killed is never heard of again, and its wait
    ends with the budget. True if every publisher was acknowledged in time."""
    from rclpy.duration import Duration
    from rclpy.qos import ReliabilityPolicy

    deadline = time.monotonic() + budget
    acked = True
    for node in nodes:
        for pub in list(node.publishers):
            if pub.qos_profile.reliability != ReliabilityPolicy.RELIABLE:
                continue
            left = deadline - time.monotonic()
            if left <= 0:
                return False
            try:
                acked = pub.wait_for_all_acked(Duration(nanoseconds=int(left * 1e9))) and acked
            except Exception:  # noqa: BLE001 -- a publisher already gone, a context shutting down: nothing to wait for
                pass
    return acked


def serve(factories, args=None, make_executor=SingleThreadedExecutor, until=None, errors=None, *, stopped=None,
          leaving=False) -> int:
    """The whole life of a process: :func:`init`; construct the nodes of ``factories`` (``[(label, factory)]``, in
    order); the nodes on one executor from ``make_executor()``; :func:`spin` with the drain (until a signal, or
    ``until()`` is true: :func:`roe_sep.run.run` in one process, a lifecycle manager whose start-up failed); then the
    executor shut down, each node's ``executor_stopped()`` called if it has one (work that may start once no
    callback runs any more: the ground_bridge's final CCSDS set, in its writer thread), and the nodes destroyed,
    the recorder first (the bag is complete before another node spends seconds on its own shutdown work, e.g.
    waiting for the ground_bridge's final CCSDS set), the others in reverse order.

    Exit code 2 when rcl refuses the ROS arguments (a missing or malformed ``--params-file``) or a node refuses its
    parameters (``[ERROR] label: ...``, or without the label when it is None),
    1 when a callback raised, else 0; the reason of a non-zero code is appended to ``errors`` (a list) if given,
    the stop signals received during the spin to ``stopped``.
    The signal handlers in place before are restored on return; with ``leaving`` (the process ends after this: a
    node's ``main()``, :func:`leave`) SIGINT and SIGTERM are ignored instead: a late SIGINT of ``ros2 launch``
    arriving after the spin's handler was gone raised Python's KeyboardInterrupt there (a cleanly stopped node
    reported as 'process has died [exit code -2]', once in a Ctrl-C of the launch test)."""
    handlers = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        init(args)
    except RosArgumentsError as exc:
        label = factories[0][0] if len(factories) == 1 else None
        print(f"[ERROR] {label}: {exc}" if label else f"[ERROR] {exc}", file=sys.stderr)
        if errors is not None:
            errors.append(str(exc))
        return 2
    nodes, executor, code = [], None, 0
    try:
        executor = make_executor()
        for label, factory in factories:
            try:
                nodes.append(factory())
            except ParameterError as exc:
                print(f"[ERROR] {label}: {exc}" if label else f"[ERROR] {exc}", file=sys.stderr)
                if errors is not None:
                    errors.append(f"{label}: {exc}" if label else str(exc))
                return 2
        for node in nodes:  # work that needs every node of the process: the recorder's first look at the topics
            getattr(node, "peers_constructed", lambda: None)()
        for node in nodes:
            executor.add_node(node)
        code = spin(executor, nodes, until, errors, stopped)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if executor is not None:
            if rclpy.ok() and not wait_for_acknowledgments(nodes):
                print(f"[WARN] messages not acknowledged by every reader within {ACK_WAIT:g} s "
                      "(a reader's process stopped or killed?)", file=sys.stderr, flush=True)
            executor.shutdown()
            for node in nodes:  # shutdown work that may start now that no callback runs (the ground_bridge's)
                getattr(node, "executor_stopped", lambda: None)()
        for node in sorted(reversed(nodes), key=lambda n: n.get_name() != "recorder"):
            node.destroy_node()
        rclpy.try_shutdown()
        for sig, handler in handlers.items():
            signal.signal(sig, signal.SIG_IGN if leaving else handler)
    return code


def leave(code: int) -> int:
    """The end of a node process's ``main()``: SIGINT/SIGTERM ignored from here on, ``code`` returned. Python's
    finalization resets a signal's Python handler to the default action, and the late SIGINT of ``ros2 launch``
    (sent after the terminal's Ctrl-C had already stopped the node) then killed a cleanly stopped node while rmw
    was tearing down ('process has died [exit code -2]')."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    return code


def run(node_factory, args=None) -> int:
    """A node's ``main()``: the node built by ``node_factory()`` alone on a SingleThreadedExecutor (:func:`serve`),
    its errors labelled with the node's name (its parameter table's), then :func:`leave`; ``-h``/``--help`` prints
    the usage and the parameter table, exit code 0, before ROS starts."""
    name = node_table(node_factory)
    if help_requested(args):
        return print_usage(name, sys.modules[node_factory.__module__].__doc__ or "")
    return leave(serve([(name, node_factory)], args, leaving=True))
