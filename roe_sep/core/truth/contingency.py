"""Contingencies as scenario inputs: a weak ejection, a late or missed drift-stop, lost radar passes, an
underperforming carrier burn, a radar range bias -- injected where they happen in flight, by the simulator (truth and
burn execution) and by the radar (measurements), never by the planners, which must find out as they would in flight.

One contingency per run, from the scenario's ``contingency:`` block (:func:`contingency_from_dict`, validated with
the key named in every error) or ``--contingency NAME`` (the node parameter ``contingency`` of ``sim`` and
``radar_od``; :func:`resolve`). Its parameters are a number (fixed) or ``[lo, hi]`` (a uniform draw per run seed).
The draws come from their own stream of the seed (:data:`CONTINGENCY_STREAM`, as the ejection delay has its own), so
a run without a contingency draws exactly what it drew before, and a run with one keeps every other dispersion of its
seed (the same SPL, thruster and drag draws): the run differs from the nominal one by the contingency alone.

The contingencies (docs/contingencies.md; :data:`SPECS`: parameters and defaults):

* ``spl_weak``: the SPL delivers a fraction f1 (``spl_fraction``) of its executed impulse, at least ``residual_dv``
  (the tail the design's Monte Carlo, f1 ~ N(1, 0.1), seed 002 Eq. 22, does not cover).
* ``drift_stop_delayed`` / ``drift_stop_missed``: the first drift-stop commanded (re-published for the same epoch
  too) executes ``delay_orbits`` whole orbits late (seed 002 Table 1 safety #4) / never (seed 000 Sec. IV); a
  replacement commanded for another epoch flies.
* ``burn_underperformance``: the ``burn``-th executed carrier burn at a ``magnitude`` fraction, or (``mode:
  pointing``) turned by ``pointing_deg`` about an axis normal to it at a uniform azimuth.
* ``radar_pass_missed``: the first ``passes`` radar passes lost (seed 001 Sec. 5), or an ``outage`` [s] from the
  first pass; ``radar_bias``: a range bias ``bias_m`` at one ``station``.
* ``ejection_pointing``: the SPL's impulse turned by ``angle_deg`` about the orbit normal (:func:`rotate_about_normal`).
* ``carrier_safe_mode``: no carrier burn for ``hours`` from ``start_h`` after the executed ejection: a burn due then
  is lost (:meth:`TruthContingency.dropped`); ``drift_stop_overperformance``: the first executed drift-stop at a
  ``magnitude`` > 1 of its magnitude.
* ``density_storm``: the truth's density times ``factor`` for ``hours`` from ``start_h`` after the executed ejection,
  for both spacecraft (:class:`DensityStorm`, applied by the truth models).
"""

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ...checks import check_number
from ...errors import ConfigError, show

CONTINGENCY_STREAM = 3  # the contingency's stream of a run seed (2: the ejection delay, radar_od's seed: stream 1)
NONE = "none"  # the contingency parameter's value for "no contingency, whatever the scenario says"


@dataclass(frozen=True)
class Spec:
    """One parameter of a contingency: ``kind`` 'range' (a number or [lo, hi] within [lo, hi] of the spec), 'irange'
    (an integer or [lo, hi] of integers), 'number', 'choice' (one of ``choices``) or 'string'."""

    kind: str
    default: object
    lo: float | None = None
    hi: float | None = None
    unit: str = ""
    choices: tuple = ()


