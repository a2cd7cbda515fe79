"""Contingency detection, without ROS: what the safety monitor can see of a contingency from what the
ground has -- the plans it approved, the executed carrier burns, the commanded ejection and the OD solutions -- never
the truth. Each finding is a named :class:`Detection`; the safety monitor raises it on ``/diagnostics`` and the run
report lists the first epoch of each name (``contingencies_detected``).

* ``burn_missing``: a carrier burn of an approved plan has not executed ``epoch_tolerance`` after its epoch
  (``drift_stop_delayed``, ``drift_stop_missed``).
* ``burn_late``: it executed later than that (``drift_stop_delayed``: k orbits late).
* ``burn_magnitude``: its executed magnitude departs from the commanded one by more than ``magnitude_z`` sigmas of
  the thruster's magnitude error (seed 002 Eq. 22; a reduced drift-stop's error on its unreduced burn, Eq. 18):
  ``burn_underperformance`` at 50-80 %.
* ``burn_pointing``: its direction departs from the commanded one by more than ``pointing_deg`` (the attitude error
  is 30 arcsec per axis): ``burn_underperformance`` with 5-15 deg.
* ``od_inconsistent``: an OD solution's e/i vectors (a de, a di: no drift, so the prediction stays sharp for days)
  against their prediction from the previous knowledge -- the previous solution, else the commanded ejection (seed
  002 Eq. 2) -- carried over the executed carrier burns: the normalized squared error (4 dof) beyond the chi-square
  quantile ``1 - od_alpha``, with the prediction's covariance from the SPL's magnitude error (f1 ~ N(1, spl_sigma),
  seed 002 Eq. 22), the burns' magnitude errors, the attitude errors and a model floor ``od_model_sigma`` per
  component: a weak ejection (``spl_weak``: f1 <= 0.5 is 5 sigmas of the nominal SPL) or a burn that did not do
  what its executed record says.
* ``od_residuals``: an OD's post-fit residual RMS r (in measurement sigmas) over m measurements: 3 m r^2 beyond the
  chi-square(3 m - 7) quantile ``1 - residual_alpha`` (``radar_bias``: a range bias of one to five range sigmas).

What it cannot see: the SPL's own execution (the carrier does not measure the picosatellite's impulse; the first
OD finds a weak ejection), missed radar passes (an OD that comes late is not yet an anomaly here).
"""

import math
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..od.batch import residual_tail
from ..relmotion.dynamics import propagate
from ..relmotion.maneuvers import control_matrix, delta_roe
from ..relmotion.orbit import angle_between, mean_motion
from ..relmotion.trajectory import Burn, Chief, state_at
from ..truth.execution import relative_impulse
from ..truth.secular import error_references

DETECTIONS = ("burn_missing", "burn_late", "burn_magnitude", "burn_pointing", "od_inconsistent", "od_residuals")
EI = slice(2, 6)  # the e/i components of the ROE
OD_PARAMETERS = 7  # ROE and drift rate: the batch OD's estimated parameters


@dataclass(frozen=True)
class AnomalyLimits:
    """Thresholds of the detections [s, sigma, deg, m, probability]."""

    epoch_tolerance: float = 60.0
    magnitude_z: float = 3.5
    pointing_deg: float = 1.0
    od_alpha: float = 1e-3
    od_model_sigma: float = 10.0
    residual_alpha: float = 1e-4


@dataclass
class Detection:
    """One finding: its name (:data:`DETECTIONS`), the sim time [s] it was made, what was seen."""

    name: str
    epoch: float
    text: str
    values: dict = field(default_factory=dict)


@dataclass
class PlannedBurn:
    source: str
    epoch: float  # s, as commanded
    dv: np.ndarray  # m/s, RTN of the spacecraft that burns
    spacecraft: str
    purpose: str
    reference: np.ndarray | None  # the burn its magnitude error acts on (Eq. 18), None: itself
    missing: bool = False  # burn_missing raised


def magnitude_z(executed: ArrayLike, commanded: ArrayLike, reference: ArrayLike | None,
                thruster_sigma: float) -> float | None:
    """The executed burn's magnitude error in sigmas of the thruster's: (|executed| - |commanded|) / (sigma |ref|),
    ``ref`` the burn the magnitude error acts on (seed 002 Eq. 22; a reduced drift-stop's error on its unreduced
    burn, Eq. 18, :func:`~roe_sep.core.truth.secular.error_references`; None: the commanded burn); None for a zero
    burn or sigma.

    Parameters
    ----------
    executed, commanded : array_like, shape (3,)
        The burn as executed and as commanded [m/s].
    reference : array_like, shape (3,), or None
        The reference burn [m/s].
    thruster_sigma : float
        The relative 1-sigma magnitude error of the thruster.

    Returns
    -------
    float or None
        The z-score.
    """
    cmd = float(np.linalg.norm(commanded))
    ref = float(np.linalg.norm(reference)) if reference is not None else cmd
    sigma = thruster_sigma * ref
    if not (cmd > 0.0 and sigma > 0.0):
        return None
    return (float(np.linalg.norm(executed)) - cmd) / sigma


