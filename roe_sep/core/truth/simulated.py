"""The simulator's truth over a run, without ROS: the dispersed truth model of a run seed, its timeline (truth samples
every ``truth_period``, an hourly report, the minimum-distance tracking) and the closest approach after the
departure. The ``sim`` node (:mod:`roe_sep.nodes.sim`) publishes what this computes.
"""

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..constants import ARCSEC
from ..od.pose import PoseCamera, camera_axes, in_view, measure_poses, pose_covariance
from ..relmotion.dynamics import arg_latitude_rate, drag_da_dot
from ..safety.ejection_check import camera_bearing
from .contingency import SIM_SIDE, ContingencyConfig, TruthContingency
from .secular import ExecutionErrors, TruthModel, chief_from_u

if TYPE_CHECKING:  # for the annotations only
    from ..config import Scenario
    from ..separation.double_impulse import DoubleImpulseDesign
    from ..separation.multi_impulse import MultiImpulseDesign
    from .nonlinear import NonlinearTruth

EJECTION_TIMING_STREAM = 2  # the ejection delay's stream of a run seed (graph.RADAR_STREAM = 1: the radar noise)
CAMERA_STREAM = 4  # the carrier camera's bearing noise (3: the contingency draws)
POSE_STREAM = 5  # the ejection footage's pose noise
STATUS_PERIOD = 3600.0  # s of sim time between the simulator's routine reports


def camera_rng(seed: int) -> np.random.Generator:
    """The carrier camera's noise generator of a run ``seed``: ``SeedSequence([seed, CAMERA_STREAM])``, a stream of
    its own, so the camera changes no other draw of the run (:func:`dispersed_truth`)."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), CAMERA_STREAM]))


def pose_rng(seed: int) -> np.random.Generator:
    """The ejection footage's noise generator of a run ``seed``: ``SeedSequence([seed, POSE_STREAM])``, a stream
    of its own like :func:`camera_rng`."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), POSE_STREAM]))


@dataclass
class Dispersed:
    """What a run seed draws: the truth model (with the dispersed differential drag), the execution errors of
    every burn (seed 002 Eq. 22) and the delay of the release mechanism after the commanded ejection epoch."""

    model: object  # TruthModel or NonlinearTruth
    errors: ExecutionErrors
    ejection_delay: float  # s
    da_dot: float  # 1/s, the true differential drag
    configured: dict  # the distributions drawn from (sigmas, the delay's upper end), for the record of the run
    drag_factor: float = 1.0  # the drawn factor of the differential ballistic coefficient
    contingency: TruthContingency | None = None  # the run's contingency on the simulator's side

    def applied(self) -> dict:
        """What the run drew, as the campaign checks it against :attr:`configured` (Kolmogorov-Smirnov): the drag
        factor, the ejection delay [s] and each burn's (spacecraft, magnitude factor, attitude errors [rad])."""
        return {"drag_factor": self.drag_factor, "ejection_delay_s": self.ejection_delay,
                "configured": self.configured, "burns": self.errors.applied}