SPECS = {
    "spl_weak": {"spl_fraction": Spec("range", (0.0, 0.5), 0.0, 1.0, "(fraction of the SPL impulse)"),
                 "residual_dv": Spec("number", 0.0, 0.0, 1.0, "m/s")},
    "drift_stop_delayed": {"delay_orbits": Spec("irange", (1, 3), 1, 10, "orbits")},
    "drift_stop_missed": {},
    "burn_underperformance": {"burn": Spec("irange", 1, 1, 50, "(n-th executed carrier burn)"),
                              "mode": Spec("choice", "magnitude", choices=("magnitude", "pointing")),
                              "magnitude": Spec("range", (0.5, 0.8), 0.0, 2.0, "(fraction of the burn)"),
                              "pointing_deg": Spec("range", (5.0, 15.0), 0.0, 180.0, "deg")},
    "radar_pass_missed": {"passes": Spec("irange", (1, 2), 1, 20, "passes"),
                          "outage": Spec("number", 0.0, 0.0, 30 * 86400.0, "s")},
    "radar_bias": {"bias_m": Spec("range", (10.0, 50.0), -10000.0, 10000.0, "m"),
                   "station": Spec("string", "")},
    "ejection_pointing": {"angle_deg": Spec("range", (-10.0, 10.0), -180.0, 180.0, "deg")},
    "carrier_safe_mode": {"start_h": Spec("range", (0.0, 12.0), 0.0, 720.0, "h"),
                          "hours": Spec("range", (6.0, 24.0), 0.0, 720.0, "h")},
    "drift_stop_overperformance": {"magnitude": Spec("range", (1.1, 1.5), 1.0, 3.0, "(fraction of the burn)")},
    "density_storm": {"factor": Spec("range", (2.0, 5.0), 0.0, 100.0, "(density multiplier)"),
                      "start_h": Spec("range", (6.0, 30.0), 0.0, 720.0, "h"),
                      "hours": Spec("range", (6.0, 24.0), 0.0, 720.0, "h")},
}
"""{contingency: {parameter: Spec}}: the contingencies and their parameters with their defaults."""
NAMES = tuple(SPECS)
SIM_SIDE = ("spl_weak", "drift_stop_delayed", "drift_stop_missed", "burn_underperformance", "ejection_pointing",
            "carrier_safe_mode", "drift_stop_overperformance", "density_storm")
RADAR_SIDE = ("radar_pass_missed", "radar_bias")


@dataclass(frozen=True)
class ContingencyConfig:
    """A validated ``contingency:`` block: the name and its parameters (every one, the defaults filled in) as sorted
    ``(key, value)`` pairs; a value is a number, a string or a ``(lo, hi)`` range."""

    name: str
    parameters: tuple = ()

    def get(self, key: str) -> float | str | tuple[float, float]:
        """The value of parameter ``key``: a number, a string or a ``(lo, hi)`` range; KeyError when it has none."""
        return dict(self.parameters)[key]


def _check_value(path, spec: Spec, value):
    """The validated value of one parameter (a range as a tuple), ConfigError naming ``path`` else."""
    integer = spec.kind == "irange"
    if spec.kind in ("range", "irange"):
        if isinstance(value, (list, tuple)):
            if len(value) != 2:
                raise ConfigError(f"{path}: expected a number or [lo, hi], got {show(value)}")
            lo, hi = (_number(f"{path}[{i}]", v, spec, integer, element=True) for i, v in enumerate(value))
            if lo > hi:
                raise ConfigError(f"{path}: expected [lo, hi] with lo <= hi, got {show(value)}")
            return (lo, hi)
        return _number(path, value, spec, integer)
    if spec.kind == "number":
        return _number(path, value, spec, False)
    if spec.kind == "choice":
        if value not in spec.choices:
            raise ConfigError(f"{path}: expected one of {list(spec.choices)}, got {show(value)}")
        return value
    if not isinstance(value, str):
        raise ConfigError(f"{path}: expected a string, got {show(value)}")
    return value


def _number(path, value, spec, integer, element=False):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or (integer and not isinstance(value, int)):
        raise ConfigError(f"{path}: expected {'an integer' if integer else 'a number'}"
                          f"{'' if spec.kind == 'number' or element else ' or [lo, hi]'}, got {show(value)}")
    try:
        check_number(path, value, spec.lo, spec.hi, integer=integer, unit=spec.unit)
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
    return int(value) if integer else float(value)


