"""The planner's decisions (docs/run.md, "Decisions"): the blind drift-stop of a commanded ejection, its hold when the
camera sees a weak ejection, its replacement when none is on record, its completion when the one on record departs
from its command.

Each ``on_<event>(state, ..., config)`` returns ``(new_state, actions)``: :class:`PublishPlan`, :class:`StopBearings`
and the shared :class:`~.common.Status` / :class:`~.common.Log`; the rules take ``state`` (:class:`PlannerState`, what
the planner knows before the event; a drift-stop check wants one in force), ``t`` (the sim time [s] of a check) and
``config`` (:class:`PlannerConfig`, the node's parameters) as they need them. Physics: seed 002 Eqs. 9, 13, 18
(:func:`~roe_sep.core.separation.double_impulse.plan_drift_stop`), seed 001 Sec. 3
(:func:`~roe_sep.core.separation.multi_impulse.plan_carrier_burns`), and
:func:`~roe_sep.core.safety.ejection_check.check_ejection` for the camera.
"""

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...stamps import sec_nanosec
from ..od.pose import estimate_ejection
from ..relmotion.dynamics import arg_latitude_rate, drag_da_dot, propagate_chief, raan_rate
from ..relmotion.orbit import angle_between
from ..relmotion.roe import wrap_angle
from ..relmotion.trajectory import Chief
from ..safety.anomaly import magnitude_z
from ..safety.ejection_check import check_ejection, nominal_fraction
from ..separation.double_impulse import plan_drift_stop, reduction_bounds
from ..separation.multi_impulse import multi_config, plan_carrier_burns
from ..truth.secular import error_references
from .cam import CamConfig, cam_decision, completion_burns, reversal_burn
from .common import (
    ERROR,
    OK,
    WARN,
    Log,
    PlannedBurn,
    Stamped,
    State,
    Status,
    optional,
    planned_from_dict,
    status,
    tuples,
)

RECORD_SETTLE = 2.0  # wall s a restarted planner (no lockstep) lets the latched executed record arrive in full


@dataclass(frozen=True)
class PlannerConfig:
    """The node's parameters (docs/parameters.md, planner): ``p`` [m/s] the drift-stop reduction (None: from each
    event), ``scenario`` (:class:`~roe_sep.core.config.Scenario`), ``multi`` the multi-impulse configuration (None:
    double impulse); angles in radians."""

    strategy: str
    k: int
    p_mode: str
    p: float | None
    j2: bool
    scenario: Any
    multi: Any = None
    retry: bool = False
    retry_tolerance: float = 0.0
    retry_margin: float = 0.0
    makeup: bool = False
    makeup_z: float = 0.0
    makeup_pointing: float = 0.0
    hold: bool = False
    camera_sigma: float = 0.0
    camera_floor: float = 0.0
    hold_sigmas: float = 0.0
    hold_alpha: float = 0.0
    hold_lead: float = 0.0
    footage: bool = False
    footage_window: float = 0.0
    cam: bool = False
    cam_latency: float = 300.0
    cam_dv: float = 0.1
    cam_sigmas: float = 3.0
    pointing_sigma: float = math.radians(1.0)
    completion: bool = False
    completion_max_pulse: float = 0.3
    stuck_fraction: float = 0.05


@dataclass(frozen=True)
class Ejection(Stamped):
    """A commanded ejection (roe_sep_msgs/EjectionEvent): its stamp ``sec``, ``nanosec``, the chief's mean elements
    ``kep`` ``[a, e, i, raan, argp, M]`` and mean argument of latitude ``u`` [rad] as the message carries it, the
    picosatellite's ``dv_rtn`` (3,) [m/s] at ``u1`` [rad]."""

    kep: tuple
    u: float
    dv_rtn: tuple
    u1: float


@dataclass(frozen=True)
class InForce:
    """The drift-stop in force: its ``ejection``, ``k`` (None: the default), ``p`` [m/s] and epoch ``t_stop`` [s]."""

    ejection: Ejection
    k: int | None
    p: float
    t_stop: float


@dataclass(frozen=True)
class Aimed:
    """A plan's ``aimed`` field: ``roe`` (dimensionless) at ``t`` [s] with the chief's ``elements`` (a, e, i, raan,
    argp, mean argument of latitude) there."""

    roe: tuple
    elements: tuple
    t: float


@dataclass(frozen=True)
class PublishPlan:
    """Publish a separation plan: ``strategy``, the ejection's stamp ``ejection_stamp`` and the header's ``stamp``
    ((sec, nanosec)), ``p_reduction`` [m/s], ``burns`` (:class:`~.common.PlannedBurn`; none: the drift-stop
    withdrawn) and ``aimed`` (None: empty)."""

    strategy: str
    ejection_stamp: tuple
    stamp: tuple
    p_reduction: float
    burns: tuple = ()
    aimed: Aimed | None = None