def dispersed_truth(scenario: "Scenario", carrier: "DoubleImpulseDesign | MultiImpulseDesign", raan: float, u0: float,
                    seed: int, *, disperse: bool, dynamics: str, j2: bool, ejection_delay_max: float,
                    contingency: ContingencyConfig | None = None) -> Dispersed:
    """The run of ``seed``. The draws are those of ``numpy.random.default_rng(seed)`` in a fixed order (ballistic
    factor, then the execution errors), the ejection delay and the contingency each from its own stream of the
    seed, so each dispersion keeps its draws whatever the others do (and a contingency changes nothing else).

    Parameters
    ----------
    scenario : Scenario
        The scenario (:func:`roe_sep.core.config.load_scenario`): its dispersions, drag and execution errors.
    carrier : DoubleImpulseDesign or MultiImpulseDesign
        The scenario's separation design: the carrier's ``a`` [m] and ``inc`` [rad].
    raan, u0 : float
        The carrier's right ascension of the ascending node and mean argument of latitude [rad] at sim time 0.
    seed, disperse : int, bool
        The run seed; False: no drag uncertainty, no execution errors, no ejection delay.
    dynamics : str
        'secular' (:class:`~.secular.TruthModel`) or 'nonlinear' (:class:`~.nonlinear.NonlinearTruth`).
    j2 : bool
        J2 in the secular truth; the nonlinear one has the zonals J2-J4 whatever ``j2`` says.
    ejection_delay_max : float
        The upper end [s] of the uniform delay of the release mechanism after the commanded ejection epoch.
    contingency : ContingencyConfig, optional
        The run's contingency (:func:`~.contingency.resolve`); only the simulator's (:data:`~.contingency.SIM_SIDE`)
        act here (a storm via the model's ``storm``), the radar's are ignored. Applied whether or not ``disperse``.

    Returns
    -------
    Dispersed
        The truth model, the execution errors, the ejection delay [s], the true differential drag [1/s] and the
        drawn contingency (None without one).
    """
    sep, mc = scenario.separation, scenario.monte_carlo
    a, inc = carrier.a, carrier.inc
    rng = np.random.default_rng(seed)
    db_factor = rng.normal(1.0, mc.ballistic_sigma) if disperse else 1.0
    da_dot = float(drag_da_dot(mc.delta_b * db_factor, mc.density, a)) if mc.drag else 0.0
    chief0 = chief_from_u(a, inc, raan, u0)
    if dynamics == "nonlinear":
        from .nonlinear import Atmosphere, NonlinearTruth

        b_c = mc.carrier.ballistic if mc.drag else 0.0
        b_d = b_c + mc.delta_b * db_factor if mc.drag else 0.0
        model = NonlinearTruth(chief0, 0.0, b_c, b_d, Atmosphere.normalised(mc.density, chief0), da_dot=da_dot)
    else:
        model = TruthModel(chief0, 0.0, da_dot, j2)
    timing = np.random.default_rng(np.random.SeedSequence([int(seed), EJECTION_TIMING_STREAM]))
    ejection_delay = float(timing.uniform(0.0, ejection_delay_max)) if disperse else 0.0
    errors = ExecutionErrors(rng, sep.spl_sigma if disperse else 0.0, sep.thruster_sigma if disperse else 0.0,
                             mc.attitude_sigma_arcsec * ARCSEC if disperse else 0.0)
    configured = {"disperse": bool(disperse), "ballistic_sigma": mc.ballistic_sigma,
                  "ejection_delay_max_s": float(ejection_delay_max),
                  **{k: getattr(errors, k) for k in ("spl_sigma", "thruster_sigma", "attitude_sigma")}}
    drawn = None
    if contingency is not None and contingency.name in SIM_SIDE:
        drawn = TruthContingency(contingency, seed, 2.0 * math.pi / float(arg_latitude_rate(a, inc, True)))
        model.storm = drawn.storm  # density_storm: the truth's drag (both spacecraft) in its window; else None
    return Dispersed(model, errors, ejection_delay, da_dot, configured, float(db_factor), drawn)


class ClosestApproach:
    """Closest approach after the departure: the smallest local minimum of |r| once it exceeded ``departure`` [m]
    (the receding start of the separation itself is no approach), fed with the distances of consecutive steps."""

    def __init__(self, departure):
        self.departure = departure
        self.departed = False
        self.min_dist = (math.inf, math.nan)  # (m, s)
        self.tail = (np.empty(0), np.empty(0))  # last samples of the previous step (local minima across steps)

    def update(self, times: np.ndarray, dist: np.ndarray) -> None:
        """Feed one step's ``times`` ``(T,)`` [s], increasing, and distances ``dist`` ``(T,)`` [m] (a step starting at
        the previous one's end repeats that sample)."""
        if self.tail[0].size and times.size and times[0] <= self.tail[0][-1]:  # consecutive steps share an end
            times, dist = times[1:], dist[1:]
        times = np.concatenate([self.tail[0], times])
        dist = np.concatenate([self.tail[1], dist])
        if not self.departed:
            out = np.nonzero(dist >= self.departure)[0]
            if out.size == 0:
                self.tail = (times[-2:], dist[-2:])
                return
            self.departed = True
            times, dist = times[out[0]:], dist[out[0]:]
        inner = np.nonzero((dist[1:-1] <= dist[:-2]) & (dist[1:-1] < dist[2:]))[0] + 1
        if inner.size:
            k = inner[np.argmin(dist[inner])]
            if dist[k] < self.min_dist[0]:
                self.min_dist = (float(dist[k]), float(times[k]))
        self.tail = (times[-2:], dist[-2:])