def contingency_from_dict(data: dict | None, path: str = "contingency") -> ContingencyConfig | None:
    """The scenario's ``contingency:`` block: None (absent, null or ``name: none``), else a mapping with ``name`` (one
    of :data:`NAMES`) and any of that contingency's parameters (:data:`SPECS`). ConfigError naming the key."""
    if data is None:
        return None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping with 'name' and its parameters, got {show(data)}")
    name = data.get("name")
    if name == NONE:
        if set(data) != {"name"}:
            raise ConfigError(f"{path}: 'name: none' takes no parameters, got {sorted(set(data) - {'name'})}")
        return None
    if name not in SPECS:
        raise ConfigError(f"{path}.name: expected one of {[*NAMES, NONE]}, got {show(name)}")
    specs = SPECS[name]
    unknown = sorted(set(data) - {"name"} - set(specs))
    if unknown:
        raise ConfigError(f"{path}: unknown key(s) {unknown} for {name}; its parameters: {sorted(specs)}")
    values = {k: _check_value(f"{path}.{k}", s, data.get(k, s.default)) for k, s in specs.items()}
    return ContingencyConfig(name, tuple(sorted(values.items())))


def default_config(name: str) -> ContingencyConfig:
    """``name`` with every parameter at its default."""
    return contingency_from_dict({"name": name})


def resolve(scenario_block: ContingencyConfig | None, name: str = "") -> ContingencyConfig | None:
    """The run's contingency: the scenario's block when ``name`` (the node parameter, ``--contingency``) is '';
    none for 'none'; else ``name`` with the block's parameters when the block names it, with the defaults when not."""
    if not name:
        return scenario_block
    if name == NONE:
        return None
    if name not in SPECS:
        raise ConfigError(f"contingency: expected one of {['', NONE, *NAMES]}, got {show(name)}")
    if scenario_block is not None and scenario_block.name == name:
        return scenario_block
    return default_config(name)


def draw(config: ContingencyConfig, seed: int) -> dict:
    """The values of a run: every parameter from ``numpy.random.default_rng(SeedSequence([seed,
    CONTINGENCY_STREAM]))``, one uniform draw per parameter in sorted order whether it is fixed or a range (a
    fixed value keeps the other parameters' draws), integers uniform in [lo, hi]; plus ``azimuth`` [rad], the
    pointing error's axis, for ``burn_underperformance``."""
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), CONTINGENCY_STREAM]))
    specs = SPECS[config.name]
    out = {}
    for key, value in config.parameters:
        u = float(rng.uniform())
        if isinstance(value, tuple):
            lo, hi = value
            if specs[key].kind == "irange":
                out[key] = int(min(hi, lo + math.floor(u * (hi - lo + 1))))
            else:
                out[key] = float(lo + u * (hi - lo))
        else:
            out[key] = value
    if config.name == "burn_underperformance":
        out["azimuth"] = float(rng.uniform(0.0, 2.0 * math.pi))
    return out


def configured(config: ContingencyConfig) -> dict:
    """The block as configured, for the record (ranges as lists)."""
    return {k: list(v) if isinstance(v, tuple) else v for k, v in config.parameters}


def rotate_normal(dv: ArrayLike, angle: float, azimuth: float) -> np.ndarray:
    """``dv`` ``(3,)`` turned by ``angle`` [rad] about the axis normal to it at ``azimuth`` [rad] (measured from the
    normal of ``dv`` in the plane of ``dv`` and the R axis, or the N axis for a radial ``dv``); magnitude kept.

    Parameters
    ----------
    dv : array_like, shape (3,)
        The burn [m/s] in RTN.
    angle : float
        The angle [rad] it is turned by.
    azimuth : float
        The azimuth [rad] of the rotation axis about ``dv``.

    Returns
    -------
    numpy.ndarray, shape (3,)
        The turned burn [m/s] in RTN, of the magnitude of ``dv`` (a copy of a zero ``dv``).
    """
    v = np.asarray(dv, dtype=float)
    mag = float(np.linalg.norm(v))
    if mag == 0.0:
        return v.copy()
    u = v / mag
    ref = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    p = np.cross(u, ref)
    p /= np.linalg.norm(p)
    q = np.cross(u, p)
    axis = math.cos(azimuth) * p + math.sin(azimuth) * q
    return v * math.cos(angle) + np.cross(axis, v) * math.sin(angle)


def rotate_about_normal(dv: ArrayLike, angle: float) -> np.ndarray:
    """``dv`` ``(3,)`` in RTN turned by ``angle`` [rad] about the N axis, right-handed (R towards T): the N
    component and the magnitude are kept.

    Parameters
    ----------
    dv : array_like, shape (3,)
        The impulse [m/s] in RTN.
    angle : float
        The angle [rad]; positive turns R towards T.

    Returns
    -------
    numpy.ndarray, shape (3,)
        The turned impulse [m/s] in RTN.
    """
    v = np.asarray(dv, dtype=float)
    c, s = math.cos(angle), math.sin(angle)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]])


