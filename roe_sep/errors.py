"""Every exception roe_sep raises on purpose, under one root, and the one way a message shows a value.

:class:`RoeSepError` is the root (a ``ValueError``: bad input, a bad file, an infeasible request); the command line
catches it for its one-line message and exit status 2. One subclass per kind of failure, named for what failed:

* :class:`ConfigError`: a configuration key or value (scenario YAML, cluster YAML, a node's config file).
* :class:`ParameterError`: a node parameter; the node stops at start-up naming it.
* :class:`InfeasibleDesignError`: a separation that violates a constraint of the design (seed 002 Table 1).
* :class:`AcquisitionInfeasible`, :class:`InvalidAcquisitionConfig`: the initial-condition acquisition planner.
* :class:`BadMessage`: a ROS message that fails validation (:mod:`roe_sep.validate`); ``field`` names what.
* :class:`BagError`, :class:`DefinitionNotFound`: a bag that cannot be read or written, a message type without an
  installed ``.msg`` file (also a ``LookupError``).
* :class:`NdmError`: a CCSDS navigation data message that cannot be read or is not what roe_sep expects.
* :class:`RosArgumentsError`: ROS arguments a node cannot use (a missing or malformed ``--params-file``).

Not an error and not under the root: :class:`Interrupted`, the ``KeyboardInterrupt`` a stop signal raises in a
parent of child processes.

:func:`show` writes a value into a message as plain Python (``0.0``, ``[1.0, 2.0]``), never as a NumPy repr
(``np.float64(0.0)``).

The lowest layer: imports nothing of roe_sep (nor NumPy), so every layer, the core included, may import it. The
modules that raised these exceptions before re-export them (``roe_sep.core.config.ConfigError`` ...).
"""

import dataclasses
import signal


def plain(value):
    """``value`` with every NumPy scalar or array (anything with ``tolist()``) as the Python number or list it
    holds, inside lists, tuples (named ones too) and dicts."""
    if callable(getattr(value, "tolist", None)) and not isinstance(value, (str, bytes)):
        value = value.tolist()
    if isinstance(value, dict):
        return {plain(k): plain(v) for k, v in value.items()}
    if isinstance(value, tuple):
        items = [plain(v) for v in value]
        return type(value)(*items) if hasattr(value, "_fields") else tuple(items)
    if isinstance(value, list):
        return [plain(v) for v in value]
    return value


def show(value) -> str:
    """How a message shows a value: the repr of :func:`plain` of it (``0.0``, ``[97.0, 0.0]``, ``'abc'``); a
    dataclass as its repr with each field shown so (``CubeSat(cd=2.2, area=0.01, mass=1.0)``)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = ", ".join(f"{f.name}={show(getattr(value, f.name))}" for f in dataclasses.fields(value) if f.repr)
        return f"{type(value).__name__}({fields})"
    return repr(plain(value))


class RoeSepError(ValueError):
    """The root of roe_sep's exceptions: the message says what is wrong, on one line, naming the value."""


class ConfigError(RoeSepError):
    """A configuration key or value is invalid; the message names it."""


class ParameterError(RoeSepError):
    """A node parameter is invalid; the message names it."""


class InfeasibleDesignError(RoeSepError):
    """The requested separation violates a constraint of seed 002 Table 1 (named in the message)."""


class AcquisitionInfeasible(RoeSepError):
    """No carrier plan reaches the initial conditions (or the estimate is unusable); the message says why."""


class InvalidAcquisitionConfig(RoeSepError):
    """A configuration field is invalid: ``name``, what it ``must`` be, and the offending ``value``."""

    def __init__(self, name, must, value):
        super().__init__(f"{name} must be {must}, got {show(value)}")
        self.name, self.must, self.value = name, must, value


class BadMessage(RoeSepError):
    """A message that fails validation; ``field`` names what is wrong."""

    def __init__(self, field, value, must):
        super().__init__(f"{field} = {show(value)}: must be {must}")
        self.field = field


class BagError(RoeSepError):
    """A bag cannot be read or written; the message says which path and why."""


class UnsupportedSchema(RoeSepError):
    """A bag schema that the compiled decoder (:mod:`roe_sep.bag.cdr`) does not cover; mcap_ros2 decodes it instead
    (caught where raised, never shown)."""


class IrregularBag(RoeSepError):
    """A part of an MCAP file that the fast record scan (:mod:`roe_sep.bag.scan`) does not read as mcap's own reader
    would; mcap's StreamReader reads it instead (caught where raised, never shown)."""


class DefinitionNotFound(RoeSepError, LookupError):
    """No installed ``.msg`` file for a type."""


class EopError(RoeSepError):
    """An Earth orientation parameter file that cannot be read (the message names the file and the line)."""


class NdmError(RoeSepError):
    """A navigation data message that cannot be read or is not what roe_sep expects (the message says why)."""


class RosArgumentsError(RoeSepError):
    """The ROS arguments cannot be used: a ``--params-file`` missing or not a ROS parameter YAML, a malformed ``-p``."""


class Interrupted(KeyboardInterrupt):
    """Not an error: a stop signal (SIGINT, SIGTERM, SIGHUP) to a parent of child processes
    (:func:`roe_sep.children.guarded`), raised as a KeyboardInterrupt so that the Ctrl-C path stops its children in
    order; ``signum`` says which (exit status ``128 + signum``)."""

    def __init__(self, signum):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


__all__ = ["AcquisitionInfeasible", "BadMessage", "BagError", "ConfigError", "DefinitionNotFound",
           "InfeasibleDesignError", "Interrupted", "InvalidAcquisitionConfig", "NdmError", "ParameterError",
           "RoeSepError", "RosArgumentsError", "plain", "show"]