@dataclass(frozen=True)
class PublishEstimate:
    """Publish the executed ejection estimated from the footage (:func:`~roe_sep.core.od.pose.estimate_ejection`):
    the release epoch ``stamp`` ((sec, nanosec)), ``dv`` (3,) [m/s] RTN and its covariance ``cov`` (9,) [m^2/s^2],
    row-major."""

    stamp: tuple
    dv: tuple
    cov: tuple


@dataclass(frozen=True)
class StopBearings:
    """The camera's decision is made: its bearings are no longer needed."""


@dataclass(frozen=True)
class PlannerState(State):
    """What the planner knows between events: the drift-stop ``in_force``, the ``executed_stops`` on record
    ((epoch [s], carrier dv RTN (3,) [m/s])), the release epoch ``released`` [s] and the wall time ``record_since``
    [s] it arrived, the camera's ``bearings`` ((t [s], unit line of sight (3,))) until ``camera_done``, the
    drift-stop epochs ``retried`` (to the ms), the ejections ``decided`` ((sec, nanosec) stamps), the ``plans``
    published and the last one, ``last_plan`` (the plan in force as the topic latches it). A restart keeps all but
    the ``VOLATILE`` fields: the release, the record's wall time and the bearings come again or are lost."""

    VOLATILE = ("released", "record_since", "bearings")

    in_force: InForce | None = None
    executed_stops: tuple = ()
    released: float | None = None
    record_since: float | None = None
    bearings: tuple = ()
    camera_done: bool = False
    retried: tuple = ()
    plans: int = 0
    decided: tuple = ()
    last_plan: PublishPlan | None = None
    commanded: Ejection | None = None  # the commanded ejection (the footage filter's chief and first guess)
    poses: tuple = ()  # the footage's (t [s], position (3,) [m], covariance (9,) [m^2]) until the estimate
    estimate: tuple | None = None  # the footage's (dv (3,) [m/s], covariance (9,) [m^2/s^2], poses used)
    footage_done: bool = False
    responded: bool = False  # the response to the footage's ejection (:func:`ejection_response`) is decided

    @classmethod
    def from_dict(cls, d: dict) -> "PlannerState":
        """The state of :meth:`to_dict`."""
        def in_force(f):
            return InForce(**{**f, "ejection": Ejection(**{k: tuples(v) for k, v in f["ejection"].items()})})

        return cls(**{**d, "in_force": optional(in_force, d["in_force"]), "executed_stops": tuples(d["executed_stops"]),
                      "bearings": tuples(d["bearings"]), "retried": tuples(d["retried"]),
                      "decided": tuples(d["decided"]), "last_plan": optional(plan_from_dict, d["last_plan"]),
                      "commanded": optional(lambda e: Ejection(**{k: tuples(v) for k, v in e.items()}),
                                            d.get("commanded")),
                      "poses": tuples(d.get("poses", ())), "estimate": optional(tuples, d.get("estimate"))})


def plan_from_dict(d: dict) -> PublishPlan:
    """A :class:`PublishPlan` from its :func:`~.common.plain` form."""
    aimed = optional(lambda a: Aimed(**{k: tuples(v) for k, v in a.items()}), d["aimed"])
    return PublishPlan(**{**d, "ejection_stamp": tuples(d["ejection_stamp"]), "stamp": tuples(d["stamp"]),
                          "burns": tuple(planned_from_dict(b) for b in d["burns"]), "aimed": aimed})


def published(state: PlannerState, plan: PublishPlan) -> PlannerState:
    """The state once ``plan`` is published: one plan more, and it is the plan in force."""
    return dataclasses.replace(state, plans=state.plans + 1, last_plan=plan)


def values(state: PlannerState, config: PlannerConfig) -> dict:
    """The status values."""
    return {"strategy": config.strategy, "k": config.k, "p_mode": config.p_mode,
            "p": "per event" if config.p is None else config.p, "plans": state.plans}


def on_ejection(state: PlannerState, ejection: Ejection, config: PlannerConfig) -> tuple:
    """A commanded ejection: its drift-stop (or multi-impulse) plan (:func:`separation_plan`); one already decided
    (a restarted planner's latched event) plans nothing again.

    Parameters
    ----------
    state, config
        As every rule takes them (module docstring).
    ejection : Ejection
        The commanded ejection.

    Returns
    -------
    tuple
        ``(new state, actions)``; an ERROR status for a malformed event.
    """
    stamp = (ejection.sec, ejection.nanosec)
    if stamp in state.decided:
        return state, (Log("info", f"ejection at t = {ejection.epoch:.1f} s already decided (plan {state.plans} in "
                                   "force): not planned again"),)
    try:
        plan = separation_plan(ejection, config)
    except ValueError as exc:
        return state, (status(ERROR, f"ejection event rejected: {exc}", values(state, config), "error"),)
    burn = plan.burns[0]
    multi = config.strategy == "multi_impulse"
    in_force = state.in_force if multi else InForce(ejection, None, plan.p_reduction, burn.epoch)
    state = dataclasses.replace(published(state, plan), in_force=in_force, decided=(*state.decided, stamp),
                                commanded=ejection)
    x, y, z = burn.dv_rtn
    log = Log("info", f"drift-stop planned at t = {burn.epoch:.1f} s, carrier dv RTN = ({x:+.6f}, {y:+.6f}, "
                      f"{z:+.6f}) m/s, p = {plan.p_reduction:g} m/s")
    return state, (plan, log, status(OK, "drift-stop plan published", values(state, config), None))