HOUR = 3600.0  # s


@dataclass(frozen=True)
class DensityStorm:
    """A geomagnetic storm of ``density_storm``: the density the truth's drag sees times ``factor`` from ``start``
    [s] after the executed ejection for ``duration`` [s] (the window half-open, [t0, t1))."""

    factor: float
    start: float  # s after the ejection
    duration: float  # s

    def window(self, ejection: float) -> tuple[float, float]:
        """The storm's window [s] of sim time for the ejection executed at ``ejection`` [s]."""
        t0 = float(ejection) + self.start
        return t0, t0 + self.duration

    def factor_at(self, t: ArrayLike, ejection: float | None) -> np.ndarray:
        """The density factor at ``t`` [s] (any shape): ``factor`` inside the window, 1 outside and before the
        ejection (``ejection`` None)."""
        t = np.asarray(t, dtype=float)
        if ejection is None:
            return np.ones_like(t)
        t0, t1 = self.window(ejection)
        return np.where((t >= t0) & (t < t1), self.factor, 1.0)


@dataclass
class Contingency:
    """A drawn contingency of one run (:func:`draw`) and what it did (``events``), for the record of the run."""

    config: ContingencyConfig
    values: dict
    events: list = field(default_factory=list)

    @property
    def name(self) -> str:
        return self.config.name

    def applied(self) -> dict:
        """{name, parameters (as drawn), configured, events}: plain JSON."""
        return {"name": self.name, "parameters": dict(self.values), "configured": configured(self.config),
                "events": list(self.events)}