class Camera:
    """The carrier camera (the simulator's sensor): from the release on (:meth:`release`, the executed ejection's
    epoch) for ``duration`` [s], a bearing of the picosatellite every ``period`` [s] (0: no camera), the truth's
    relative position turned into a noisy unit line of sight in the carrier's RTN frame
    (:func:`~roe_sep.core.safety.ejection_check.camera_bearing`, ``sigma`` [rad] per axis, the generator ``rng``,
    :func:`camera_rng`), handed to ``on_bearings(epochs, lines_of_sight)``."""

    def __init__(self, period: float, sigma: float, duration: float, rng: np.random.Generator,
                 on_bearings: Callable[[list, np.ndarray], None]) -> None:
        self.period, self.sigma, self.duration, self.rng = period, sigma, duration, rng
        self.on_bearings = on_bearings
        self.start = None  # s, the release
        self.next = math.inf

    def release(self, t: float) -> None:
        """The picosatellite left at ``t`` [s]: bearings from ``t + period`` on (a second release is ignored)."""
        if self.start is None and self.period > 0.0:
            self.start = float(t)
            self.next = self.start + self.period

    def observe(self, model: "TruthModel | NonlinearTruth", t_from: float, t_to: float) -> None:
        """The bearings due in (``t_from``, ``t_to``] of ``model``'s truth, handed to ``on_bearings``.

        Parameters
        ----------
        model : TruthModel or NonlinearTruth
            The truth (its ``rtn_at``: the relative position [m] in the carrier's RTN frame).
        t_from, t_to : float
            The window [s] of sim time.

        Returns
        -------
        None
        """
        if self.start is None:
            return
        end = min(float(t_to), self.start + self.duration)
        epochs = []
        while self.next <= end + 1e-9:
            if self.next > t_from:
                epochs.append(self.next)
            self.next += self.period
        if epochs:
            pos = model.rtn_at(np.asarray(epochs, dtype=float))[0]
            self.on_bearings(epochs, camera_bearing(pos, self.sigma, self.rng))


class PoseFootage:
    """The ejection footage (the simulator's sensor, seed 001 Sec. 2.1 req. 3 and 2.3): from the release
    (:meth:`release`, with the commanded ejection's direction as the boresight) for ``window`` [s] (the ejection
    contact's footage), a pose every ``cam.frame_period`` on the sim-time grid while the picosatellite is in view
    and lit (:func:`~roe_sep.core.od.pose.in_view`; ``lit(epochs)``: the carrier's shadow test), the truth's
    relative position with the pose noise (:func:`~roe_sep.core.od.pose.measure_poses`, generator ``rng``,
    :func:`pose_rng`) and its covariance handed to ``on_poses(epochs, positions, covariances)``."""

    def __init__(self, cam: "PoseCamera", window: float, rng: np.random.Generator,
                 lit: Callable[[np.ndarray], np.ndarray], on_poses: Callable) -> None:
        self.cam, self.window, self.rng, self.lit, self.on_poses = cam, window, rng, lit, on_poses
        self.start = None  # s, the release
        self.axes = None
        self.next = math.inf

    def release(self, t: float, boresight_rtn: Sequence[float]) -> None:
        """The picosatellite left at ``t`` [s], the camera looking along ``boresight_rtn`` (a second release, a
        zero window or a zero boresight: ignored)."""
        if self.start is None and self.window > 0.0 and np.linalg.norm(boresight_rtn) > 0.0:
            self.start = float(t)
            self.axes = camera_axes(boresight_rtn)
            self.next = math.floor(self.start / self.cam.frame_period + 1.0) * self.cam.frame_period

    def observe(self, model: "TruthModel | NonlinearTruth", t_from: float, t_to: float) -> None:
        """The poses due in (``t_from``, ``t_to``] of ``model``'s truth, handed to ``on_poses``.

        Parameters
        ----------
        model : TruthModel or NonlinearTruth
            The truth (its ``rtn_at``: the relative position [m] in the carrier's RTN frame).
        t_from, t_to : float
            The window [s] of sim time.

        Returns
        -------
        None
        """
        if self.start is None:
            return
        end = min(float(t_to), self.start + self.window)
        epochs = []
        while self.next <= end + 1e-9:
            if self.next > t_from:
                epochs.append(self.next)
            self.next += self.cam.frame_period
        if not epochs:
            return
        t = np.asarray(epochs, dtype=float)
        pos = model.rtn_at(t)[0]
        keep = in_view(pos, self.cam, self.axes) & self.lit(t)
        if np.any(keep):
            measured = measure_poses(pos[keep], self.cam, self.axes, self.rng)
            self.on_poses(t[keep].tolist(), measured, pose_covariance(pos[keep], self.cam, self.axes))


