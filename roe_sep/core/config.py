"""Scenario configuration: YAML/dict -> validated dataclasses, every bad key or value named in the error.

The embedded defaults are the dataclass defaults (the BIROS/picosatellite case of seeds 000/002); a file only
overrides what it names. Layout::

    separation: {altitude: 515000.0, u1_deg: 88.0, ...}        # SeparationConfig fields
    monte_carlo: {samples: 100000, seed: 0, p_values: [...], carrier: {cd: 2.3, area: 0.48, mass: 140.0}, ...}
"""

import dataclasses
import math
import types
import typing
from dataclasses import dataclass, field

from .montecarlo.sweep import DEFAULT_P_VALUES, MonteCarloConfig
from .separation.double_impulse import SeparationConfig


class ConfigError(ValueError):
    """A configuration key or value is invalid; the message names it."""


@dataclass(frozen=True)
class Scenario:
    """Everything the CLI and the nodes need for one separation scenario."""

    separation: SeparationConfig = field(default_factory=SeparationConfig)
    monte_carlo: MonteCarloConfig = field(default_factory=MonteCarloConfig)
    p_values: tuple = DEFAULT_P_VALUES


def _coerce(path, value, hint):
    """Check ``value`` against a field's type hint; ints are accepted for floats, never bools for numbers."""
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        args = typing.get_args(hint)
        if value is None and type(None) in args:
            return None
        hint = next(a for a in args if a is not type(None))
    if dataclasses.is_dataclass(hint):
        return _build(path, hint, value)
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{path}: expected true/false, got {value!r}")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{path}: expected an integer, got {value!r}")
        return value
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{path}: expected a number, got {value!r}")
        if not math.isfinite(value):
            raise ConfigError(f"{path}: expected a finite number, got {value!r}")
        return float(value)
    return value


def _build(path, cls, data):
    if data is None:
        return cls()
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping, got {type(data).__name__}")
    hints = typing.get_type_hints(cls)
    names = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(data) - set(names))
    if unknown:
        raise ConfigError(f"{path}: unknown key(s) {unknown}; known keys: {names}")
    kwargs = {k: _coerce(f"{path}.{k}", v, hints[k]) for k, v in data.items()}
    return cls(**kwargs)


def scenario_from_dict(data) -> Scenario:
    """Build a :class:`Scenario` from a parsed YAML mapping (``None`` or ``{}`` gives the defaults)."""
    data = {} if data is None else data
    if not isinstance(data, dict):
        raise ConfigError(f"configuration: expected a mapping at the top level, got {type(data).__name__}")
    unknown = sorted(set(data) - {"separation", "monte_carlo"})
    if unknown:
        raise ConfigError(f"configuration: unknown section(s) {unknown}; known: ['separation', 'monte_carlo']")
    mc = dict(data.get("monte_carlo") or {})
    p_values = mc.pop("p_values", DEFAULT_P_VALUES)
    if not isinstance(p_values, (list, tuple)) or not p_values:
        raise ConfigError(f"monte_carlo.p_values: expected a non-empty list of numbers [m/s], got {p_values!r}")
    p_values = tuple(_coerce(f"monte_carlo.p_values[{i}]", p, float) for i, p in enumerate(p_values))
    if any(p < 0 for p in p_values):
        raise ConfigError(f"monte_carlo.p_values: reductions |p| must be non-negative, got {list(p_values)}")
    return Scenario(
        separation=_build("separation", SeparationConfig, data.get("separation")),
        monte_carlo=_build("monte_carlo", MonteCarloConfig, mc),
        p_values=p_values,
    )


def read_yaml(path):
    """The parsed content of a YAML configuration file; unreadable or invalid files raise :class:`ConfigError`."""
    import yaml

    try:
        with open(path, encoding="utf-8") as fh:
            return yaml.safe_load(fh)
    except OSError as exc:
        raise ConfigError(f"cannot read configuration {path}: {exc.strerror}") from exc
    except yaml.YAMLError as exc:
        raise ConfigError(f"configuration {path} is not valid YAML: {exc}") from exc


def load_scenario(path=None) -> Scenario:
    """Read a scenario YAML file; ``None`` gives the embedded default scenario."""
    return Scenario() if path is None else scenario_from_dict(read_yaml(path))


__all__ = ["ConfigError", "Scenario", "load_scenario", "read_yaml", "scenario_from_dict"]
