"""The planner's start-up sweep stored on disk between processes: file I/O kept out of the pure core
(:mod:`roe_sep.core.montecarlo.sweep` computes, this module stores). No rclpy."""

import functools
import hashlib
import json
import os
from pathlib import Path

import numpy as np

from ..core.montecarlo.sweep import MonteCarloConfig, p_best
from ..core.separation.double_impulse import SeparationConfig


def cache_dir():
    """Where the start-up sweep's result is stored between processes: ``ROE_SEP_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/roe_sep`` (``~/.cache/roe_sep``); None (not stored) when ``ROE_SEP_CACHE_DIR`` is ``off``."""
    env = os.environ.get("ROE_SEP_CACHE_DIR")
    if env:
        return None if env == "off" else env
    return os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "roe_sep")


@functools.lru_cache(maxsize=1)
def code_version() -> str:
    """A digest of the core's source (every ``roe_sep/core`` module) and NumPy's version: what :func:`p_best`'s value
    depends on besides its arguments."""
    h = hashlib.sha256(np.__version__.encode())
    root = Path(__file__).resolve().parents[1] / "core"
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()


@functools.lru_cache(maxsize=8)
def p_best_stored(separation: SeparationConfig, mc: MonteCarloConfig, p_values: tuple[float, ...],
                  directory: str) -> float:
    """:func:`p_best`, stored on disk in ``directory`` (one small JSON file per key) so that a fresh process (a cold
    ``roe-sep run``) does not repeat the identical sweep. The key is a SHA-256 of the arguments' exact ``repr``
    (floats round-trip) and :func:`code_version`: a changed input or core module computes anew. A missing,
    unreadable or foreign file is computed and (atomically) rewritten; a directory that cannot be written costs
    only the sweep.

    Parameters
    ----------
    separation, mc, p_values
        As for :func:`~roe_sep.core.montecarlo.sweep.p_best`.
    directory : str
        Directory of the stored values (created when missing).

    Returns
    -------
    float
        The reduction |p| [m/s] of least risk, the same float as :func:`~roe_sep.core.montecarlo.sweep.p_best`.
    """
    key = hashlib.sha256(repr((separation, mc, tuple(float(p) for p in p_values), code_version())).encode())
    key = key.hexdigest()
    path = Path(directory) / f"p_best_{key[:40]}.json"
    try:
        stored = json.loads(path.read_text(encoding="utf-8"))
        if stored.get("key") == key and isinstance(stored.get("p_best"), float):
            return stored["p_best"]
    except (OSError, ValueError, AttributeError):
        pass
    value = p_best(separation, mc, p_values)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps({"key": key, "p_best": value}), encoding="utf-8")
        os.replace(tmp, path)
    except OSError:
        pass
    return value
