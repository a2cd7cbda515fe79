"""The simulator's burn execution, without ROS: the burns of the ejection and of the plans in force, the safety
monitor's verdicts on the plans, and each burn flown on the truth at its epoch with the seeded execution and
attitude errors (seed 002 Eq. 22; a reduced drift-stop's magnitude error on its unreduced burn, Eq. 18).

A plan replaces the burns of the previous plan on the same topic that are not executed yet; a burn already flown is
never flown again (a restarted planner re-publishes the plan it made before).
"""

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .secular import error_references

EJECTION = "ejection"  # the source of the ejection's burn (a plan's source: the topic it came on)


def relative_impulse(dv_rtn: ArrayLike, spacecraft: str) -> np.ndarray:
    """The impulse's effect ``(3,)`` [m/s] RTN on the relative motion (picosatellite w.r.t. carrier) of ``dv_rtn``
    ``(3,)`` [m/s] of ``spacecraft``: +dv for the picosatellite's own velocity change (the ejection), -dv for a
    carrier burn."""
    dv = np.asarray(dv_rtn, dtype=float)
    if spacecraft == "carrier":
        return -dv
    if spacecraft == "picosatellite":
        return dv
    raise ValueError(f"unknown spacecraft {spacecraft!r} (expected 'carrier' or 'picosatellite')")


@dataclass
class PendingBurn:
    epoch: float  # s, when it is flown
    dv_rtn: np.ndarray  # m/s, as commanded, in the RTN frame of the spacecraft that burns
    spacecraft: str
    purpose: str
    source: str  # EJECTION or the topic of its plan
    plan_stamp: float  # s, the stamp of its plan (the ejection event's)
    error_reference: np.ndarray | None = None  # the unreduced drift-stop its magnitude error acts on (Eq. 18)

    @property
    def key(self) -> tuple[str, str, float]:
        """What identifies a burn across re-published plans: (source, purpose, epoch [s] to the ms)."""
        return self.source, self.purpose, round(self.epoch, 3)


@dataclass
class ExecutedBurn:
    epoch: float  # s
    u: float  # rad, the carrier's mean argument of latitude at the burn (before it)
    dv_rtn: np.ndarray  # m/s, as executed
    spacecraft: str
    purpose: str