class SimulatedTruth:
    """The truth's timeline: :meth:`advance` moves ``model`` to a sim time, hands the truth samples of every
    ``truth_period`` epoch on the way to ``on_samples(epochs, (kep, roe, (pos, vel)))``, tracks the closest approach
    on a ``distance_step`` grid and calls ``on_hour()`` at every full hour of sim time at its own epoch, so that every
    output is the same whatever the step size.

    A model with a dense output (:class:`~.nonlinear.NonlinearTruth`: ``integrated_to``, ``revision``) has the
    samples of every epoch up to the end of its integrated span evaluated in one vectorised pass when the first of
    them is due (an hour of samples, not a step's), each step taking its own from them; a burn (a new ``revision``)
    drops those after it. Every sample is the value of its own epoch, whatever the pass it was evaluated in (the
    evaluation is element-wise), so the samples are those of a pass per step to the bit."""

    def __init__(self, model, truth_period, distance_step, departure, on_samples, *, on_hour):
        self.model = model
        self.truth_period, self.distance_step = truth_period, distance_step
        self.closest = ClosestApproach(departure)
        self.on_samples, self.on_hour = on_samples, on_hour
        self.t = 0.0
        self.next_truth = 0.0
        self.next_status = STATUS_PERIOD
        self.camera = None  # a Camera observing on the way (the simulator's)
        self.footage = None  # a PoseFootage observing on the way (the simulator's)
        self._ahead = None  # (model revision, epochs, their samples, index of the next step's first epoch)

    def advance(self, t_to: float) -> None:
        """Move the truth to ``t_to`` [s]."""
        while self.next_status <= t_to:
            self._advance_to(self.next_status)
            self.next_status += STATUS_PERIOD
            self.on_hour()
        self._advance_to(t_to)

    def _advance_to(self, t_to):
        if t_to <= self.t:
            return
        if self.model.separated:
            self.closest.update(*self.model.distances(self.t, t_to, self.distance_step))
        epochs = []
        while self.next_truth <= t_to:
            epochs.append(self.next_truth)
            self.next_truth += self.truth_period
        if epochs:
            self.on_samples(epochs, self._step_samples(epochs))
        if self.camera is not None:
            self.camera.observe(self.model, self.t, t_to)
        if self.footage is not None:
            self.footage.observe(self.model, self.t, t_to)
        self.t = t_to

    def publish(self, epochs: Sequence[float]) -> None:
        """The truth samples at each of ``epochs`` [s] (evaluated in one vectorized pass) to ``on_samples``."""
        self.on_samples(epochs, self.model.samples(np.asarray(epochs, dtype=float)))

    def _step_samples(self, epochs: list) -> tuple:
        """The samples of a step's truth ``epochs`` (the next ones of the grid): from the pass over the epochs up to
        the end of the model's integrated span (see the class), evaluated again when the step's are not in it."""
        model = self.model
        if not hasattr(model, "integrated_to"):
            return model.samples(np.asarray(epochs, dtype=float))
        n = len(epochs)
        if self._ahead is not None:
            revision, grid, samples, i = self._ahead
            if revision == model.revision and grid[i:i + n] == epochs:
                self._ahead = (revision, grid, samples, i + n)
                kep, roe, (pos, vel) = samples
                return kep[i:i + n], roe[i:i + n], (pos[i:i + n], vel[i:i + n])
        end = model.integrated_to(epochs[-1])
        grid = list(epochs)
        t = self.next_truth  # the grid goes on as _advance_to continues it
        while t <= end:
            grid.append(t)
            t += self.truth_period
        samples = model.samples(np.asarray(grid, dtype=float))
        kep, roe, (pos, vel) = samples
        for a in (kep, roe, pos, vel):  # the steps get views of them
            a.flags.writeable = False
        self._ahead = (model.revision, grid, samples, n)
        return kep[:n], roe[:n], (pos[:n], vel[:n])