def on_executed(state: PlannerState, burn: PlannedBurn, wall: float, config: PlannerConfig) -> tuple:
    """An executed maneuver on record: a carrier drift-stop, or the release (the ejection's epoch: when, not how
    fast).

    Parameters
    ----------
    state, config
        As every rule takes them (module docstring).
    burn : PlannedBurn
        The executed maneuver as its record carries it.
    wall : float
        The wall time [s] it arrived (:func:`record_recovered`).

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    if burn.spacecraft == "carrier" and burn.purpose == "drift_stop":
        if any(round(e, 3) == round(burn.epoch, 3) for e, _ in state.executed_stops):
            return state, ()  # on record already (the latched record again, after a restart)
        return dataclasses.replace(state, executed_stops=(*state.executed_stops, (burn.epoch, burn.dv_rtn))), ()
    if burn.purpose == "ejection" and state.released is None:
        return dataclasses.replace(state, released=burn.epoch, record_since=wall), ()
    return state, ()


def on_bearing(state: PlannerState, t: float, los: ArrayLike, config: PlannerConfig) -> tuple:
    """The camera's measured line of sight, kept until the camera's decision (only with ``hold``).

    Parameters
    ----------
    state, config
        As every rule takes them (module docstring).
    t : float
        The bearing's epoch [s].
    los : array_like, shape (3,)
        The unit line of sight.

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    if not config.hold or state.camera_done:
        return state, ()
    return dataclasses.replace(state, bearings=(*state.bearings, (t, tuple(float(c) for c in los)))), ()


def on_restart(state: PlannerState, config: PlannerConfig) -> tuple:
    """A planner restarted with the recovered ``state``: the plan in force latched again as it was published
    (never a withdrawn one: the hold's empty plan stays the plan in force), the camera left alone once decided."""
    actions = (StopBearings(),) if state.camera_done else ()
    if state.last_plan is not None:
        actions += (state.last_plan,)
    text = (f"restarted with {state.plans} plan(s) decided: " + ("no plan in force" if state.last_plan is None else
            f"the plan in force ({len(state.last_plan.burns)} burn(s)) latched again"))
    return state, (*actions, status(OK, text, values(state, config)))


def on_pose(state: PlannerState, t: float, pos: ArrayLike, cov: ArrayLike, config: PlannerConfig) -> tuple:
    """A pose of the footage at ``t`` [s], kept until the estimate.

    Parameters
    ----------
    state, t, config
        As every rule takes them (module docstring).
    pos : array_like, shape (3,)
        The relative position [m] RTN.
    cov : array_like, shape (9,)
        Its covariance [m^2], row-major.

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    if not config.footage or state.footage_done:
        return state, ()
    pose = (float(t), tuple(float(c) for c in pos), tuple(float(c) for c in cov))
    return dataclasses.replace(state, poses=(*state.poses, pose)), ()


def footage_estimate(state: PlannerState, t: float, config: PlannerConfig) -> tuple:
    """The executed ejection from the footage once it is complete (``footage_window`` after its first pose, at
    ``t`` [s]): :func:`~roe_sep.core.od.pose.estimate_ejection` from the commanded ejection's chief, the release
    guessed one frame before the first pose; a :class:`PublishEstimate`. Fewer than 2 poses: no estimate (the
    bearings decide).

    Parameters
    ----------
    state, t, config
        As every rule takes them (module docstring).

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    if not config.footage or state.footage_done or not state.poses or state.commanded is None \
            or t < state.poses[0][0] + config.footage_window:
        return state, ()
    state = dataclasses.replace(state, footage_done=True)
    poses, ej = state.poses, state.commanded
    times = np.array([p[0] for p in poses])
    if len(times) < 2:
        return dataclasses.replace(state, poses=()), (Log("info", f"footage: {len(times)} pose(s), no estimate"),)
    frame = float(np.min(np.diff(times)))
    try:
        est = estimate_ejection(times, np.array([p[1] for p in poses]),
                                np.array([p[2] for p in poses]).reshape(-1, 3, 3), times[0] - frame,
                                (ej.kep[0], ej.kep[2], ej.kep[4] + ej.kep[5], ej.epoch), j2=config.j2)
    except (ValueError, np.linalg.LinAlgError) as exc:  # a singular geometry: the bearings decide
        return dataclasses.replace(state, poses=()), (Log("warning", f"footage: no estimate ({exc})"),)
    dv, cov = tuple(float(c) for c in est.dv), tuple(float(c) for c in est.cov.reshape(-1))
    if not all(math.isfinite(c) for c in dv + cov):
        return dataclasses.replace(state, poses=()), (Log("warning", "footage: the filter did not converge"),)
    state = dataclasses.replace(state, poses=(), estimate=(dv, cov, len(times)))
    mag = float(np.linalg.norm(est.dv))
    sig = math.sqrt(float(est.dv @ est.cov @ est.dv)) / mag
    cmd = float(np.linalg.norm(ej.dv_rtn))
    log = Log("info", f"footage: {len(times)} poses, executed ejection |dv| = {mag:.5f} +- {sig:.5f} m/s "
                      f"({100 * sig / mag:.3f} %, {mag / cmd:.4f} of the commanded), release at "
                      f"t = {float(est.t0):.3f} +- {float(est.sigma_t0):.3f} s, chi-square {float(est.chi2):.1f} for "
                      f"{3 * len(times) - 4} dof")
    return state, (PublishEstimate(sec_nanosec(float(est.t0)), dv, cov), log)