class TruthContingency(Contingency):
    """The simulator's side (:data:`SIM_SIDE`): which burns it moves or drops when commanded (:meth:`reschedule`) or
    when due (:meth:`dropped`), how it changes an executed burn (:meth:`executed`) and the truth's density storm
    (:attr:`storm`). ``period`` [s]: the carrier's orbit in mean argument of latitude (the drift-stop's delay is
    whole orbits)."""

    def __init__(self, config: ContingencyConfig, seed: int, period: float):
        super().__init__(config, draw(config, seed))
        self.period = float(period)
        self.carrier_burns = 0
        self.drift_stops = 0  # executed carrier drift-stops
        self.drift_stop_epoch = None  # s (to the ms), the first drift-stop commanded: the one that fails
        self.ejection_epoch = None  # s, the executed ejection (the safe mode's and the storm's windows start there)
        self._seen = set()

    @property
    def storm(self) -> DensityStorm | None:
        """The density storm the truth applies (``density_storm``), None for every other contingency."""
        if self.name != "density_storm":
            return None
        v = self.values
        return DensityStorm(v["factor"], v["start_h"] * HOUR, v["hours"] * HOUR)

    def safe_mode_window(self) -> tuple[float, float] | None:
        """The carrier's safe mode [s] of sim time, [t0, t1), for ``carrier_safe_mode`` once the ejection executed;
        None else."""
        if self.name != "carrier_safe_mode" or self.ejection_epoch is None:
            return None
        t0 = self.ejection_epoch + self.values["start_h"] * HOUR
        return t0, t0 + self.values["hours"] * HOUR

    def dropped(self, epoch: float, purpose: str, spacecraft: str) -> bool:
        """Whether a burn due at ``epoch`` is lost when it comes due: a carrier burn commanded into the safe mode's
        window (``carrier_safe_mode``: the carrier executes no time-tagged command then); an event records it.

        Parameters
        ----------
        epoch : float
            The burn's epoch [s] of sim time.
        purpose : str
            The burn's purpose (for the record).
        spacecraft : str
            Who burns (only the ``carrier``'s burns are lost).

        Returns
        -------
        bool
            True when the burn never executes.
        """
        window = self.safe_mode_window()
        if window is None or spacecraft != "carrier" or not window[0] <= epoch < window[1]:
            return False
        self._event(("safe_mode", purpose, round(epoch, 3)), f"{purpose} commanded at t = {epoch:.1f} s: not "
                    f"executed (carrier safe mode from t = {window[0]:.1f} s to t = {window[1]:.1f} s)")
        return True

    def _event(self, key, text):
        if key not in self._seen:
            self._seen.add(key)
            self.events.append(text)

    def reschedule(self, epoch: float, purpose: str, spacecraft: str) -> float | None:
        """The epoch [s] a planned burn commanded at ``epoch`` executes at, None when it never does: the first
        commanded ``drift_stop`` (and the same burn re-published) k orbits late (``drift_stop_delayed``) or dropped
        (``drift_stop_missed``); every other burn on time, a replacement drift-stop commanded for another epoch too.

        Parameters
        ----------
        epoch : float
            The commanded epoch [s] of sim time.
        purpose : str
            The burn's purpose (only a ``drift_stop`` moves).
        spacecraft : str
            Who burns (only the ``carrier``'s burns move).

        Returns
        -------
        float or None
            The epoch [s] of sim time it executes at, None when it never does.
        """
        if purpose != "drift_stop" or spacecraft != "carrier":
            return epoch
        if self.drift_stop_epoch is None:
            self.drift_stop_epoch = round(epoch, 3)
        if round(epoch, 3) != self.drift_stop_epoch:  # a replacement commanded for another epoch flies
            return epoch
        if self.name == "drift_stop_missed":
            self._event(("missed", round(epoch, 3)), f"drift_stop commanded at t = {epoch:.1f} s: not executed")
            return None
        if self.name == "drift_stop_delayed":
            late = epoch + self.values["delay_orbits"] * self.period
            self._event(("delayed", round(epoch, 3)), f"drift_stop commanded at t = {epoch:.1f} s: executes at "
                        f"t = {late:.1f} s ({self.values['delay_orbits']} orbit(s) late)")
            return late
        return epoch

    def executed(self, dv_executed: ArrayLike, purpose: str, spacecraft: str, epoch: float) -> np.ndarray:
        """The burn as executed under the contingency from ``dv_executed`` ``(3,)`` [m/s], the burn with its
        nominal execution errors (:meth:`~.secular.ExecutionErrors.executed`, drawn as without the contingency).

        Parameters
        ----------
        dv_executed : array_like, shape (3,)
            The burn [m/s] in the RTN frame of the spacecraft that burns, with its nominal execution errors.
        purpose : str
            The burn's purpose (``ejection`` for the SPL's).
        spacecraft : str
            Who burns: ``carrier`` or ``picosatellite`` (the carrier's burns are counted).
        epoch : float
            The epoch [s] of sim time it executes at (for the record).

        Returns
        -------
        numpy.ndarray, shape (3,)
            The burn [m/s] as executed under the contingency (``dv_executed`` when it is not touched).
        """
        dv = np.asarray(dv_executed, dtype=float)
        if spacecraft == "carrier":
            self.carrier_burns += 1
        if purpose == "ejection" and self.ejection_epoch is None:
            self.ejection_epoch = float(epoch)
            self._windows(epoch)
        if self.name == "ejection_pointing" and purpose == "ejection":
            out = rotate_about_normal(dv, math.radians(self.values["angle_deg"]))
            self.events.append(f"ejection at t = {epoch:.1f} s: turned by {self.values['angle_deg']:+.2f} deg about "
                               f"N, dv RTN ({out[0]:+.4f}, {out[1]:+.4f}, {out[2]:+.4f}) m/s")
            return out
        if self.name == "drift_stop_overperformance" and spacecraft == "carrier" and purpose == "drift_stop":
            self.drift_stops += 1
            if self.drift_stops == 1:
                self.events.append(f"drift_stop at t = {epoch:.1f} s: {self.values['magnitude']:.3f} of its "
                                   "magnitude")
                return self.values["magnitude"] * dv
        if self.name == "spl_weak" and purpose == "ejection":
            f1 = self.values["spl_fraction"]
            out = f1 * dv
            mag, residual = float(np.linalg.norm(dv)), self.values["residual_dv"]
            if mag > 0.0 and float(np.linalg.norm(out)) < residual:
                out = dv * (residual / mag)
            self.events.append(f"ejection at t = {epoch:.1f} s: {float(np.linalg.norm(out)):.4f} m/s of "
                               f"{mag:.4f} m/s (f1 = {f1:.4f})")
            return out
        if self.name == "burn_underperformance" and spacecraft == "carrier" \
                and self.carrier_burns == self.values["burn"]:
            if self.values["mode"] == "pointing":
                angle = math.radians(self.values["pointing_deg"])
                out = rotate_normal(dv, angle, self.values["azimuth"])
                self.events.append(f"{purpose} at t = {epoch:.1f} s (carrier burn {self.carrier_burns}): turned by "
                                   f"{self.values['pointing_deg']:.2f} deg")
                return out
            out = self.values["magnitude"] * dv
            self.events.append(f"{purpose} at t = {epoch:.1f} s (carrier burn {self.carrier_burns}): "
                               f"{self.values['magnitude']:.3f} of its magnitude")
            return out
        return dv


    def _windows(self, ejection):
        """Record the safe mode's or the storm's window, now that the ejection executed at ``ejection`` [s]."""
        if self.name == "carrier_safe_mode":
            t0, t1 = self.safe_mode_window()
            self.events.append(f"carrier safe mode from t = {t0:.1f} s to t = {t1:.1f} s: no carrier burn")
        elif self.name == "density_storm":
            t0, t1 = self.storm.window(ejection)
            self.events.append(f"density storm x{self.values['factor']:.3f} from t = {t0:.1f} s to t = {t1:.1f} s")


