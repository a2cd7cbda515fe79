"""The simulator's free-running clock (no lockstep participants): ``time_step`` of sim time every ``tick_period`` wall
seconds, holding while the ground owes an answer, each hold for at most ``approval_timeout`` wall seconds: a burn
due whose plan the safety monitor has not checked yet, the drift-stop plan after the ejection, the acquisition
planner's decision on a new OD solution. (Under lockstep, :class:`~.lockstep.Coordinator`, the reaction rounds of a
step wait for all of these.)
"""

import time

from .. import interfaces
from .diagnostics import ERROR, OK, WARN

ACQUISITION_PLANNER = "roe_sep/ic_planner"  # its /diagnostics status name


class FreeRunningClock:
    """``sim`` (the simulator node) provides ``t``, ``done``, ``duration``, ``time_step``, ``approval_timeout``,
    ``wait_for``, ``start_timeout``, ``waiting_since``, ``execution`` (its
    :class:`~roe_sep.core.truth.execution.BurnExecution`), ``advance(t)``, ``execute(burn)``, ``publish_clock()``,
    ``status(level, message)``, ``count_subscribers`` and ``get_logger``."""

    def __init__(self, sim):
        self.sim = sim
        self.holds = {}  # what the clock waits for -> wall time the wait began (see _holding)
        self.od_seen = set()

    # ------------------------------------------------------------------ what the ground owes
    def on_plan(self, topic):
        if topic == interfaces.DRIFT_STOP_PLAN_TOPIC:
            self.holds.pop("drift_stop", None)

    def on_od(self, stamp):
        """A new OD solution opens the wall-clock hold for the acquisition planner's decision."""
        if stamp not in self.od_seen:
            self.od_seen.add(stamp)
            self.holds["acquisition"] = time.monotonic()

    def on_diagnostics(self, names):
        if ACQUISITION_PLANNER in names:
            self.holds.pop("acquisition", None)  # the acquisition planner has decided on the newest OD solution

    # ------------------------------------------------------------------ loop
    def ready(self):
        """Start the clock once every node is up (``wait_for``: subscribers per topic, from the ROS graph), so that
        nobody misses the first seconds; after ``start_timeout`` start anyway (WARN)."""
        sim = self.sim
        if sim.waiting_since is None:
            return True
        missing = {t: n for t, n in sim.wait_for.items() if sim.count_subscribers(t) < n}
        if not missing:
            sim.waiting_since = None
            return True
        if time.monotonic() - sim.waiting_since > sim.start_timeout:
            sim.waiting_since = None
            sim.status(WARN, f"started after {sim.start_timeout:g} s without the subscribers {missing}")
            return True
        sim.publish_clock()
        return False

    def _holding(self, reason):
        """The one wall-clock wait of the clock: True while ``reason`` (the drift-stop plan, an approval, the
        acquisition decision) has been awaited for at most ``approval_timeout`` wall seconds (the wait starts now
        unless it began earlier); False once that has run out, and the wait is forgotten."""
        since = self.holds.setdefault(reason, time.monotonic())
        if time.monotonic() - since > self.sim.approval_timeout:
            del self.holds[reason]
            return False
        return True

    def awaiting_drift_stop(self):
        """After the ejection the ground owes the drift-stop plan: hold the clock until one answering it has
        arrived (at most ``approval_timeout`` wall seconds), as for a plan awaiting its safety check."""
        sim, execution = self.sim, self.sim.execution
        if execution.ejected_at is None or interfaces.DRIFT_STOP_PLAN_TOPIC in execution.plan_stamps:
            return False
        if not self._holding("drift_stop"):
            execution.ejected_at = None
            sim.status(ERROR, f"no drift-stop plan within {sim.approval_timeout:g} s of the ejection")
            return False
        sim.publish_clock()
        return True

    def awaiting_acquisition(self):
        """After a new OD solution the acquisition planner owes a decision (a plan, or why not: it ends every
        decision with a /diagnostics status): hold the clock until it arrives, at most ``approval_timeout``."""
        if "acquisition" not in self.holds:
            return False
        if not self._holding("acquisition"):
            self.sim.status(ERROR, f"no decision of {ACQUISITION_PLANNER} within {self.sim.approval_timeout:g} s "
                                   "of an OD solution")
            return False
        self.sim.publish_clock()
        return True

    def _approval(self, burn):
        """True: execute; False: drop; None: wait."""
        execution = self.sim.execution
        if not execution.needs_check(burn):
            return True
        verdict = execution.verdict(burn)
        if verdict is not None:
            self.holds.pop("approval", None)
            return verdict
        if not self._holding("approval"):
            self.sim.status(ERROR, f"{execution.describe(burn)} not executed: no safety check within "
                                   f"{self.sim.approval_timeout:g} s")
            return False
        return None

    def tick(self):
        sim = self.sim
        if sim.done or not self.ready() or self.awaiting_drift_stop() or self.awaiting_acquisition():
            return
        t_next = min(sim.t + sim.time_step, sim.duration)
        while True:
            due = sim.execution.due(t_next)
            if not due:
                break
            burn = due[0]
            verdict = self._approval(burn)
            if verdict is None:  # hold the clock until the monitor has spoken or the wait times out
                sim.advance(max(sim.t, min(burn.epoch, t_next)))
                sim.publish_clock()
                return
            sim.execution.take(burn)
            if verdict:
                sim.execute(burn)
        sim.advance(t_next)
        sim.publish_clock()
        if sim.t >= sim.duration:
            sim.done = True
            sim.status(OK, "scenario complete")
            sim.get_logger().info("scenario complete")
