"""The ic_planner's decisions (docs/run.md, "Decisions"): when an OD solution re-plans the acquisition, when the final
OD trims it, when a committed burn defers a re-plan, when a departing burn re-plans or re-trims.

Each ``on_<event>(state, event, config)`` returns ``(new_state, actions)``: :class:`PublishPlan` and the shared
:class:`~.common.Status` / :class:`~.common.Log`. The rules take ``state`` (:class:`IcPlannerState`, what the ic_planner
knows before the event), ``od`` (an :class:`OdSolution`), ``now`` (the decision time [s]) and ``config``
(:class:`IcPlannerConfig`, the node's parameters) as they need them. The physics is :mod:`roe_sep.core.acquisition`
(seed 001 Sec. 4: the linear program and its quantized re-solve; seed 002 Eq. 2 for the trim and the departure of a
burn).
"""

import dataclasses
import functools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..acquisition.lp_transfer import grid_epochs
from ..acquisition.planner import (
    AcquisitionConfig,
    AcquisitionInfeasible,
    AcquisitionPlan,
    check_inputs,
    plan_acquisition,
)
from ..acquisition.trim import (
    CLUSTER_GAP,
    TrimDecision,
    a_da_change,
    burns_drift_sigma,
    drift_lattice,
    ei_margin,
    final_od_arc,
    plan_trim,
    predicted_drift_sigma,
    radar_passes,
    trim_problems,
)
from ..constants import ARCSEC, SECONDS_PER_DAY
from ..relmotion.dynamics import drag_da_dot, propagate_chief
from ..relmotion.maneuvers import control_matrix, delta_roe
from ..relmotion.orbit import mean_motion
from ..relmotion.roe import wrap_angle
from ..relmotion.trajectory import Chief, state_at
from .common import (
    ERROR,
    OK,
    WARN,
    Log,
    PlannedBurn,
    State,
    burn_from_dict,
    guarded,
    optional,
    planned_from_dict,
    scalar,
    status,
    tuples,
)

PASS_SLACK = 900.0  # s, between a predicted pass and its OD solution (the 5 km separation, the solution's delay)
SUMMARY_KEYS = ("total_dv", "n_burns", "time_to_ic", "a_dl_f", "a_da_f", "min_rn", "fov_ok", "solve_time")


@dataclass(frozen=True)
class IcPlannerConfig:
    """The node's parameters (docs/parameters.md, ic_planner) and ``jd0``, the Julian date of sim time 0."""

    cfg: AcquisitionConfig
    trim: bool
    burn_sigma: float
    final_od_arc: float
    replan_on_burn: bool
    ei_margin_sigmas: float
    ic_drift_tolerance: float
    jd0: float
    blind_after: float = 0.0


@dataclass(frozen=True)
class OdSolution:
    """One OD solution (roe_sep_msgs/OrbitDetermination): solution ``stamp`` and estimate ``epoch`` [s], the chief's
    mean elements ``kep`` ``[a, e, i, raan, argp, M]`` and its mean argument of latitude ``u`` [rad] as the message
    carries it, the dimensionless ``roe``, their ``covariance`` (36, a*ROE [m^2]), ``a_da_dot`` [m/s] and its
    1-sigma ``a_da_dot_sigma``."""

    stamp: float
    epoch: float
    kep: tuple
    u: float
    roe: tuple
    covariance: tuple
    a_da_dot: float
    a_da_dot_sigma: float

    @property
    def a(self) -> float:
        return self.kep[0]

    @property
    def sigma_a_da(self) -> float:
        """m, 1-sigma of a da from the covariance."""
        return math.sqrt(max(self.covariance[0], 0.0))


@dataclass(frozen=True)
class PublishPlan:
    """Publish the acquisition plan: header ``stamp`` [s], its ``burns`` (:class:`~.common.PlannedBurn`), ``aimed``
    the predicted ROE (dimensionless) at the IC epoch ``t_final`` [s] with the chief's mean elements ``aimed_kep``
    there (angles wrapped)."""

    stamp: float
    burns: tuple
    aimed_roe: tuple
    aimed_kep: tuple
    t_final: float