def record_recovered(state: PlannerState, wall: float, lockstep: bool) -> bool:
    """Whether the executed-maneuver record is complete enough to say a drift-stop is missing: the executed ejection
    is on it and, without ``lockstep`` (where every round holds every message), ``RECORD_SETTLE`` wall seconds have
    passed since it arrived (a restarted planner's latched history taken in full).

    Parameters
    ----------
    state
        As every rule takes them (module docstring).
    wall : float
        The wall time [s] now.
    lockstep : bool
        Whether the run is in lockstep.

    Returns
    -------
    bool
        True when a missing drift-stop may be told from the record.
    """
    if state.released is None:
        return False
    return lockstep or wall - state.record_since >= RECORD_SETTLE


def on_step(state: PlannerState, t: float, wall: float, lockstep: bool, config: PlannerConfig) -> tuple:
    """Sim-time checks at ``t`` [s] (wall time ``wall``; ``lockstep``: the record holds every message): the camera's
    decision before the drift-stop (:func:`camera_decision`), a missing drift-stop's replacement
    (:func:`missing`, :func:`replace_missing`), a departing one's completion (:func:`check_executed`).

    Parameters
    ----------
    state, t, config
        As every rule takes them (module docstring).
    wall : float
        The wall time [s] (:func:`record_recovered`).
    lockstep : bool
        Whether the record holds every message (a lockstep run).

    Returns
    -------
    tuple
        ``(new state, actions)``; a failed check adds an ERROR status.
    """
    if state.in_force is None and (state.footage_done or state.commanded is None):
        return state, ()
    actions = ()
    recovered = record_recovered(state, wall, lockstep)
    try:
        state, actions = footage_estimate(state, t, config)
        state, more = ejection_response(state, t, config)
        actions += more
        if state.in_force is not None and not state.camera_done and t >= state.in_force.t_stop - config.hold_lead:
            state, actions = dataclasses.replace(state, camera_done=True), actions + (StopBearings(),)
            state, more = camera_decision(state, t, config)
            actions += more
        if config.retry and state.in_force is not None and recovered and missing(state, t, config):
            # found missing once, even when its replacement fails
            state = dataclasses.replace(state, retried=(*state.retried, round(state.in_force.t_stop, 3)))
            state, more = replace_missing(state, t, config)
            actions += more
        if config.makeup and state.in_force is not None and recovered:
            state, more = check_executed(state, t, config)
            actions += more
    except ValueError as exc:
        actions += (status(ERROR, f"drift-stop check failed: {exc}", values(state, config), "error"),)
    return state, actions


def finding(name: str, t: float, text: str, extra: dict) -> Status:
    """A contingency the planner acted on: logged, and a WARN status on the ``contingency`` part.

    Parameters
    ----------
    name : str
        The contingency's name ("weak_ejection", "drift_stop_replaced", ...), the status value ``contingency``.
    t : float
        The finding's sim time [s]: the status's stamp and its ``epoch_s``.
    text : str
        What was found and done.
    extra : dict
        More status values.

    Returns
    -------
    Status
        The action.
    """
    return status(WARN, f"{name}: {text}", {"contingency": name, "epoch_s": f"{t:.1f}", **extra}, "warning",
                  part="contingency", stamp=t)


