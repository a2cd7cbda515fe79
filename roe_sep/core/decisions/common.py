"""What every decision module shares: the status and log actions, the guard that turns a failure into an ERROR
status, a planned burn as its message carries it, and the strict-JSON form of a state."""

import dataclasses
import json
import math
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...stamps import sec_nanosec, time_to_sec
from ..relmotion.roe import wrap_angle
from ..relmotion.trajectory import Burn
from ..truth.execution import relative_impulse

OK, WARN, ERROR = 0, 1, 2  # diagnostic_msgs/DiagnosticStatus levels


@dataclass(frozen=True)
class Status:
    """Publish a status on /diagnostics (``part``: the name's suffix; ``stamp`` [s] or None: the node's time) and
    log ``log_text`` (default ``message``) at logger level ``log`` ("debug", "info", "warning", "error"; None: not
    logged). ``values``: ``(key, value)`` pairs."""

    level: int
    message: str
    values: tuple = ()
    log: str | None = None
    log_text: str | None = None
    part: str = ""
    stamp: float | None = None


@dataclass(frozen=True)
class Log:
    """Log ``text`` at logger level ``level`` ("debug", "info", "warning", "error")."""

    level: str
    text: str


def status(level: int, message: str, values: dict, log: str | None = "info", **kwargs: Any) -> Status:
    """A :class:`Status` logged (at ``log``) and published with the ``values`` dict.

    Parameters
    ----------
    level : int
        :data:`OK`, :data:`WARN` or :data:`ERROR` (diagnostic_msgs/DiagnosticStatus levels).
    message : str
        The status message, also the logged text unless ``log_text`` is given.
    values : dict
        The status values, in their order.
    log : str or None
        The logger level ("debug", "info", "warning", "error"); None: published only.
    **kwargs
        The other fields of :class:`Status` (``log_text``, ``part``, ``stamp``).

    Returns
    -------
    Status
        The action.
    """
    return Status(level, message, tuple(values.items()), log, **kwargs)


def guarded(rejected: str, failed: str, values: dict, fn: Callable, *args: Any, **kwargs: Any) -> tuple[Any, tuple]:
    """``fn(*args, **kwargs)`` with its failure as an ERROR status: a ValueError is a bad input or no solution, anything
    else a bug (logged with its traceback) that must not take a node down.

    Parameters
    ----------
    rejected, failed : str
        The message's prefix for a ValueError and for any other exception.
    values : dict
        The values of the ERROR status.
    fn : callable
        The step to run, with ``*args`` and ``**kwargs``.

    Returns
    -------
    tuple
        ``(fn's result, ())``, or ``(None, (Status,))`` when it raised.
    """
    try:
        return fn(*args, **kwargs), ()
    except ValueError as exc:
        return None, (status(ERROR, f"{rejected}: {exc}", values, "error"),)
    except Exception as exc:  # noqa: BLE001 -- reported, never fatal
        text = f"{failed}: {exc!r}"
        return None, (status(ERROR, text, values, "error", log_text=f"{text}\n{traceback.format_exc()}"),)


@dataclass(frozen=True)
class Stamped:
    """Something a message stamps: ``sec``, ``nanosec`` as builtin_interfaces/Time carries them."""

    sec: int
    nanosec: int

    @property
    def epoch(self) -> float:
        """s, as :func:`roe_sep.stamps.time_to_sec` reads the stamp."""
        return time_to_sec(self)


class State:
    """A decision state: ``to_dict`` gives its strict-JSON primitives (:func:`plain`); each state's ``from_dict``
    reads them back. ``VOLATILE``: the fields a restart does not keep (:meth:`persisted`, :meth:`restored`): what the
    latched inputs give again or what means nothing in another process (a wall time)."""

    VOLATILE: tuple = ()

    def to_dict(self) -> dict:
        return plain(self)

    def persisted(self) -> dict:
        """:meth:`to_dict` without the ``VOLATILE`` fields: what the decisions topic keeps."""
        return {k: v for k, v in self.to_dict().items() if k not in self.VOLATILE}

    @classmethod
    def restored(cls, d: dict) -> "State":
        """The state of :meth:`persisted` (each ``VOLATILE`` field at its default); ValueError for a field that is
        unknown, missing or malformed."""
        fields = {f.name for f in dataclasses.fields(cls)} - set(cls.VOLATILE)
        if not isinstance(d, dict) or set(d) != fields:
            got = sorted(d) if isinstance(d, dict) else type(d).__name__
            raise ValueError(f"a {cls.__name__} needs the fields {sorted(fields)}, got {got}")
        try:
            return cls.from_dict({**cls().to_dict(), **d})
        except (TypeError, KeyError, AttributeError, IndexError) as exc:
            raise ValueError(f"a malformed {cls.__name__}: {exc!r}") from exc


def _not_finite(name: str):
    raise ValueError(f"{name} is not strict JSON")


RECORD_FORMAT = 1  # the layout of a decision record (:func:`decision_record`)