class BurnExecution:
    """The pending burns and their execution on ``truth`` (a :class:`~.simulated.SimulatedTruth`). ``report(level,
    text)`` (level 'WARN' or 'ERROR') says why a burn or a plan was not taken as it came."""

    def __init__(self, truth, errors, ejection_delay, require_approval, report, *, contingency=None):
        self.truth, self.errors, self.ejection_delay = truth, errors, ejection_delay
        self.contingency = contingency  # a TruthContingency: moves, drops or changes burns; None: none
        self.require_approval = require_approval
        self.report = report
        self.pending: list[PendingBurn] = []
        self.flown = set()  # key of every executed burn
        self.plan_stamps = {}  # source -> stamp of the plan in force
        self.approvals = {}  # (source, plan stamp) -> bool
        self.seen_ejections = set()
        self.burns = 0
        self.ejected_at = None  # s, set by the ejection (the free-running clock clears it)

    # ------------------------------------------------------------------ inputs
    def eject(self, stamp: float, dv_rtn: ArrayLike, spacecraft: str, purpose: str) -> None:
        """The commanded ejection at ``stamp`` [s]: the spring fires ``ejection_delay`` after it (the executed
        maneuver says when). The same event again is ignored; a bad one or a second ejection is reported.

        Parameters
        ----------
        stamp : float
            The ejection event's stamp [s] of sim time.
        dv_rtn : array_like, shape (3,)
            The commanded ejection [m/s] in the picosatellite's RTN frame.
        spacecraft : str
            Who burns: ``picosatellite`` (anything else is reported and ignored).
        purpose : str
            The burn's purpose (``ejection``).

        Returns
        -------
        None
        """
        dv = np.asarray(dv_rtn, dtype=float)
        if stamp in self.seen_ejections:
            return
        if not (math.isfinite(stamp) and np.all(np.isfinite(dv))) or spacecraft != "picosatellite":
            self.report("ERROR", f"ejection event rejected (epoch {stamp}, dv {dv.tolist()}, "
                                 f"spacecraft {spacecraft!r})")
            return
        if self.truth.model.separated:
            self.report("WARN", "second ejection event ignored: the picosatellite is already released")
            return
        self.seen_ejections.add(stamp)
        self.pending.append(PendingBurn(stamp + self.ejection_delay, dv, spacecraft, purpose, EJECTION, stamp))

    def plan(self, source: str, stamp: float, maneuvers: Iterable[tuple[float, ArrayLike, str, str]],
             p_reduction: float) -> list[PendingBurn] | None:
        """A plan of ``maneuvers`` stamped ``stamp`` [s] on ``source``: its burns not flown yet replace the pending
        ones of that source. ValueError (the plan is not taken) for a bad burn.

        Parameters
        ----------
        source : str
            The topic the plan came on.
        stamp : float
            The plan's stamp [s] of sim time.
        maneuvers : iterable of (float, array_like, str, str)
            Each burn's epoch [s], dv ``(3,)`` [m/s] in the RTN frame of the spacecraft that burns, that spacecraft
            (``carrier`` or ``picosatellite``) and its purpose.
        p_reduction : float
            The plan's drift-stop reduction |p| [m/s] (:func:`~.secular.error_references`).

        Returns
        -------
        list of PendingBurn or None
            The plan's burns now pending, or None for the plan in force again.
        """
        if self.plan_stamps.get(source) == stamp:
            return None
        burns = [PendingBurn(epoch, np.asarray(dv, dtype=float), spacecraft, purpose, source, stamp)
                 for epoch, dv, spacecraft, purpose in maneuvers]
        for b in burns:
            relative_impulse(b.dv_rtn, b.spacecraft)
            if not (math.isfinite(b.epoch) and np.all(np.isfinite(b.dv_rtn))):
                raise ValueError("non-finite epoch or dv")
        refs = error_references([b.purpose for b in burns], [b.dv_rtn for b in burns], p_reduction)
        for b, ref in zip(burns, refs):
            b.error_reference = ref
        if self.contingency is not None:  # a late or missed burn: the plan stands, its execution does not
            for b in burns:
                b.epoch = self.contingency.reschedule(b.epoch, b.purpose, b.spacecraft)
            burns = [b for b in burns if b.epoch is not None]
        burns = [b for b in burns if b.key not in self.flown]
        self.pending = [b for b in self.pending if b.source != source] + burns
        self.plan_stamps[source] = stamp
        return burns

    def check(self, source: str, stamp: float, safe: bool) -> None:
        """The safety monitor's verdict on the plan of ``source`` stamped ``stamp`` [s].

        Parameters
        ----------
        source : str
            The topic of the plan.
        stamp : float
            The plan's stamp [s] of sim time.
        safe : bool
            The verdict: True to fly the plan, False (flagged) not to.

        Returns
        -------
        None
        """
        self.approvals[(source, stamp)] = bool(safe)

    # ------------------------------------------------------------------ execution
    def due(self, t: float) -> list[PendingBurn]:
        """The pending burns with an epoch up to ``t`` [s], in epoch order; those the contingency loses when they
        come due (a carrier in safe mode: :meth:`~.contingency.TruthContingency.dropped`) are taken off, unflown."""
        if self.contingency is not None:
            for b in [b for b in self.pending if b.epoch <= t]:
                if self.contingency.dropped(b.epoch, b.purpose, b.spacecraft):
                    self.pending.remove(b)
        return sorted((b for b in self.pending if b.epoch <= t), key=lambda b: b.epoch)

    def needs_check(self, burn: PendingBurn) -> bool:
        """Whether ``burn`` waits for the safety monitor's verdict on its plan (a planned burn, when approval is
        required; never the ejection)."""
        return burn.source != EJECTION and self.require_approval

    def verdict(self, burn: PendingBurn) -> bool | None:
        """True: fly it; False: the monitor flagged its plan (reported); None: its plan is not checked yet."""
        if not self.needs_check(burn):
            return True
        verdict = self.approvals.get((burn.source, burn.plan_stamp))
        if verdict is False:
            self.report("ERROR", f"{self.describe(burn)} not executed: the safety monitor flagged the plan")
        return verdict

    @staticmethod
    def describe(burn: PendingBurn) -> str:
        """``burn`` in a report: its epoch [s] and the topic of its plan."""
        return f"burn at t = {burn.epoch:.0f} s of the plan on {burn.source}"

    def take(self, burn: PendingBurn) -> PendingBurn:
        """Take ``burn`` off the pending ones (to fly it or to drop it)."""
        self.pending.remove(burn)
        return burn

    def execute(self, burn: PendingBurn) -> ExecutedBurn:
        """Fly ``burn`` (taken) at its epoch, or now if that has passed (WARN): the truth moves there, the dispersed
        burn is applied."""
        t_exec = max(burn.epoch, self.truth.t)
        if burn.epoch < self.truth.t - 1e-6:
            self.report("WARN", f"{burn.purpose} burn executed late at t = {self.truth.t:.0f} s (planned "
                                f"{burn.epoch:.0f} s)")
        self.truth.advance(t_exec)
        executed = self.errors.executed(burn.dv_rtn, burn.spacecraft, burn.error_reference)
        if self.contingency is not None:
            executed = self.contingency.executed(executed, burn.purpose, burn.spacecraft, t_exec)
        done = ExecutedBurn(t_exec, float(self.truth.model.u_at(t_exec)), executed, burn.spacecraft, burn.purpose)
        self.truth.model.apply(t_exec, relative_impulse(executed, burn.spacecraft), burn.spacecraft)
        self.flown.add(burn.key)
        if burn.purpose == "ejection":
            self.ejected_at = t_exec
        self.burns += 1
        return done