def camera_decision(state: PlannerState, t: float, config: PlannerConfig) -> tuple:
    """Test the camera's bearings against the commanded ejection
    (:func:`~roe_sep.core.safety.ejection_check.check_ejection`); withdraw the drift-stop of a weak one (an empty
    plan).

    Parameters
    ----------
    state, t, config
        As every rule takes them (module docstring).

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    f = state.in_force
    if config.hold and state.estimate is not None and t < f.t_stop:
        return footage_decision(state, t, config)
    if not config.hold or state.released is None or t >= f.t_stop or not state.bearings:
        return state, ()
    ejection = f.ejection
    chief = propagate_chief(np.array(ejection.kep, dtype=float), state.released - ejection.epoch, config.j2)
    mc = config.scenario.monte_carlo
    da_dot = nominal_da_dot(config, chief[0])
    times = np.array([b[0] for b in state.bearings])
    los = np.array([b[1] for b in state.bearings])
    bound = nominal_fraction(config.scenario.separation.spl_sigma, mc.ballistic_sigma, config.hold_sigmas)
    check = check_ejection(times, los, np.array(ejection.dv_rtn, dtype=float), state.released, chief,
                           da_dot=da_dot, sigma=config.camera_sigma, floor=config.camera_floor, bound=bound,
                           alpha=config.hold_alpha, j2=config.j2)
    state = dataclasses.replace(state, bearings=())
    log = Log("info", f"camera check of the ejection: best f1/g = {check.f1:.2f} (nominal >= {bound:.3f}), chi-square "
                      f"gain {check.gain:.1f}, {check.samples} bearings: "
                      f"{'drift-stop held' if check.weak else 'drift-stop flies'}")
    if not check.weak:
        return state, (log,)
    hold = PublishPlan("double_impulse", (ejection.sec, ejection.nanosec), sec_nanosec(t), 0.0)
    state = dataclasses.replace(published(state, hold), in_force=None)
    return state, (log, hold, finding(
        "weak_ejection", t, f"the camera's bearings fit f1 = {check.f1:.2f} of the commanded ejection at the nominal "
        f"drag (chi-square gain {check.gain:.1f} over the nominal set f1/g >= {bound:.3f}, {check.samples} bearings): "
        f"drift-stop at t = {f.t_stop:.0f} s withdrawn, the acquisition starts from the first OD",
        {"f1": f"{check.f1:.3f}", "gain": f"{check.gain:.2f}", "samples": check.samples}))


def footage_decision(state: PlannerState, t: float, config: PlannerConfig) -> tuple:
    """The weak-ejection test on the footage's estimate: the fraction f1 of the commanded ejection (the estimate
    projected on it) against the nominal set's bound of the bearings test (the same rule, so nominal runs decide as
    before), weak when below it by more than the normal quantile 1 - ``hold_alpha`` of its sigma; withdraw the
    drift-stop of a weak one (an empty plan).

    Parameters
    ----------
    state, t, config
        As every rule takes them (module docstring).

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    f = state.in_force
    cmd = np.array(f.ejection.dv_rtn, dtype=float)
    dv, cov = np.array(state.estimate[0]), np.array(state.estimate[1]).reshape(3, 3)
    frac = float(dv @ cmd) / float(cmd @ cmd)
    sigma = math.sqrt(float(cmd @ cov @ cmd)) / float(cmd @ cmd)
    mc = config.scenario.monte_carlo
    bound = nominal_fraction(config.scenario.separation.spl_sigma, mc.ballistic_sigma, config.hold_sigmas)
    from scipy.special import ndtri  # here, not at import (as check_ejection's chdtri)

    z = (bound - frac) / sigma if sigma > 0.0 else math.inf
    weak = bool(frac < bound and z > float(ndtri(1.0 - config.hold_alpha)))
    state = dataclasses.replace(state, bearings=())
    log = Log("info", f"footage check of the ejection: f1 = {frac:.4f} +- {sigma:.4f} (nominal >= {bound:.3f}): "
                      f"{'drift-stop held' if weak else 'drift-stop flies'}")
    if not weak:
        return state, (log,)
    hold = PublishPlan("double_impulse", (f.ejection.sec, f.ejection.nanosec), sec_nanosec(t), 0.0)
    state = dataclasses.replace(published(state, hold), in_force=None)
    return state, (log, hold, finding(
        "weak_ejection", t, f"the footage measured f1 = {frac:.4f} +- {sigma:.4f} of the commanded ejection "
        f"({z:.1f} sigma below the nominal set f1 >= {bound:.3f}): drift-stop at t = {f.t_stop:.0f} s withdrawn, "
        "the acquisition starts from the first OD",
        {"f1": f"{frac:.3f}", "gain": f"{z * z:.2f}", "samples": state.estimate[2], "source": "footage"}))