def decision_record(node: str, version: int, stamp: float, state: State) -> str:
    """The strict-JSON decision record of ``node`` (docs/run.md, "Decisions"): its ``version`` (1, 2, ... each
    decision of the run), the sim time ``stamp`` [s] of the decision and the :meth:`State.persisted` state.

    Parameters
    ----------
    node : str
        The deciding node's name ("planner", "ic_planner").
    version : int
        The record's number in the run, counted on across restarts.
    stamp : float
        s, sim time of the decision.
    state : State
        The state after the decision.

    Returns
    -------
    str
        One JSON object: ``format``, ``node``, ``version``, ``stamp``, ``state``.
    """
    record = {"format": RECORD_FORMAT, "node": node, "version": int(version), "stamp": float(stamp),
              "state": state.persisted()}
    return json.dumps(record, allow_nan=False, sort_keys=True, separators=(",", ":"))


def read_record(text: str, node: str) -> tuple:
    """``(version, stamp [s], persisted state dict)`` of a :func:`decision_record` of ``node``; ValueError naming
    what is wrong (not JSON, another node's or format's record, a field missing).

    Parameters
    ----------
    text : str
        The record as the decisions topic carries it.
    node : str
        The node whose record it must be.

    Returns
    -------
    tuple
        ``(version, stamp, state)``: int, float [s], dict (read it with the state's ``restored``).
    """
    try:
        record = json.loads(text, parse_constant=_not_finite)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"a decision record is not JSON: {exc}") from exc
    if not isinstance(record, dict) or record.get("format") != RECORD_FORMAT:
        raise ValueError(f"not a decision record of format {RECORD_FORMAT}")
    if record.get("node") != node:
        raise ValueError(f"a decision record of {record.get('node')!r}, not of {node!r}")
    version, stamp, state = record.get("version"), record.get("stamp"), record.get("state")
    if not isinstance(version, int) or not isinstance(stamp, (int, float)) or not isinstance(state, dict):
        raise ValueError("a decision record needs an integer version, a numeric stamp and a state object")
    if not math.isfinite(stamp):
        raise ValueError(f"a decision record's stamp is not finite: {stamp}")
    return version, float(stamp), state


@dataclass(frozen=True)
class PlannedBurn(Stamped):
    """One impulsive maneuver as its message (roe_sep_msgs/ImpulsiveManeuver) carries it: epoch stamp ``sec``,
    ``nanosec``, mean argument of latitude ``u`` [rad], ``dv_rtn`` (3,) [m/s] of ``spacecraft`` ("carrier" or
    "picosatellite"), ``purpose``."""

    u: float
    dv_rtn: tuple
    spacecraft: str
    purpose: str

    @classmethod
    def at(cls, epoch: float, u: float, dv_rtn: ArrayLike, spacecraft: str, purpose: str) -> "PlannedBurn":
        """The burn a message built at ``epoch`` carries.

        Parameters
        ----------
        epoch : float
            The burn's epoch [s] (sim time), stamped as ``sec``, ``nanosec``.
        u : float
            Its mean argument of latitude [rad], wrapped to [-pi, pi).
        dv_rtn : array_like, shape (3,)
            The impulse [m/s] in the burning spacecraft's RTN frame.
        spacecraft, purpose : str
            "carrier" or "picosatellite"; the message's purpose ("drift_stop", "ic_acquisition", ...).

        Returns
        -------
        PlannedBurn
            The burn, its numbers as Python floats.
        """
        sec, nanosec = sec_nanosec(epoch)
        return cls(sec, nanosec, float(wrap_angle(u)), tuple(float(c) for c in dv_rtn), spacecraft, purpose)

    def relative(self) -> Burn:
        """Its relative impulse (:func:`~roe_sep.core.truth.execution.relative_impulse`); ValueError for an unknown
        spacecraft."""
        return Burn(self.epoch, tuple(relative_impulse(np.array(self.dv_rtn, dtype=float), self.spacecraft)))


def plain(value: Any) -> Any:
    """``value`` as strict-JSON primitives: a dataclass as a dict of its fields, a tuple or list as a list, a numpy
    scalar as its Python value; ValueError for a float that is not finite."""
    if dataclasses.is_dataclass(value):
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, (tuple, list)):
        return [plain(v) for v in value]
    value = scalar(value)
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"a state holds a value that is not finite: {value}")
    return value


def scalar(value: Any) -> Any:
    """A numpy scalar as its Python value; anything else unchanged."""
    return value.item() if isinstance(value, np.generic) else value


def tuples(value: Any) -> Any:
    """A JSON list (nested) back as tuples; anything else unchanged."""
    return tuple(tuples(v) for v in value) if isinstance(value, list) else value


def optional(make: Callable, value: Any) -> Any:
    """``make(value)``, or None for None."""
    return None if value is None else make(value)


def burn_from_dict(d: dict) -> Burn:
    """A :class:`~roe_sep.core.relmotion.trajectory.Burn` from its :func:`plain` form."""
    return Burn(d["epoch"], tuples(d["dv_rel"]))


def planned_from_dict(d: dict) -> PlannedBurn:
    """A :class:`PlannedBurn` from its :func:`plain` form."""
    return PlannedBurn(**{**d, "dv_rtn": tuples(d["dv_rtn"])})