@dataclass(frozen=True)
class EjectionPrior:
    """What the ground knows of the pair before any OD (issue 41 part 3): the release epoch ``t`` [s], the chief's
    mean elements ``kep`` ``[a, e, i, raan, argp, M]`` and mean argument of latitude ``u`` [rad] there, the
    picosatellite's ejection ``dv`` (3,) [m/s] RTN and its covariance ``cov`` (9,) [m^2/s^2] (the commanded one with
    the SPL's errors, or the footage's measured one), the nominal differential drag ``a_da_dot`` [m/s] and its
    1-sigma ``a_da_dot_sigma`` [m/s], and ``source`` ("commanded" or "footage")."""

    t: float
    kep: tuple
    u: float
    dv: tuple
    cov: tuple
    a_da_dot: float
    a_da_dot_sigma: float
    source: str = "commanded"

    @classmethod
    def commanded(cls, t: float, kep: ArrayLike, u: float, dv: ArrayLike, scenario: Any) -> "EjectionPrior":
        """The commanded ejection with the scenario's SPL magnitude error ``spl_sigma`` along it and its attitude
        error ``attitude_sigma_arcsec`` across it as the covariance (seed 002 Eq. 22), and its nominal differential
        drag with the ``ballistic_sigma`` fraction as its 1-sigma.

        Parameters
        ----------
        t : float
            The ejection's epoch [s].
        kep : array_like, shape (6,)
            The chief's mean elements ``[a, e, i, raan, argp, M]`` there.
        u : float
            Its mean argument of latitude [rad].
        dv : array_like, shape (3,)
            The commanded ejection [m/s] RTN.
        scenario : Scenario
            The scenario (:func:`~roe_sep.core.config.load_scenario`).

        Returns
        -------
        EjectionPrior
            The prior, ``source`` "commanded".
        """
        dv = np.asarray(dv, dtype=float)
        sep, mc = scenario.separation, scenario.monte_carlo
        along = np.outer(dv, dv)
        cov = sep.spl_sigma ** 2 * along + (mc.attitude_sigma_arcsec * ARCSEC) ** 2 * (float(dv @ dv) * np.eye(3)
                                                                                        - along)
        a = float(kep[0])
        a_da_dot = float(drag_da_dot(mc.delta_b, mc.density, a)) * a if mc.drag else 0.0
        return cls(float(t), tuple(float(x) for x in kep), float(u), tuple(float(x) for x in dv),
                   tuple(float(x) for x in cov.reshape(-1)), a_da_dot, abs(a_da_dot) * mc.ballistic_sigma)

    def measured(self, dv: ArrayLike, cov: ArrayLike) -> "EjectionPrior":
        """The same knowledge with the footage's measured ejection ``dv`` (3,) [m/s] RTN and its covariance (3, 3)
        or (9,) [m^2/s^2] in place of the commanded one (``source`` "footage")."""
        return dataclasses.replace(self, dv=tuple(float(x) for x in np.asarray(dv, dtype=float).reshape(-1)),
                                   cov=tuple(float(x) for x in np.asarray(cov, dtype=float).reshape(-1)),
                                   source="footage")

    def solution(self, stamp: float) -> "OdSolution":
        """The prior as an OD solution at the release, made at ``stamp`` [s]: the ROE of the ejection (seed 002
        Eq. 2 at the release: :func:`~roe_sep.core.relmotion.maneuvers.delta_roe`) and their a-scaled covariance
        mapped linearly from the dv's."""
        a = self.kep[0]
        n = float(mean_motion(a))
        roe = delta_roe(np.array(self.dv, dtype=float), self.u, a, n)
        jac = control_matrix(self.u) / n  # (6, 3): a times Eq. 2's dROE / d dv, m per m/s
        cov = jac @ np.array(self.cov, dtype=float).reshape(3, 3) @ jac.T
        return OdSolution(float(stamp), float(self.t), tuple(self.kep), float(self.u), tuple(float(x) for x in roe),
                          tuple(float(x) for x in cov.reshape(-1)), float(self.a_da_dot), float(self.a_da_dot_sigma))


@dataclass(frozen=True)
class IcPlannerState(State):
    """What the ic_planner knows between events: the separation plan's last burn ``separation_end`` [s] (None: no
    separation plan), the carrier burns ``executed`` (relative impulses), the IC epoch ``t_final`` [s], the newest OD's
    ``last_key`` (solution stamp, epoch), the plan in force (``plan_in_force`` burns, their ``burn_epochs``, the
    1-sigma ``plan_sigma`` [m] of a da at t_F from its OD at ``plan_od_epoch``), whether the final OD decided
    (``final_decided``), the newest OD after the separation ``last_od``, a deferred re-plan ``replan_pending``, the
    last plan's ``summary`` ((key, value) pairs as the status shows them), the ``plans`` published and the last one,
    ``last_plan`` (the plan in force as the topic latches it), the knowledge of the ejection before any OD
    ``ejection`` (:class:`EjectionPrior`) and whether the blind acquisition was planned (``blind``). A restart
    keeps it all."""

    separation_end: float | None = None
    executed: tuple = ()
    t_final: float | None = None
    last_key: tuple | None = None
    burn_epochs: tuple | None = None
    plan_in_force: tuple | None = None
    final_decided: bool = False
    plan_sigma: float | None = None
    plan_od_epoch: float | None = None
    last_od: OdSolution | None = None
    replan_pending: bool = False
    summary: tuple = ()
    plans: int = 0
    last_plan: PublishPlan | None = None
    ejection: EjectionPrior | None = None
    blind: bool = False

    @classmethod
    def from_dict(cls, d: dict) -> "IcPlannerState":
        """The state of :meth:`to_dict`."""
        return cls(**{**d, "executed": tuple(burn_from_dict(b) for b in d["executed"]),
                      "ejection": optional(lambda e: EjectionPrior(**{k: tuples(v) for k, v in e.items()}),
                                           d.get("ejection")),
                      "last_key": optional(tuples, d["last_key"]), "burn_epochs": optional(tuples, d["burn_epochs"]),
                      "plan_in_force": optional(lambda p: tuple(planned_from_dict(b) for b in p), d["plan_in_force"]),
                      "last_od": optional(lambda o: OdSolution(**{k: tuples(v) for k, v in o.items()}), d["last_od"]),
                      "summary": tuples(d["summary"]), "last_plan": optional(plan_from_dict, d["last_plan"])})


def plan_from_dict(d: dict) -> PublishPlan:
    """A :class:`PublishPlan` from its :func:`~.common.plain` form."""
    return PublishPlan(**{**d, "burns": tuple(planned_from_dict(b) for b in d["burns"]),
                          "aimed_roe": tuples(d["aimed_roe"]), "aimed_kep": tuples(d["aimed_kep"])})