def ejection_response(state: PlannerState, t: float, config: PlannerConfig) -> tuple:
    """The response to the executed ejection the footage measured (issue 41 part 2; docs/run.md, "The ejection
    camera"), decided once, as soon as the estimate is made (``cam``, ``completion``):

    1. :func:`~.cam.cam_decision`: an ejection off its command whose measured trajectory comes back inside the
       keep-out gets a carrier CAM ``cam_latency`` after the estimate (with ``cam``);
    2. a stuck picosatellite (the measured fraction of the commanded ejection below ``stuck_fraction``: seed 004's
       jamming) is reported as such and its drift-stop withdrawn (the carrier keeps the CAM's drift; the acquisition
       starts from the first OD);
    3. otherwise (with ``completion``, double impulse) the ejection is completed
       (:func:`~.cam.completion_burns`: commanded minus measured at the release's u, whole orbits later, in pulses of
       at most ``completion_max_pulse``), the CAM undone after it (:func:`~.cam.reversal_burn`), and the designed
       drift-stop (seed 002 Eqs. 9, 18) flown the first odd number of half orbits after both: the pair reaches the
       designed e/i vectors and drift. The plan in force becomes that one, and the camera's later hold test is
       moot.

    Without ``completion`` (or for the multi-impulse plan) the CAM is added to the plan in force. A nominal ejection
    (within its command) changes nothing.

    Parameters
    ----------
    state, t, config
        As every rule takes them (module docstring).

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    if state.responded or state.estimate is None or state.commanded is None or not (config.cam or config.completion):
        return state, ()
    state = dataclasses.replace(state, responded=True)
    if state.in_force is not None and t >= state.in_force.t_stop:  # the drift-stop is due: too late to act before it
        return state, (Log("warning", f"footage: the estimate came at t = {t:.0f} s, after the drift-stop's epoch "
                                      f"t = {state.in_force.t_stop:.0f} s: no response"),)
    ej = state.commanded
    dv, cov = np.array(state.estimate[0]), np.array(state.estimate[1]).reshape(3, 3)
    cmd = np.array(ej.dv_rtn, dtype=float)
    chief = Chief(ej.kep[0], ej.kep[2], ej.u1, ej.epoch)
    da_dot = nominal_da_dot(config, chief.a)
    cam_config = CamConfig(spl_sigma=config.scenario.separation.spl_sigma, pointing_sigma=config.pointing_sigma,
                           latency=config.cam_latency, sigmas=config.cam_sigmas, dv_cam=config.cam_dv, j2=config.j2)
    found = cam_decision(dv, cov, cmd, chief, t, da_dot=da_dot, config=cam_config)
    if not found.off:
        return state, (Log("info", f"footage: {found.reason}"),)
    frac = float(dv @ cmd) / float(cmd @ cmd)
    cam = found.burn if config.cam else None
    f, last = state.in_force, state.last_plan
    stuck = frac < config.stuck_fraction
    values_ = {"f1": f"{frac:.3f}", "magnitude_z": f"{found.magnitude_z:.1f}", "pointing_z": f"{found.pointing_z:.1f}",
               "cam_m_s": "0" if cam is None else f"{cam.dv_rtn[1]:+.3f}"}
    stamp = (ej.sec, ej.nanosec)
    if stuck or not config.completion or config.strategy == "multi_impulse" or f is None:
        keep = () if stuck or last is None else last.burns
        if cam is None and not stuck:
            return state, (Log("warning", f"footage: {found.reason}; nothing to change in the plan in force"),)
        plan = PublishPlan(config.strategy, stamp, sec_nanosec(t), 0.0 if stuck or last is None else last.p_reduction,
                           tuple(sorted(((cam,) if cam else ()) + keep, key=lambda b: b.epoch)),
                           None if stuck or last is None else last.aimed)
        state = published(state, plan)
        if stuck:
            state = dataclasses.replace(state, in_force=None, camera_done=True)
        if not stuck:
            return state, (plan, finding("ejection_off", t, found.reason, values_))
        text = (f"the footage measured f1 = {frac:.3f} of the commanded ejection (below {config.stuck_fraction:g}: "
                f"stuck), drift-stop withdrawn, the acquisition starts from the first OD; {found.reason}")
        return state, (plan, StopBearings(), finding("stuck_ejection", t, text, values_))
    period = orbit_period(ej, config)
    pulses = completion_burns(dv, cmd, t_release=ej.epoch, u_release=ej.u1, period=period,
                              t_earliest=t + config.cam_latency + (1.0 if cam else 0.0),
                              max_pulse=config.completion_max_pulse)
    extra = (cam,) if cam else ()
    end = max([b.epoch for b in pulses], default=t + config.cam_latency)
    extra += pulses
    if cam is not None:
        undo = reversal_burn(cam, period, end)
        extra, end = extra + (undo,), max(end, undo.epoch)
    k = config.k if f.k is None else f.k
    k += 2 * max(0, math.ceil((end - (ej.epoch + k * period / 2.0)) / period))  # the first odd k after ``end``
    stop = separation_plan(ej, config, k=k, p=f.p)
    while stop.burns[0].epoch <= end:  # at most once: the drift-stop's own rate against ``period``
        k += 2
        stop = separation_plan(ej, config, k=k, p=f.p)
    plan = PublishPlan("double_impulse", stamp, sec_nanosec(t), stop.p_reduction, extra + stop.burns, stop.aimed)
    t_stop = stop.burns[0].epoch
    done = state.camera_done
    state = published(dataclasses.replace(state, in_force=InForce(ej, k, f.p, t_stop), camera_done=True), plan)
    rest = float(np.linalg.norm(cmd - dv))
    values_.update(completion_m_s=f"{rest:.4f}", pulses=len(pulses), drift_stop_epoch_s=f"{t_stop:.1f}")
    return state, (plan, *(() if done else (StopBearings(),)), finding(
        "ejection_off", t, f"{found.reason}; the rest of the ejection, {rest:.4f} m/s, in {len(pulses)} carrier "
        f"pulse(s) from t = {pulses[0].epoch if pulses else t:.0f} s" + ("" if cam is None else ", the CAM undone at "
                                                        f"t = {extra[-1].epoch:.0f} s") +
        f", the drift-stop {k} half orbits after the release at t = {t_stop:.0f} s", values_))


def orbits_later(ejection: Ejection, t: float, t_burn: float, config: PlannerConfig) -> tuple:
    """Where a replaced or completed drift-stop flies at its argument of latitude: whole orbits after the burn.

    Parameters
    ----------
    config
        As every rule takes them (module docstring).
    ejection : Ejection
        The commanded ejection (its chief's a and i give the period, with J2 when ``config.j2``).
    t, t_burn : float
        The finding's time and the burn's epoch [s].

    Returns
    -------
    tuple
        ``(orbits, period)``: the whole orbits (at least one) after ``t_burn`` to the first epoch ``retry_margin``
        after ``t``, and the period [s].
    """
    period = orbit_period(ejection, config)
    return max(1, math.ceil((t + config.retry_margin - t_burn) / period - 1e-9)), period


def orbit_period(ejection: Ejection, config: PlannerConfig) -> float:
    """The period [s] of the mean argument of latitude of the ejection's chief (its a and i; with J2 when
    ``config.j2``)."""
    return 2.0 * math.pi / float(arg_latitude_rate(ejection.kep[0], ejection.kep[2], config.j2))


def nominal_da_dot(config: PlannerConfig, a: float) -> float:
    """The nominal differential-drag rate of da [1/s] at the semi-major axis ``a`` [m] (the scenario's ballistic
    difference and density; 0 without drag): what the planner predicts the pair with."""
    mc = config.scenario.monte_carlo
    return float(drag_da_dot(mc.delta_b, mc.density, a)) if mc.drag else 0.0


def missing(state: PlannerState, t: float, config: PlannerConfig) -> bool:
    """Whether the record shows no drift-stop ``retry_tolerance`` after the epoch of the one in force (not replaced
    yet).

    Parameters
    ----------
    state, t, config
        As every rule takes them (module docstring).

    Returns
    -------
    bool
        True for a missing drift-stop.
    """
    f = state.in_force
    if t <= f.t_stop + config.retry_tolerance or round(f.t_stop, 3) in state.retried:
        return False
    return not any(e >= f.t_stop - config.retry_tolerance for e, _ in state.executed_stops)


def replace_missing(state: PlannerState, t: float, config: PlannerConfig) -> tuple:
    """The missing drift-stop in force replaced: the same one whole orbits later (seed 002 Eqs. 9, 18), a new plan
    stamped with the finding.

    Parameters
    ----------
    state, t, config
        As every rule takes them (module docstring).

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    f = state.in_force
    k = config.k if f.k is None else f.k
    orbits, _ = orbits_later(f.ejection, t, f.t_stop, config)
    plan = dataclasses.replace(separation_plan(f.ejection, config, k=k + 2 * orbits, p=f.p), stamp=sec_nanosec(t))
    t_new = plan.burns[0].epoch
    state = dataclasses.replace(published(state, plan), in_force=InForce(f.ejection, k + 2 * orbits, f.p, t_new))
    return state, (plan, finding(
        "drift_stop_replaced", t, f"no drift-stop on record {t - f.t_stop:.0f} s after its epoch t = {f.t_stop:.1f} "
        f"s: the same drift-stop {orbits} orbit(s) later, at t = {t_new:.1f} s",
        {"planned_epoch_s": f"{f.t_stop:.1f}", "replacement_epoch_s": f"{t_new:.1f}"}))


