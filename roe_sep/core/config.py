"""Scenario configuration: YAML/dict -> validated dataclasses, every bad key or value named in the error.

The embedded defaults are the dataclass defaults (the BIROS/picosatellite case of seeds 000/002); a file only
overrides what it names. Layout::

    separation: {altitude: 515000.0, u1_deg: 88.0, ...}        # SeparationConfig fields
    monte_carlo: {samples: 100000, seed: 0, p_values: [...], carrier: {cd: 2.3, area: 0.48, mass: 140.0}, ...}
    contingency: {name: spl_weak, spl_fraction: [0.0, 0.5]}   # optional: roe_sep.core.truth.contingency
    earth: {eop_file: finals2000A.all}                     # optional: IERS EOP file (roe_sep.core.frames)
"""

import dataclasses
import math
import types
import typing
from collections.abc import Callable
from dataclasses import dataclass, field
from os import PathLike

from ..checks import SEED_MAX, check_number, one_line
from ..errors import ConfigError, EopError, show
from .constants import SECONDS_PER_DAY
from .frames import use_eop_file
from .montecarlo.sweep import DEFAULT_P_VALUES, MonteCarloConfig, Spacecraft
from .separation.double_impulse import SeparationConfig
from .truth.contingency import ContingencyConfig, contingency_from_dict

# The range of every numeric key: (class, field) -> (lo, hi, lo_open, hi_open, unit). Physical limits or the domain
# of the models (LEO circular carrier, close formation); a value outside is refused with the key, value and range.
RANGES = {
    (SeparationConfig, "altitude"): (150e3, 2000e3, False, False, "m"),
    (SeparationConfig, "inclination_deg"): (0.0, 180.0, True, True, "deg"),
    (SeparationConfig, "u1_deg"): (-360.0, 360.0, False, False, "deg"),
    (SeparationConfig, "spl_dv"): (0.0, 10.0, True, False, "m/s"),
    (SeparationConfig, "a_de_f"): (0.0, 1e5, True, False, "m"),
    (SeparationConfig, "a_di_f"): (0.0, 1e5, True, False, "m"),
    (SeparationConfig, "k"): (1, 99, False, False, "(odd)"),
    (SeparationConfig, "eta_deg"): (-360.0, 360.0, False, False, "deg"),
    (SeparationConfig, "spl_sigma"): (0.0, 1.0, False, True, "(fraction of |dv|)"),
    (SeparationConfig, "thruster_sigma"): (0.0, 1.0, False, True, "(fraction of |dv|)"),
    (SeparationConfig, "p_sigma_level"): (0.0, 10.0, False, False, "sigma"),
    (SeparationConfig, "a_dl_min"): (0.0, 1e7, True, False, "m"),
    (SeparationConfig, "a_dl_max"): (0.0, 1e7, True, False, "m"),
    (SeparationConfig, "min_rn_distance"): (0.0, 1e5, False, False, "m"),
    (SeparationConfig, "fov_half_r_deg"): (0.0, 90.0, True, True, "deg"),
    (SeparationConfig, "fov_half_n_deg"): (0.0, 90.0, True, True, "deg"),
    (MonteCarloConfig, "samples"): (1, 10_000_000, False, False, ""),
    (MonteCarloConfig, "seed"): (0, SEED_MAX, False, False, ""),
    (MonteCarloConfig, "attitude_sigma_arcsec"): (0.0, 36000.0, False, False, "arcsec"),
    (MonteCarloConfig, "ballistic_sigma"): (0.0, 10.0, False, False, "(relative)"),
    (MonteCarloConfig, "density"): (0.0, 1e-6, False, False, "kg/m^3"),
    (MonteCarloConfig, "horizon"): (0.0, 30 * SECONDS_PER_DAY, True, False, "s"),
    (MonteCarloConfig, "evaporation_distance"): (0.0, 1e8, True, False, "m"),
    (Spacecraft, "cd"): (0.0, 10.0, True, False, ""),
    (Spacecraft, "area"): (0.0, 1e3, True, False, "m^2"),
    (Spacecraft, "mass"): (0.0, 1e6, True, False, "kg"),
}
SECTIONS = ("separation", "monte_carlo", "contingency", "earth")
P_RANGE = (0.0, 1.0)  # m/s, drift-stop reductions |p| (as `roe-sep mc --p`)


@dataclass(frozen=True)
class EarthConfig:
    """The Earth orientation's data: ``eop_file`` an IERS EOP file in the finals2000A format (None: the one shipped
    by astropy-iers-data, or ``$ROE_SEP_EOP_FILE``); loading the scenario makes :mod:`roe_sep.core.frames` use it."""

    eop_file: str | None = None