class RadarContingency(Contingency):
    """The radar's side (:data:`RADAR_SIDE`): which measurements are never made (:meth:`dropped`) and the range
    bias of a station (:meth:`range_bias`). ``stations``: the radar's station names, in order."""

    def __init__(self, config: ContingencyConfig, seed: int, stations):
        super().__init__(config, draw(config, seed))
        self.stations = list(stations)
        self.passes_opened = 0
        self.dropped_passes = set()  # (station index, pass id)
        self.outage_start = None
        self.bias_station = None
        if self.name == "radar_bias":
            name = self.values["station"]
            if name and name not in self.stations:
                raise ConfigError(f"contingency.station: {name!r} is not a radar station (stations: "
                                  f"{self.stations})")
            self.bias_station = self.stations.index(name) if name else 0
            self.events.append(f"range bias {self.values['bias_m']:+.2f} m at {self.stations[self.bias_station]}")

    def pass_opened(self, station: int, pass_id: int, t: float) -> None:
        """A pass of ``station`` opened at ``t`` [s] (the first measurement epoch of it).

        Parameters
        ----------
        station : int
            The station's index in ``stations``.
        pass_id : int
            The pass's id at that station.
        t : float
            The epoch [s] of sim time of the pass's first measurement.

        Returns
        -------
        None
        """
        if self.name != "radar_pass_missed":
            return
        self.passes_opened += 1
        if self.values["outage"] > 0.0:
            if self.outage_start is None:
                self.outage_start = t
                self.events.append(f"radar outage from t = {t:.1f} s to t = {t + self.values['outage']:.1f} s")
        elif self.passes_opened <= self.values["passes"]:
            self.dropped_passes.add((station, pass_id))
            self.events.append(f"{self.stations[station]} pass {pass_id} from t = {t:.1f} s: no measurement")

    def dropped(self, station: int, pass_id: int, t: float) -> bool:
        """Whether the measurement of ``station`` in its pass ``pass_id`` at ``t`` [s] is never made.

        Parameters
        ----------
        station : int
            The station's index in ``stations``.
        pass_id : int
            The pass's id at that station.
        t : float
            The epoch [s] of sim time of the measurement.

        Returns
        -------
        bool
            True when the measurement is never made (a dropped pass or within the outage).
        """
        if self.name != "radar_pass_missed":
            return False
        if self.outage_start is not None:
            return self.outage_start <= t < self.outage_start + self.values["outage"]
        return (station, pass_id) in self.dropped_passes

    def range_bias(self, station: int) -> float:
        """The range bias [m] of ``station``'s measurements."""
        return self.values["bias_m"] if station == self.bias_station else 0.0