def check_executed(state: PlannerState, t: float, config: PlannerConfig) -> tuple:
    """Complete the drift-stop in force when the record's drift-stop departs from its command (beyond ``makeup_z``
    sigmas or ``makeup_pointing``): the rest, commanded minus executed, whole orbits later at the same argument of
    latitude (seed 002 Eq. 2 is linear in the burn at a given u).

    Parameters
    ----------
    state, t, config
        As every rule takes them (module docstring).

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    f = state.in_force
    done = [(e, dv) for e, dv in state.executed_stops if e >= f.t_stop - config.retry_tolerance]
    if not done or config.strategy == "multi_impulse":
        return state, ()
    if len(done) > 1:  # a completion already flew (a restarted planner's record)
        return dataclasses.replace(state, in_force=None), ()
    t_exec, dv_exec = done[0][0], np.array(done[0][1], dtype=float)
    plan = separation_plan(f.ejection, config, k=f.k, p=f.p)
    burn = plan.burns[0]
    dv_cmd = np.array(burn.dv_rtn, dtype=float)
    ref = error_references(["drift_stop"], [dv_cmd], plan.p_reduction)[0]
    z = magnitude_z(dv_exec, dv_cmd, ref, config.scenario.separation.thruster_sigma)
    off = float(angle_between(dv_exec, dv_cmd))
    state = dataclasses.replace(state, in_force=None)  # one drift-stop, checked once
    if (z is None or abs(z) <= config.makeup_z) and off <= config.makeup_pointing:
        return state, ()
    orbits, period = orbits_later(f.ejection, t, burn.epoch, config)
    t_new = burn.epoch + orbits * period
    rest = dv_cmd - dv_exec
    out = PublishPlan("double_impulse", (f.ejection.sec, f.ejection.nanosec), sec_nanosec(t), 0.0,
                      (PlannedBurn.at(t_new, burn.u, rest, "carrier", "drift_stop"),), plan.aimed)
    state = published(state, out)
    norm = float(np.linalg.norm(rest))
    return state, (out, finding(
        "drift_stop_completed", t, f"the drift-stop at t = {t_exec:.1f} s executed {float(np.linalg.norm(dv_exec)):.4f}"
        f" m/s of {float(np.linalg.norm(dv_cmd)):.4f} m/s ({'n/a' if z is None else f'{z:+.1f}'} sigma, "
        f"{math.degrees(off):.2f} deg off): the rest, {norm:.4f} m/s, {orbits} orbit(s) later at t = {t_new:.1f} s",
        {"executed_epoch_s": f"{t_exec:.1f}", "completion_epoch_s": f"{t_new:.1f}", "rest_m_s": f"{norm:.4f}"}))


def separation_plan(ejection: Ejection, config: PlannerConfig, *, k: int | None = None,
                    p: float | None = None) -> PublishPlan:
    """The plan of one commanded ejection: the drift-stop k pi later with reduction ``p`` (defaults: the config's;
    seed 002 Eqs. 9, 18, 21) or every multi-impulse carrier burn (seed 001 Sec. 3).

    Parameters
    ----------
    config
        As every rule takes them (module docstring).
    ejection : Ejection
        The commanded ejection.
    k : int, optional
        The drift-stop's half-orbit count (default ``config.k``).
    p : float, optional
        The drift reduction [m/s] (default ``config.p``, or the least of :func:`reduction_bounds`).

    Returns
    -------
    PublishPlan
        The plan; ValueError on a malformed event (NaN, impossible orbit).
    """
    a, e, inc, raan, argp = ejection.kep[:5]
    if not (math.isfinite(a) and a > 6.4e6 and math.isfinite(inc) and math.isfinite(raan)):
        raise ValueError(f"chief elements are not a valid low Earth orbit (a = {a} m, i = {inc} rad)")
    dv1 = np.array(ejection.dv_rtn, dtype=float)
    if not np.all(np.isfinite(dv1)):
        raise ValueError(f"ejection dv is not finite: {dv1.tolist()}")
    stamp, epoch1 = (ejection.sec, ejection.nanosec), ejection.epoch
    if config.strategy == "multi_impulse":
        sep = multi_config(config.scenario.separation, config.multi)
        da_dot = nominal_da_dot(config, a)  # the pair is planned on the nominal differential drag
        plan = plan_carrier_burns(dv1, ejection.u1, epoch1, a, inc, sep=sep, mcfg=config.multi, j2=config.j2,
                                  da_dot=da_dot)
        burns = tuple(PlannedBurn.at(b.epoch, b.u, b.dv_carrier_rtn, "carrier", b.purpose) for b in plan.burns)
        return PublishPlan("multi_impulse", stamp, stamp, float(plan.p), burns,
                           _aimed(ejection, plan.roe_final, plan.ic_epoch, plan.burns[-1].u, config))
    if p is None:
        p = reduction_bounds(dv1[1], config.scenario.separation)[0] if config.p is None else config.p
    stop = plan_drift_stop(dv1, ejection.u1, epoch1, a, inc, k=k or config.k, p=p, j2=config.j2)
    burn = PlannedBurn.at(stop.epoch, stop.u2, stop.dv_carrier_rtn, "carrier", "drift_stop")
    return PublishPlan("double_impulse", stamp, stamp, float(stop.p), (burn,),
                       _aimed(ejection, stop.aimed_roe, stop.epoch, stop.u2, config))


def _aimed(ejection: Ejection, roe, t: float, u: float, config: PlannerConfig) -> Aimed:
    """``roe`` at ``t`` [s] with the chief's elements there (its RAAN drifted under J2, mean argument of latitude
    ``u``)."""
    a, e, inc, raan, argp = ejection.kep[:5]
    dt = t - ejection.epoch
    raan_t = float(wrap_angle(raan + (raan_rate(a, inc) * dt if config.j2 else 0.0)))
    return Aimed(tuple(float(x) for x in roe), (a, e, inc, raan_t, argp, float(wrap_angle(u))), float(t))