def ei_transition(a: float, inc: float, dt: float, j2: bool) -> np.ndarray:
    """The 4x4 transition of the e/i vectors over ``dt`` [s] in the secular model (J2 turns the relative
    eccentricity vector; :func:`~roe_sep.core.relmotion.dynamics.propagate` is linear in the ROE without drag).

    Parameters
    ----------
    a : float
        The chief's semi-major axis [m].
    inc : float
        The chief's inclination [rad].
    dt : float
        The time span [s] of the transition.
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    numpy.ndarray, shape (4, 4)
        The transition of the (dimensionless or a-scaled) e/i components of the ROE over ``dt``.
    """
    cols = propagate(np.eye(6), dt, a, inc, j2, da_dot=0.0)  # row k: the propagated unit vector e_k
    return cols.T[EI, EI]


class AnomalyWatch:
    """The detections of one run. Feed it the commanded ejection (:meth:`ejection`), every approved plan
    (:meth:`plan`), every executed carrier burn (:meth:`executed`), the sim time as it advances (:meth:`at`) and every
    OD solution (:meth:`od`); each returns the new detections."""

    def __init__(self, limits: AnomalyLimits, spl_sigma: float, thruster_sigma: float, attitude_sigma: float,
                 j2: bool = True):
        self.limits = limits
        self.spl_sigma, self.thruster_sigma, self.attitude_sigma = spl_sigma, thruster_sigma, attitude_sigma
        self.j2 = j2
        self.planned: list[PlannedBurn] = []  # the approved carrier burns not executed yet
        self.matched = set()  # (source, purpose, epoch to the ms) of the planned burns executed
        self.knowledge = None  # (t, dimensionless ROE, Chief, a*e/i covariance [m^2], da_dot)
        self.burns = []  # (Burn, a*e/i covariance [m^2] it adds) executed after the knowledge's epoch
        self.measured_from = None  # what replaced the commanded ejection as the knowledge: "footage", "od"

    # ------------------------------------------------------------------ burns
    def plan(self, source: str, burns: Iterable[tuple[float, ArrayLike, str, str]], p_reduction: float) -> None:
        """An approved plan on ``source``: ``burns`` (epoch [s], dv (3,) [m/s], spacecraft, purpose); its carrier
        burns not executed yet replace those of the previous plan on that source (as the simulator takes it).

        Parameters
        ----------
        source : str
            The topic the plan came on.
        burns : iterable of (float, array_like, str, str)
            Each burn's epoch [s], dv ``(3,)`` [m/s] in the RTN frame of the spacecraft that burns, that spacecraft
            (``carrier`` or ``picosatellite``) and its purpose.
        p_reduction : float
            The plan's drift-stop reduction |p| [m/s] (:func:`~roe_sep.core.truth.secular.error_references`).

        Returns
        -------
        None
        """
        burns = list(burns)
        refs = error_references([b[3] for b in burns], [np.asarray(b[1], dtype=float) for b in burns], p_reduction)
        new = [PlannedBurn(source, float(e), np.asarray(dv, dtype=float), sc, purpose, ref)
               for (e, dv, sc, purpose), ref in zip(burns, refs) if sc == "carrier"]
        new = [b for b in new if (b.source, b.purpose, round(b.epoch, 3)) not in self.matched]
        self.planned = [b for b in self.planned if b.source != source] + new

    def at(self, t: float) -> list[Detection]:
        """``burn_missing`` for each planned burn not executed by ``t`` [s] (its epoch + the tolerance)."""
        out = []
        for b in self.planned:
            if not b.missing and t > b.epoch + self.limits.epoch_tolerance:
                b.missing = True
                out.append(Detection("burn_missing", t, f"{b.purpose} burn planned at t = {b.epoch:.0f} s not "
                                     f"executed by t = {t:.0f} s", {"planned_epoch_s": b.epoch}))
        return out

    def executed(self, epoch: float, dv: ArrayLike, spacecraft: str, purpose: str, u: float) -> list[Detection]:
        """An executed burn (epoch [s], dv (3,) [m/s] as executed in its own RTN, the carrier's mean argument of
        latitude ``u`` [rad] then): compared with its planned burn (the open one of that purpose nearest in time,
        not after it by more than the tolerance), and kept for the OD's prediction.

        Parameters
        ----------
        epoch : float
            The epoch [s] of sim time the burn executed at.
        dv : array_like, shape (3,)
            The burn as executed [m/s] in the RTN frame of the spacecraft that burned.
        spacecraft : str
            Who burned: ``carrier`` (any other burn is ignored).
        purpose : str
            The burn's purpose (matched with the planned burns of that purpose).
        u : float
            The carrier's mean argument of latitude [rad] at the burn.

        Returns
        -------
        list of Detection
            ``burn_late``, ``burn_magnitude`` and ``burn_pointing`` findings on this burn (empty when none).
        """
        dv = np.asarray(dv, dtype=float)
        if spacecraft != "carrier":
            return []
        out = []
        tol = self.limits.epoch_tolerance
        candidates = [b for b in self.planned if b.purpose == purpose and b.epoch <= epoch + tol]
        sigma_factor = 1.0
        if candidates:
            b = min(candidates, key=lambda c: abs(epoch - c.epoch))
            self.planned.remove(b)
            self.matched.add((b.source, b.purpose, round(b.epoch, 3)))
            out += self._compare(b, epoch, dv)
            cmd = float(np.linalg.norm(b.dv))
            if cmd > 0.0 and b.reference is not None:
                sigma_factor = float(np.linalg.norm(b.reference)) / cmd
        if self.knowledge is not None:
            k_chief = self.knowledge[2]
            rel = relative_impulse(dv, spacecraft)
            x = delta_roe(rel, u, k_chief.a, mean_motion(k_chief.a))[EI] * k_chief.a
            sig = self.thruster_sigma * sigma_factor
            cov = sig * sig * np.outer(x, x) + (self.attitude_sigma ** 2) * float(x @ x) * np.eye(4)
            self.burns.append((Burn(float(epoch), tuple(rel)), cov))
        return out

    def _compare(self, b: PlannedBurn, epoch, dv):
        out = []
        lim = self.limits
        if epoch > b.epoch + lim.epoch_tolerance:
            out.append(Detection("burn_late", epoch, f"{b.purpose} burn planned at t = {b.epoch:.0f} s executed "
                                 f"{epoch - b.epoch:.0f} s late", {"planned_epoch_s": b.epoch,
                                                                   "delay_s": epoch - b.epoch}))
        cmd = float(np.linalg.norm(b.dv))
        z = magnitude_z(dv, b.dv, b.reference, self.thruster_sigma)
        if z is not None:
            if abs(z) > lim.magnitude_z:
                out.append(Detection("burn_magnitude", epoch, f"{b.purpose} burn at t = {epoch:.0f} s executed "
                                     f"{float(np.linalg.norm(dv)):.4f} m/s of {cmd:.4f} m/s ({z:+.1f} sigma)",
                                     {"ratio": float(np.linalg.norm(dv)) / cmd, "z": z}))
        off = math.degrees(float(angle_between(dv, b.dv)))
        if cmd > 0.0 and off > lim.pointing_deg:
            out.append(Detection("burn_pointing", epoch, f"{b.purpose} burn at t = {epoch:.0f} s executed "
                                 f"{off:.2f} deg off its commanded direction", {"angle_deg": off}))
        return out

    # ------------------------------------------------------------------ knowledge
    def ejection(self, t: float, dv_commanded: ArrayLike, chief: Chief, da_dot: float) -> None:
        """The commanded ejection at ``t`` [s] (the picosatellite's dv (3,) [m/s]): the first knowledge, with the
        SPL's magnitude and attitude errors as its e/i covariance.

        Parameters
        ----------
        t : float
            The epoch [s] of sim time of the ejection.
        dv_commanded : array_like, shape (3,)
            The commanded ejection [m/s] in the picosatellite's RTN frame.
        chief : Chief
            The chief's a [m], i [rad] and mean argument of latitude u0 [rad] at its epoch t0 [s].
        da_dot : float
            The differential-drag rate of da [1/s].

        Returns
        -------
        None
        """
        roe = delta_roe(np.asarray(dv_commanded, dtype=float), chief.u0, chief.a, mean_motion(chief.a))
        x = roe[EI] * chief.a
        cov = self.spl_sigma ** 2 * np.outer(x, x) + (self.attitude_sigma ** 2) * float(x @ x) * np.eye(4)
        self.knowledge = (float(t), roe, chief, cov, float(da_dot))
        self.burns = []
        self.measured_from = None  # the knowledge is the commanded ejection's (measured_ejection: the footage's)

    def measured_ejection(self, dv: ArrayLike, cov: ArrayLike) -> None:
        """The executed ejection the footage measured (:func:`~roe_sep.core.od.pose.estimate_ejection`): it replaces
        the commanded one as the knowledge the first OD is predicted from, with its own covariance (seed 002 Eq. 2,
        linear in dv), until an OD does; ignored before the commanded ejection or after an OD.

        Parameters
        ----------
        dv : array_like, shape (3,)
            The measured ejection [m/s], the picosatellite's RTN.
        cov : array_like, shape (3, 3)
            Its covariance [m^2/s^2].

        Returns
        -------
        None
        """
        if self.knowledge is None or self.measured_from == "od":
            return
        t, _, chief, _, da_dot = self.knowledge
        n = mean_motion(chief.a)
        roe = delta_roe(np.asarray(dv, dtype=float), chief.u0, chief.a, n)
        jac = control_matrix(chief.u0)[EI] / n  # (4, 3): a times Eq. 2's dROE / d dv
        self.knowledge = (t, roe, chief, jac @ np.asarray(cov, dtype=float) @ jac.T, da_dot)
        self.measured_from = "footage"

    def od(self, t_now: float, t_od: float, roe: ArrayLike, cov6: ArrayLike, chief: Chief, *, da_dot: float,
           residual_rms: float, measurements: int) -> list[Detection]:
        """An OD solution at ``t_od`` [s] (dimensionless ROE, its a*ROE covariance (6, 6) [m^2], the drift rate
        [1/s], the residual RMS in sigmas over ``measurements``), published at ``t_now``: ``od_residuals`` and
        ``od_inconsistent``; the solution is then the knowledge the next one is predicted from.

        Parameters
        ----------
        t_now : float
            The epoch [s] of sim time the solution is published at (the findings' epoch).
        t_od : float
            The epoch [s] of sim time of the solution.
        roe : array_like, shape (6,)
            The estimated ROE (dimensionless) at ``t_od``.
        cov6 : array_like, shape (6, 6)
            The covariance [m^2] of the a-scaled ROE (a non-finite one is not taken as knowledge).
        chief : Chief
            The chief's a [m], i [rad] and mean argument of latitude u0 [rad] at its epoch t0 [s].
        da_dot : float
            The estimated drift rate of da [1/s].
        residual_rms : float
            The post-fit residual RMS in measurement sigmas (dimensionless).
        measurements : int
            The number of measurements of the batch.

        Returns
        -------
        list of Detection
            ``od_residuals`` and ``od_inconsistent`` findings on this solution (empty when none).
        """
        # the chi-square quantile from scipy.special (what scipy.stats.chi2.isf calls, the same floats):
        # scipy.stats costs about 0.3 CPU-s to import; here, not at import: every node process imports this module
        from scipy.special import chdtri

        roe = np.asarray(roe, dtype=float)
        cov6 = np.asarray(cov6, dtype=float)
        out = []
        m = int(measurements)
        if 3 * m > OD_PARAMETERS and math.isfinite(residual_rms):
            p = residual_tail(residual_rms, m, OD_PARAMETERS)
            if p < self.limits.residual_alpha:
                out.append(Detection("od_residuals", t_now, f"OD at t = {t_od:.0f} s: residual RMS "
                                     f"{residual_rms:.2f} sigma over {m} measurements (p = {p:.1e})",
                                     {"residual_rms": residual_rms, "p": p}))
        if self.knowledge is not None and t_od >= self.knowledge[0]:
            t0, roe0, chief0, cov0, da0 = self.knowledge
            burns = [b for b, _ in self.burns if b.epoch >= t0 and b.epoch <= t_od]
            pred = state_at(roe0, t0, burns, t_od, chief0, j2=self.j2, da_dot=da0)
            # each covariance carried from its own epoch (J2 turns the relative eccentricity vector)
            p_pred = ei_transition(chief0.a, chief0.inc, t_od - t0, self.j2)
            p_pred = p_pred @ cov0 @ p_pred.T
            for b, c in self.burns:
                if t0 <= b.epoch <= t_od:
                    phi = ei_transition(chief0.a, chief0.inc, t_od - b.epoch, self.j2)
                    p_pred = p_pred + phi @ c @ phi.T
            a = chief0.a
            d = (roe[EI] - pred[EI]) * a
            total = p_pred + cov6[EI, EI] + self.limits.od_model_sigma ** 2 * np.eye(4)
            try:
                nees = float(d @ np.linalg.solve(total, d))
            except np.linalg.LinAlgError:
                nees = math.inf
            bound = float(chdtri(4, self.limits.od_alpha))
            if nees > bound:
                seen, expected = np.round(roe[EI] * a, 1).tolist(), np.round(pred[EI] * a, 1).tolist()
                out.append(Detection("od_inconsistent", t_now, f"OD at t = {t_od:.0f} s: e/i vectors {seen} m "
                                     f"against {expected} m predicted (NEES {nees:.1f} > {bound:.1f})",
                                     {"nees": nees, "bound": bound, "predicted": (pred[EI] * a).tolist(),
                                      "estimate": (roe[EI] * a).tolist()}))
        if np.all(np.isfinite(cov6)):
            self.knowledge = (float(t_od), roe, chief, cov6[EI, EI].copy(), float(da_dot))
            self.measured_from = "od"
            self.burns = [(b, c) for b, c in self.burns if b.epoch > t_od]
        return out