@dataclass(frozen=True)
class Scenario:
    """Everything the CLI and the nodes need for one separation scenario."""

    separation: SeparationConfig = field(default_factory=SeparationConfig)
    monte_carlo: MonteCarloConfig = field(default_factory=MonteCarloConfig)
    p_values: tuple = DEFAULT_P_VALUES
    # the run's contingency, None: nominal. Not in the repr: a scenario without one hashes as before
    # (a campaign directory's settings, roe_sep.campaign.settings, add it when set)
    contingency: ContingencyConfig | None = field(default=None, repr=False)
    # the EOP file; not in the repr either (the default scenario hashes as before)
    earth: EarthConfig = field(default_factory=EarthConfig, repr=False)


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
            raise ConfigError(f"{path}: expected true/false, got {show(value)}")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{path}: expected an integer, got {show(value)}")
        return value
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{path}: expected a number, got {show(value)}")
        if not math.isfinite(value):
            raise ConfigError(f"{path}: expected a finite number, got {show(value)}")
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
    for k, v in kwargs.items():
        if (cls, k) in RANGES and v is not None and not dataclasses.is_dataclass(v):
            lo, hi, lo_open, hi_open, unit = RANGES[(cls, k)]
            try:
                check_number(f"{path}.{k}", v, lo, hi, lo_open=lo_open, hi_open=hi_open, integer=hints[k] is not float
                             and isinstance(lo, int), unit=unit)
            except ValueError as exc:
                raise ConfigError(str(exc)) from None
    return cls(**kwargs)


def scenario_from_dict(data: dict | None) -> Scenario:
    """Build a :class:`Scenario` from a parsed YAML mapping (``None`` or ``{}`` gives the defaults)."""
    data = {} if data is None else data
    if not isinstance(data, dict):
        raise ConfigError(f"configuration: expected a mapping at the top level, got {type(data).__name__}")
    unknown = sorted(set(data) - set(SECTIONS))
    if unknown:
        raise ConfigError(f"configuration: unknown section(s) {unknown}; known: {list(SECTIONS)}")
    mc = dict(data.get("monte_carlo") or {})
    p_values = mc.pop("p_values", DEFAULT_P_VALUES)
    if not isinstance(p_values, (list, tuple)) or not p_values:
        raise ConfigError(f"monte_carlo.p_values: expected a non-empty list of numbers [m/s], got {show(p_values)}")
    p_values = tuple(_coerce(f"monte_carlo.p_values[{i}]", p, float) for i, p in enumerate(p_values))
    if any(not P_RANGE[0] <= p <= P_RANGE[1] for p in p_values):
        raise ConfigError(f"monte_carlo.p_values: reductions |p| must be non-negative and at most {P_RANGE[1]:g} m/s, "
                          f"got {list(p_values)}")
    earth = _build("earth", EarthConfig, data.get("earth"))
    if earth.eop_file is not None:
        if not isinstance(earth.eop_file, str) or not earth.eop_file.strip():
            raise ConfigError(f"earth.eop_file: expected the path of a finals2000A file, got {show(earth.eop_file)}")
        try:
            use_eop_file(earth.eop_file)
        except EopError as exc:
            raise ConfigError(f"earth.eop_file: {exc}") from None
    return Scenario(
        earth=earth,
        separation=_build("separation", SeparationConfig, data.get("separation")),
        monte_carlo=_build("monte_carlo", MonteCarloConfig, mc),
        p_values=p_values,
        contingency=contingency_from_dict(data.get("contingency")),
    )


def read_yaml(path: str | PathLike) -> object:
    """The parsed content of a YAML configuration file (a mapping, a list, a scalar or None for an empty file);
    unreadable or invalid files raise :class:`ConfigError`."""
    import yaml

    try:
        with open(path, encoding="utf-8") as fh:
            return yaml.safe_load(fh)
    except OSError as exc:
        raise ConfigError(f"cannot read configuration {path}: {exc.strerror}") from exc
    except UnicodeDecodeError as exc:
        raise ConfigError(f"configuration {path} is not UTF-8 text (byte {exc.start})") from exc
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        what = getattr(exc, "problem", None) or one_line(exc)
        raise ConfigError(f"configuration {path} is not valid YAML{where}: {what}") from exc


def load_yaml_config(path: str | PathLike, build: Callable[[object], typing.Any],
                     what: str = "configuration") -> typing.Any:
    """``build(read_yaml(path))``; a :class:`ConfigError` of ``build`` gets the file's name in front
    (``configuration FILE: separation.spl_dv: expected ...``).

    Parameters
    ----------
    path : str or os.PathLike
        The YAML file.
    build : callable
        Parsed YAML -> the configuration object; raises :class:`ConfigError` naming the key.
    what : str
        What the file is, in front of its name in a message.

    Returns
    -------
    object
        What ``build`` returns.
    """
    data = read_yaml(path)
    try:
        return build(data)
    except ConfigError as exc:
        raise ConfigError(f"{what} {path}: {exc}") from None


def load_scenario(path: str | PathLike | None = None) -> Scenario:
    """Read a scenario YAML file; ``None`` gives the embedded default scenario."""
    return Scenario() if path is None else load_yaml_config(path, scenario_from_dict)


__all__ = ["ConfigError", "EarthConfig", "Scenario", "load_scenario", "load_yaml_config", "read_yaml",
           "scenario_from_dict"]