def values(state: IcPlannerState) -> dict:
    """The status values: plans published and the last plan's summary."""
    return {"plans": state.plans, **dict(state.summary)}


def _shown(value):
    """A summary value as the status shows it: a float to 6 significant digits, else its Python value."""
    value = scalar(value)
    return f"{value:.6g}" if isinstance(value, float) else value


def on_ejection(state: IcPlannerState, prior: EjectionPrior, config: IcPlannerConfig) -> tuple:
    """The commanded ejection, the knowledge a blind acquisition starts from (:func:`on_step`); a measured one on
    record is kept (the latched event again after a restart, or after the estimate).

    Parameters
    ----------
    state, config
        As every rule takes them (module docstring).
    prior : EjectionPrior
        The commanded ejection with the SPL's errors as its covariance.

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    if state.ejection is not None and (state.ejection.source != "commanded" or state.ejection == prior):
        return state, ()
    return dataclasses.replace(state, ejection=prior), ()


def on_measured(state: IcPlannerState, dv: ArrayLike, cov: ArrayLike, config: IcPlannerConfig) -> tuple:
    """The executed ejection the footage measured (the planner's ground filter): it replaces the commanded one.

    Parameters
    ----------
    state, config
        As every rule takes them (module docstring).
    dv : array_like, shape (3,)
        The measured ejection [m/s] RTN.
    cov : array_like, shape (9,)
        Its covariance [m^2/s^2], row-major.

    Returns
    -------
    tuple
        ``(new state, actions)``; without the commanded ejection on record, nothing (its chief is needed).
    """
    if state.ejection is None:
        return state, ()
    measured = state.ejection.measured(dv, cov)
    return (state, ()) if measured == state.ejection else (dataclasses.replace(state, ejection=measured), ())


def blind_burn(state: IcPlannerState, prior: EjectionPrior, now: float, config: IcPlannerConfig) -> tuple:
    """The blind acquisition's one burn (:func:`on_step`): a carrier tangential burn at the first grid epoch
    ``planning_margin`` after ``now`` that makes the mean along-track separation as large again ``blind_after``
    later as at the burn, under the nominal drag (seed 002 Eq. 2 and the secular model, affine in the burn: two
    propagations give it). With the drag's da decaying at a da_dot, that is a da = -a_da_dot H / 2 after the burn
    (H = ``blind_after``), so the separation dips by about 1.5 n a_da_dot H^2 / 8 and comes back: the pair neither
    drifts off to evaporation nor turns back on the carrier, for another outage as long, whatever the first OD finds.
    Quantized to ``dv_quantum`` and at most ``max_burn_dv``.

    Parameters
    ----------
    state, config
        As every rule takes them (module docstring).
    prior : EjectionPrior
        The ejection on record.
    now : float
        The decision's sim time [s].

    Returns
    -------
    tuple
        ``(burn, roe_at_burn, chief_at_burn)``: the :class:`~.common.PlannedBurn` (None when none is needed), the
        predicted dimensionless ROE and :class:`Chief` at its epoch; ValueError on a bad prior.
    """
    cfg = config.cfg
    od = prior.solution(now)
    roe0, chief, da_dot = start_state(state, od, now, config)
    t_burn = float(grid_epochs(now + cfg.planning_margin, now + cfg.planning_margin + cfg.window, chief,
                               cfg.grid_per_orbit, cfg.j2)[0])
    roe_b = state_at(roe0, chief.t0, (), t_burn, chief, j2=cfg.j2, da_dot=da_dot)
    chief_b = Chief(chief.a, chief.inc, float(chief.u_at(t_burn, cfg.j2)), t_burn)
    horizon = t_burn + config.blind_after

    def dl_at_horizon(dv_t):
        burns = [PlannedBurn.at(t_burn, chief_b.u0, (0.0, dv_t, 0.0), "carrier", "ic_acquisition").relative()]
        return float(state_at(roe_b, t_burn, burns, horizon, chief_b, j2=cfg.j2, da_dot=da_dot)[1])

    base, unit = dl_at_horizon(0.0), dl_at_horizon(1.0)
    dv_t = (float(roe_b[1]) - base) / (unit - base)
    dv_t = float(np.clip(np.round(dv_t / cfg.dv_quantum) * cfg.dv_quantum, -cfg.max_burn_dv, cfg.max_burn_dv))
    if dv_t == 0.0:
        return None, roe_b, chief_b
    return PlannedBurn.at(t_burn, chief_b.u0, (0.0, dv_t, 0.0), "carrier", "ic_acquisition"), roe_b, chief_b


def on_step(state: IcPlannerState, now: float, config: IcPlannerConfig) -> tuple:
    """A blind acquisition through a radar outage (issue 41 part 3): ``blind_after`` after the release without any
    OD solution (and no acquisition plan yet), the along-track separation is held from the ejection on record (the
    measured one where there is one, else the commanded one: :class:`EjectionPrior`) and the carrier burns executed
    since, by one tangential burn (:func:`blind_burn`): the pair neither evaporates nor turns back on the carrier
    before the first OD after the outage, which then plans the acquisition in a window of its own. (An acquisition
    planned to the ICs from this knowledge would aim the separation down to a_dl_min on a prediction whose drag and
    ejection errors grow to kilometres: tried, it took the pair inside the keep-out in 10 of 100 runs.)

    Parameters
    ----------
    state, config
        As every rule takes them (module docstring).
    now : float
        The sim time [s] of the step.

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    prior = state.ejection
    if (config.blind_after <= 0.0 or state.blind or prior is None or state.last_key is not None or state.plans
            or now < prior.t + config.blind_after
            or (state.separation_end is not None and now < state.separation_end)):
        return state, ()
    state = dataclasses.replace(state, blind=True)
    made, failed = guarded("blind acquisition rejected", "blind acquisition failed", values(state), blind_burn,
                           state, prior, now, config)
    if made is None:
        return state, failed
    burn, roe_b, chief_b = made
    a = chief_b.a
    text = (f"blind_acquisition: no OD {(now - prior.t) / 3600.0:.1f} h after the release: from the {prior.source} "
            f"ejection and the {len(state.executed)} carrier burn(s) on record, a dl = {roe_b[1] * a:.0f} m and a da "
            f"= {roe_b[0] * a:.1f} m at t = {chief_b.t0:.0f} s")
    extra = {**values(state), "contingency": "blind_acquisition", "epoch_s": f"{now:.1f}", "source": prior.source}
    if burn is None:
        return state, (status(WARN, text + ": the separation holds without a burn", extra, "warning",
                              part="contingency", stamp=now),)
    t_hold = chief_b.t0 + config.blind_after
    roe_hold = state_at(roe_b, chief_b.t0, [burn.relative()], t_hold, chief_b, j2=config.cfg.j2,
                        da_dot=prior.a_da_dot / a)
    publish = PublishPlan(now, (burn,), *aimed(prior.solution(now), roe_hold, t_hold, config), t_hold)
    state = dataclasses.replace(state, last_plan=publish, plan_in_force=(burn,), burn_epochs=(burn.epoch,),
                                plans=state.plans + 1)
    text += (f": a tangential burn of {burn.dv_rtn[1]:+.3f} m/s at t = {burn.epoch:.0f} s holds a dl until "
             f"t = {t_hold:.0f} s (predicted {roe_hold[1] * a:.0f} m); the first OD plans the acquisition")
    return state, (status(WARN, text, extra, "warning", part="contingency", stamp=now), publish)

def on_separation_plan(state: IcPlannerState, burn_epochs: Iterable[float], config: IcPlannerConfig) -> tuple:
    """The separation plan: the acquisition starts from an OD made after its last burn.

    Parameters
    ----------
    state, config
        As every rule takes them (module docstring).
    burn_epochs : iterable of float
        The separation plan's burn epochs [s] (none: no separation plan).

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    return dataclasses.replace(state, separation_end=max(burn_epochs, default=None)), ()


def on_own_plan(state: IcPlannerState, burns: Sequence[PlannedBurn], t_final: float, config: IcPlannerConfig) -> tuple:
    """The latched acquisition plan, read back: a restarted ic_planner continues it (a state with an IC epoch keeps
    its own).

    Parameters
    ----------
    state, config
        As every rule takes them (module docstring).
    burns : sequence of PlannedBurn
        The plan's burns.
    t_final : float
        Its IC epoch [s].

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    if state.t_final is not None or not burns or state.blind:  # the blind burn's plan fixes no IC epoch (on_step)
        return state, ()
    return dataclasses.replace(state, t_final=t_final, burn_epochs=tuple(b.epoch for b in burns),
                               plan_in_force=tuple(burns)), ()


def on_restart(state: IcPlannerState, config: IcPlannerConfig) -> tuple:
    """An ic_planner restarted with the recovered ``state``: the plan in force latched again as it was published
    (never one a re-plan or trim replaced); the latched OD and record then come again and are not newer or already
    on record (:func:`on_od`, :func:`on_executed`)."""
    text = (f"restarted with {state.plans} plan(s) decided: " + ("no plan in force" if state.last_plan is None else
            f"the plan in force ({len(state.last_plan.burns)} burn(s)) latched again"))
    return state, (*(() if state.last_plan is None else (state.last_plan,)), status(OK, text, values(state)))


def on_od(state: IcPlannerState, od: OdSolution, now: float, config: IcPlannerConfig) -> tuple:
    """A new OD solution: ignored unless newer than the last one and made after the separation plan; else
    :func:`decide`.

    Parameters
    ----------
    state, od, config
        As every rule takes them (module docstring).
    now : float
        The node's time [s].

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    key = (od.stamp, od.epoch)
    if state.last_key is not None and key <= state.last_key:
        return state, (Log("debug", f"OD solution {key} is not newer than {state.last_key}: ignored"),)
    state = dataclasses.replace(state, last_key=key)
    if state.separation_end is not None and state.separation_end >= od.epoch:
        text = (f"OD at t = {od.epoch:.1f} s not used: the separation plan flies until t = {state.separation_end:.1f}"
                " s; the acquisition starts from an OD made after it")
        return state, (status(OK, text, values(state)),)
    state = dataclasses.replace(state, last_od=od)
    state, actions, _ = decide(state, od, now, config)
    return state, actions


def on_executed(state: IcPlannerState, burn: PlannedBurn, config: IcPlannerConfig) -> tuple:
    """An executed maneuver on record: a carrier burn is flown (ERROR status for a malformed one); with
    ``replan_on_burn`` an acquisition burn may re-plan (:func:`after_burn`).

    Parameters
    ----------
    state, config
        As every rule takes them (module docstring).
    burn : PlannedBurn
        The executed maneuver as its record carries it.

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    if burn.spacecraft != "carrier":
        return state, ()
    try:
        flown = burn.relative()
    except ValueError as exc:
        return state, (status(ERROR, f"executed maneuver rejected: {exc}", values(state), None),)
    if any(round(b.epoch, 3) == round(flown.epoch, 3) for b in state.executed):
        return state, ()  # on record already (the latched record again, after a restart): decided then
    state = dataclasses.replace(state, executed=(*state.executed, flown))
    if not (config.replan_on_burn and burn.purpose == "ic_acquisition"):
        return state, ()
    result, actions = guarded("re-plan after a burn rejected", "re-plan after a burn failed", values(state),
                              after_burn, state, burn, config)
    return (state, actions) if result is None else result


def after_burn(state: IcPlannerState, burn: PlannedBurn, config: IcPlannerConfig) -> tuple:
    """An executed acquisition burn departing from its plan by more than half the trim lattice in a da (seed 002
    Eq. 2: a Delta da = 2 dvT / n), or the committed burn a departure's re-plan waited for: re-plan the rest from the
    last OD and the record, or re-trim once the final OD decided.

    Parameters
    ----------
    state, config
        As every rule takes them (module docstring).
    burn : PlannedBurn
        The executed carrier burn (purpose "ic_acquisition").

    Returns
    -------
    tuple
        ``(new state, actions)``; ValueError on a bad estimate (the caller guards it).
    """
    t, od = burn.epoch, state.last_od
    if od is None or state.plan_in_force is None or state.t_final is None or t >= state.t_final:
        return state, ()
    planned = next((p for p in state.plan_in_force if p.spacecraft == "carrier" and abs(p.epoch - t) < 1e-3), None)
    if planned is None:
        return state, ()
    departure = abs(float(a_da_change(burn.dv_rtn[1] - planned.dv_rtn[1], od.a)))
    departed = departure > 0.5 * drift_lattice(od.a, config.cfg.dv_quantum)
    if not (departed or state.replan_pending):
        return state, ()
    why = (f"burn at t = {t:.1f} s departed from its plan by {departure:.2f} m of a da" if departed else
           f"burn at t = {t:.1f} s flown, the committed burn that deferred an earlier departure's re-plan")
    text = f"{why}: {'re-trim' if state.final_decided else 're-plan'} from the OD at t = {od.epoch:.1f} s"
    actions = (status(OK, text, values(state)),)
    state = dataclasses.replace(state, replan_pending=False)
    if state.final_decided:
        state, more = final_trim(state, od, t, config, after_burn=True)
        return state, actions + more
    # a committed burn keeps the plan in force: its own execution record re-plans then
    state, more, deferred = decide(state, od, t, config)
    return dataclasses.replace(state, replan_pending=deferred), actions + more


def decide(state: IcPlannerState, od: OdSolution, now: float, config: IcPlannerConfig) -> tuple:
    """What an OD solution does: the final trim, a re-plan, or nothing (docs/run.md, "Decisions").

    Parameters
    ----------
    state, od, now, config
        As every rule takes them (module docstring).

    Returns
    -------
    tuple
        ``(new state, actions, deferred)``; ``deferred`` True when a committed burn of the plan in force kept it.
    """
    cfg = config.cfg
    arc = radar_arc(od, state.t_final, config) if state.t_final is not None else None
    final_band = state.t_final is not None and now < state.t_final < now + 2.0 * cfg.planning_margin
    if config.trim and (od.epoch >= arc[1] - PASS_SLACK if arc else final_band):
        if state.final_decided:  # once (a departing burn re-trims through after_burn)
            return state, (), False
        return (*final_trim(state, od, now, config), False)
    keep_arc = arc is None or max(od.epoch, now) + cfg.planning_margin <= arc[0]
    actions = ()
    if not keep_arc:
        missed, actions = guarded("OD estimate rejected", "acquisition check failed", values(state), plan_problems,
                                  state, od, now, config)
        if missed is None:
            return state, actions, False
        if not missed:
            text = (f"OD at t = {od.epoch:.1f} s not used: the plan in force meets the initial conditions by it, and "
                    f"its burns would fall in the final OD's radar arc [{arc[0]:.0f}, {arc[2]:.0f}] s (the final "
                    f"OD comes after the pass at t = {arc[1]:.0f} s)")
            return state, (status(OK, text, values(state)),), False
        actions = (Log("info", f"OD at t = {od.epoch:.1f} s: the plan in force would miss the initial conditions "
                               f"({'; '.join(missed)}): re-planned within the final OD's radar arc"),)
    sigma, known = drift_sigma(od, state.t_final, config), plan_knowledge(state, od, config)
    if sigma is not None and known is not None and sigma > known:
        text = (f"OD at t = {od.epoch:.1f} s not used: its a da at the IC epoch is known to {sigma:.2f} m (1-sigma), "
                f"the plan in force's to {known:.2f} m")
        return state, actions + (status(OK, text, values(state)),), False
    blocking = committed_burn(state, od.epoch, now, cfg.planning_margin)
    if blocking is not None:
        text = (f"OD at t = {od.epoch:.1f} s not used: the burn at t = {blocking:.1f} s of the plan in force is "
                f"{'executed after the OD epoch' if blocking < now else 'committed (within planning_margin)'}")
        return state, actions + (status(WARN, text, values(state), "warning"),), True
    made, failed = guarded("OD estimate rejected", "acquisition planning failed", values(state), make_plan, state,
                           od, now, config, keep_arc=keep_arc)
    if made is None:
        return state, actions + failed, False
    publish, plan = made
    if not publish.burns:  # the ICs are met without a burn: nothing to fly (an empty plan is no plan)
        text = (f"OD at t = {od.epoch:.1f} s: the initial conditions are met at t = {plan.t_final:.1f} s without a "
                "further burn; the plan in force stays")
        return state, actions + (status(OK, text, values(state)),), False
    summary = plan.summary()
    state = dataclasses.replace(
        state, replan_pending=False, last_plan=publish, plan_in_force=publish.burns,
        plan_sigma=drift_sigma(od, plan.t_final, config),
        plan_od_epoch=od.epoch, burn_epochs=tuple(float(t) for t in plan.epochs),
        t_final=float(plan.t_final) if state.t_final is None else state.t_final, plans=state.plans + 1,
        summary=tuple((k, _shown(summary[k])) for k in summary if k in SUMMARY_KEYS))
    log = Log("info", f"IC acquisition planned from the OD at t = {od.epoch:.1f} s: {plan.n_burns} burns, total dv = "
                      f"{plan.total_dv:.3f} m/s (LP {plan.lp_dv:.4f}), ICs at t = {plan.t_final:.1f} s, "
                      f"a dl_F = {plan.final_roe[1] * plan.a:.0f} m, min R-N = {plan.min_rn:.0f} m")
    return state, actions + (publish, log, status(OK, "acquisition plan published", values(state), None)), False


def final_trim(state: IcPlannerState, od: OdSolution, now: float, config: IcPlannerConfig, *,
               after_burn: bool = False) -> tuple:
    """The final OD's drift trim from the first newer solution near t_F whose flown burns are all on record
    (:func:`~roe_sep.core.acquisition.trim.plan_trim`).

    Parameters
    ----------
    state, od, now, config
        As every rule takes them (module docstring).
    after_burn : bool
        Again after a departing burn: a plan is published only for a trim.

    Returns
    -------
    tuple
        ``(new state, actions)``.
    """
    if state.t_final is not None and now >= state.t_final:
        text = (f"OD at t = {od.epoch:.1f} s not used: it arrives after the IC epoch t = {state.t_final:.1f} s "
                "without a final OD trim decision before it")
        state = dataclasses.replace(state, final_decided=True)
        return state, (status(WARN, text, values(state), "warning"),)
    flown = {round(b.epoch, 3) for b in state.executed}
    if any(od.epoch <= t < now and round(t, 3) not in flown for t in state.burn_epochs or ()):
        return state, ()  # a burn flown after the OD epoch is not on record yet: the next solution decides
    kept = tuple(b for b in state.plan_in_force or () if b.epoch >= now and round(b.epoch, 3) not in flown)
    decision, actions = guarded("final OD rejected", "drift trim failed", values(state), trim_decision, state, od,
                                now, config, kept)
    if decision is None:
        return state, actions
    state = dataclasses.replace(state, final_decided=True)
    if after_burn and not decision.trim:
        return state, ()
    state = dataclasses.replace(state, summary=_updated(state.summary, {f"final_{k}": _shown(v) for k, v in
                                                                         decision.summary().items()}))
    text = (f"final OD at t = {od.epoch:.1f} s: predicted a da at the IC epoch {decision.predicted_a_da:+.2f} m "
            f"(1-sigma {decision.sigma_a_da:.2f} m, trim threshold {decision.threshold:.2f} m): ")
    if not decision.trim:
        return state, (status(OK, text + "no trim", values(state)),)
    burns = (*kept, PlannedBurn.at(decision.epoch, float(wrap_angle(decision.u)), (0.0, decision.dv_t, 0.0),
                                   "carrier", "ic_acquisition"))
    publish = PublishPlan(now, burns, *aimed(od, decision.final_roe, decision.t_final, config), decision.t_final)
    state = dataclasses.replace(state, plan_in_force=burns, t_final=decision.t_final, last_plan=publish,
                                burn_epochs=tuple(b.epoch for b in burns), plans=state.plans + 1)
    text += f"trim of {decision.dv_t:+.3f} m/s at t = {decision.epoch:.1f} s, IC epoch t = {decision.t_final:.1f} s"
    if decision.problems:  # missed anyway: the trim nulls the drift to hold the formation
        text += f"; the initial conditions are missed even so ({'; '.join(decision.problems)}): drift nulled"
        return state, (publish, status(WARN, text, values(state), "warning"))
    return state, (publish, status(OK, text, values(state)))


def _updated(pairs: tuple, new: dict) -> tuple:
    """``(key, value)`` pairs updated as a dict would be (order kept, new keys last)."""
    merged = dict(pairs)
    merged.update(new)
    return tuple(merged.items())


def committed_burn(state: IcPlannerState, t_od: float, now: float, planning_margin: float) -> float | None:
    """A burn epoch [s] of the plan in force that a re-plan must not touch: due within ``planning_margin`` from
    ``now``, or executed after the OD epoch without its record yet.

    Parameters
    ----------
    state
        As every rule takes them (module docstring).
    t_od, now : float
        The OD's epoch and the decision time [s].
    planning_margin : float
        The least time [s] between a decision and a burn it plans.

    Returns
    -------
    float or None
        The burn's epoch [s]; t_F when the acquisition is (nearly) complete; None when re-planning is free.
    """
    flown = {round(b.epoch, 3) for b in state.executed}
    for t in state.burn_epochs or ():
        if round(t, 3) in flown:  # flown (a re-plan after a burn starts at that burn's epoch)
            continue
        if now <= t < now + planning_margin or t_od <= t < now:
            return t
    if state.t_final is not None and now + 2.0 * planning_margin > state.t_final:
        return state.t_final  # no new acquisition from here
    return None


def start_state(state: IcPlannerState, od: OdSolution, now: float, config: IcPlannerConfig) -> tuple:
    """The best knowledge at max(OD epoch, now, the latest burn on record): the estimate plus every carrier burn
    flown since its epoch.

    Parameters
    ----------
    state, od, now, config
        As every rule takes them (module docstring).

    Returns
    -------
    tuple
        ``(roe, chief, da_dot)``: the dimensionless ROE (6,), the :class:`Chief` at that time and the drag
        [1/s]; ValueError on a bad estimate.
    """
    a, inc, j2 = od.a, od.kep[2], config.cfg.j2
    if not (math.isfinite(a) and a > 6.4e6):
        raise ValueError(f"chief semi-major axis {a} m is not a valid low Earth orbit")
    od_chief = Chief(a=a, inc=inc, u0=od.u, t0=od.epoch)
    roe_od = np.array(od.roe, dtype=float)
    da_dot = od.a_da_dot / a
    check_inputs(roe_od, od_chief, da_dot)
    # every burn on record, also one flown after ``now`` (a solution stamped before a burn it arrives after)
    t_start = max(od.epoch, now, *(b.epoch for b in state.executed))
    flown = [b for b in state.executed if od.epoch < b.epoch <= t_start]
    roe0 = state_at(roe_od, od.epoch, flown, t_start, od_chief, j2=j2, da_dot=da_dot)
    return roe0, Chief(a=a, inc=inc, u0=float(od_chief.u_at(t_start, j2)), t0=t_start), da_dot


def _to_fly(state: IcPlannerState, kept, t0: float) -> tuple:
    """(relative impulses of the plan's ``kept`` burns, those plus the burns flown after ``t0``)."""
    to_fly = [b.relative() for b in kept]
    return to_fly, to_fly + [b for b in state.executed if b.epoch > t0]


def plan_problems(state: IcPlannerState, od: OdSolution, now: float, config: IcPlannerConfig) -> list:
    """The initial conditions that the plan in force misses at t_F by this OD (:func:`trim_problems`, and the drift
    beyond ``ic_drift_tolerance``: a smaller one is the final trim's).

    Parameters
    ----------
    state, od, now, config
        As every rule takes them (module docstring).

    Returns
    -------
    list of str
        One line a missed condition; [] when the plan meets them all. ValueError on a bad estimate.
    """
    roe0, chief, da_dot = start_state(state, od, now, config)
    flown = {round(b.epoch, 3) for b in state.executed}
    kept = [b for b in state.plan_in_force or () if b.epoch >= chief.t0 and round(b.epoch, 3) not in flown]
    final = state_at(roe0, chief.t0, _to_fly(state, kept, chief.t0)[1], max(state.t_final, chief.t0), chief,
                     j2=config.cfg.j2, da_dot=da_dot)
    problems = trim_problems(final, chief.a, config.cfg, roe0[1] > 0)
    a_da = float(final[0]) * chief.a
    if abs(a_da) > config.ic_drift_tolerance:  # no waiting for a final OD that may not come
        problems.append(f"|a da_F| = {abs(a_da):.1f} m beyond ic_drift_tolerance = {config.ic_drift_tolerance:g} m")
    return problems


def trim_decision(state: IcPlannerState, od: OdSolution, now: float, config: IcPlannerConfig,
                  kept: Sequence[PlannedBurn]) -> TrimDecision:
    """:func:`plan_trim` from the OD with the burns of the plan in force still to fly and the burns flown after the
    decision time.

    Parameters
    ----------
    state, od, now, config
        As every rule takes them (module docstring).
    kept : sequence of PlannedBurn
        The burns of the plan in force still to fly.

    Returns
    -------
    TrimDecision
        The decision; :class:`AcquisitionInfeasible` (a ValueError) when the trim would break an initial condition.
    """
    roe0, chief, da_dot = start_state(state, od, now, config)
    to_fly, burns = _to_fly(state, kept, chief.t0)
    return plan_trim(roe0, chief, da_dot, burns, state.t_final, t_earliest=now + config.cfg.planning_margin,
                     sigma_a_da=od.sigma_a_da, sigma_rate=od.a_da_dot_sigma, tolerance=config.ic_drift_tolerance,
                     cfg=config.cfg, t_od=od.epoch,
                     sigma_burns=burns_drift_sigma([b.dv_rel[1] for b in to_fly], chief.a, config.burn_sigma))


def make_plan(state: IcPlannerState, od: OdSolution, now: float, config: IcPlannerConfig, *,
              keep_arc: bool = True) -> tuple[PublishPlan, AcquisitionPlan]:
    """The acquisition plan of one OD solution (:func:`plan_acquisition`, the e/i planned with the OD's uncertainty
    as margin, ``ei_margin_sigmas``; without that margin when it has no solution).

    Parameters
    ----------
    state, od, now, config
        As every rule takes them (module docstring).
    keep_arc : bool
        No burn in the final OD's radar arc (:func:`radar_arc`).

    Returns
    -------
    tuple
        ``(PublishPlan, core plan)``; ValueError on a bad estimate or no solution.
    """
    roe0, chief, da_dot = start_state(state, od, now, config)
    t_start = chief.t0
    # corrections of an acquisition in progress aim at its IC epoch; a first plan opens a new window
    cfg = config.cfg if state.t_final is None else dataclasses.replace(config.cfg, window=state.t_final - t_start)
    t_f = state.t_final
    if t_f is None:
        t_f = float(grid_epochs(t_start, t_start + cfg.window, chief, cfg.grid_per_orbit, cfg.j2)[-1])
    arc = radar_arc(od, t_f, config) if keep_arc else None
    kwargs = dict(t_earliest=t_start + config.cfg.planning_margin, no_burns=[(arc[0], arc[2])] if arc else ())
    margin = ei_margin(np.array(od.roe, dtype=float) * chief.a, od.covariance, config.ei_margin_sigmas)
    try:
        plan = plan_acquisition(roe0, chief, da_dot, dataclasses.replace(cfg, min_ei=cfg.min_ei + margin), **kwargs)
    except AcquisitionInfeasible:
        if margin == 0.0:
            raise
        plan = plan_acquisition(roe0, chief, da_dot, cfg, **kwargs)
    burns = tuple(PlannedBurn.at(float(t), float(wrap_angle(u)), dv, "carrier", "ic_acquisition")
                  for t, u, dv in zip(plan.epochs, plan.u, plan.dv_carrier))
    return PublishPlan(t_start, burns, *aimed(od, plan.final_roe, plan.t_final, config), plan.t_final), plan


def aimed(od: OdSolution, final_roe: ArrayLike, t_final: float, config: IcPlannerConfig) -> tuple:
    """What a plan aims at: its final ROE with the OD's chief propagated to the IC epoch.

    Parameters
    ----------
    od, config
        As every rule takes them (module docstring).
    final_roe : array_like, shape (6,)
        The plan's dimensionless ROE at ``t_final``.
    t_final : float
        The IC epoch [s].

    Returns
    -------
    tuple
        ``(roe, kep)``: the ROE and the chief's mean elements ``[a, e, i, raan, argp, M]`` (angles wrapped), as
        floats.
    """
    kep = propagate_chief(np.array(od.kep, dtype=float), t_final - od.epoch, config.cfg.j2)
    kep[3:] = wrap_angle(kep[3:])
    return tuple(float(x) for x in final_roe), tuple(float(x) for x in kep)


def drift_sigma(od: OdSolution, t_final: float | None, config: IcPlannerConfig) -> float | None:
    """The 1-sigma of a da at the IC epoch predicted from the OD (:func:`predicted_drift_sigma`).

    Parameters
    ----------
    od, config
        As every rule takes them (module docstring).
    t_final : float or None
        The IC epoch [s].

    Returns
    -------
    float or None
        The 1-sigma [m]; None without ``trim`` or IC epoch.
    """
    if not config.trim or t_final is None:
        return None
    return predicted_drift_sigma(od.sigma_a_da, od.a_da_dot_sigma, t_final - od.epoch)


def plan_knowledge(state: IcPlannerState, od: OdSolution, config: IcPlannerConfig) -> float | None:
    """The 1-sigma of a da at t_F as the plan in force knows it: its OD's, with the execution errors of the burns
    flown since (``burn_sigma`` of 2 |dvT| / n each, seed 002 Eq. 2).

    Parameters
    ----------
    state, od, config
        As every rule takes them (module docstring).

    Returns
    -------
    float or None
        The 1-sigma [m]; None without a plan (or ``trim``).
    """
    if state.plan_sigma is None:
        return None
    flown = [b.dv_rel[1] for b in state.executed if b.epoch > state.plan_od_epoch]
    return math.hypot(state.plan_sigma, burns_drift_sigma(flown, od.a, config.burn_sigma))


def radar_arc(od: OdSolution, t_final: float, config: IcPlannerConfig) -> tuple | None:
    """The final OD's burn-free radar arc for the IC epoch (:func:`final_od_arc` of the predicted TIRA passes of
    the OD's chief).

    Parameters
    ----------
    od, config
        As every rule takes them (module docstring).
    t_final : float
        The IC epoch [s].

    Returns
    -------
    tuple or None
        ``(start, last_rise, end)`` [s]; None with ``trim`` or ``final_od_arc`` off, or without an arc.
    """
    if not (config.trim and config.final_od_arc):
        return None
    return _arc(tuple(od.kep), od.epoch, t_final, config.final_od_arc, config.jd0, j2=config.cfg.j2)


@functools.lru_cache(maxsize=16)
def _arc(kep: tuple, t_od: float, t_final: float, min_arc: float, jd0: float, *, j2: bool) -> tuple | None:
    """:func:`radar_arc`, memoised: one OD and IC epoch give one arc, asked by every rule and re-plan."""
    passes = radar_passes(np.array(kep, dtype=float), t_od, t_final - 2.0 * SECONDS_PER_DAY,
                          t_final + 3.0 * CLUSTER_GAP, jd0, j2=j2)
    return final_od_arc(passes, t_final, min_arc)
