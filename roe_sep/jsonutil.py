"""Strict JSON for every file and every ``--json`` output of roe_sep (RFC 8259: no NaN, no Infinity).

Python's ``json`` writes ``NaN``/``Infinity`` by default, which strict parsers (JavaScript ``JSON.parse``, Go, jq
in strict mode, ``json.loads(..., parse_constant=...)``) refuse. :func:`strict_json` replaces every non-finite float
by ``null`` and records why under a top-level ``"null_reasons"`` mapping ``{JSON path: reason}``, e.g.
``{"rows[3].a_dl_horizon_mean": "NaN (no sample in the class)"}``; :func:`dumps`/:func:`dump` then write with
``allow_nan=False``, so a value that slips through is an error at the writer, never invalid JSON in a file.

Layer 0 (no roe_sep import): usable by the core, the runner (``report.json``) and the command line alike.
"""

import json
import math

import numpy as np

REASONS_KEY = "null_reasons"


def _reason(x: float, why) -> str:
    kind = "NaN" if math.isnan(x) else ("+Infinity" if x > 0 else "-Infinity")
    return f"{kind} ({why})" if why else f"{kind}: not a finite number"


def _path(parent: str, key) -> str:
    if isinstance(key, int):
        return f"{parent}[{key}]"
    return f"{parent}.{key}" if parent else str(key)


def strict_json(obj, reasons=None, why=None):
    """A copy of ``obj`` that strict JSON can hold: dicts, lists, str, int, finite float, bool, None.

    Non-finite floats become ``None`` with an entry ``{path: reason}`` in ``reasons`` (a dict, filled in place).
    ``why`` maps a path (exact, or a key name matching any path ending in it) to the explanation written for it.
    numpy scalars and arrays become Python numbers and lists; tuples and sets become lists; other objects are
    refused with TypeError (JSON would refuse them too). For a top-level dict, use :func:`with_null_reasons`.
    """
    reasons = {} if reasons is None else reasons
    why = why or {}

    def explain(path):
        if path in why:
            return why[path]
        leaf = path.rsplit(".", 1)[-1].split("[", 1)[0]
        return why.get(leaf)

    def walk(x, path):
        if isinstance(x, (bool, np.bool_)):
            return bool(x)
        if x is None or isinstance(x, str):
            return x
        if isinstance(x, (int, np.integer)):
            return int(x)
        if isinstance(x, (float, np.floating)):
            x = float(x)
            if math.isfinite(x):
                return x
            reasons[path or "$"] = _reason(x, explain(path))
            return None
        if isinstance(x, dict):
            return {str(k): walk(v, _path(path, str(k))) for k, v in x.items()}
        if isinstance(x, np.ndarray):
            x = x.tolist()
        if isinstance(x, (list, tuple, set, frozenset)):
            return [walk(v, _path(path, i)) for i, v in enumerate(x)]
        raise TypeError(f"{path or '$'}: {type(x).__name__} is not JSON serializable")

    return walk(obj, "")


def with_null_reasons(obj, why=None):
    """:func:`strict_json` of ``obj``; a dict gets ``"null_reasons": {path: reason}`` when something was nulled
    (merged with a ``null_reasons`` it already has)."""
    reasons = {}
    out = strict_json(obj, reasons, why)
    if reasons:
        if not isinstance(out, dict):
            raise ValueError(f"non-finite values at {sorted(reasons)} and no top-level object to explain them in")
        merged = dict(out.get(REASONS_KEY) or {})
        merged.update(reasons)
        out[REASONS_KEY] = merged
    return out


def dumps(obj, indent=2, why=None) -> str:
    """Strict JSON text of ``obj`` (non-finite floats -> null + ``null_reasons``; ``allow_nan=False``)."""
    return json.dumps(with_null_reasons(obj, why), indent=indent, allow_nan=False)


def dump(obj, fh, indent=2, why=None):
    """Write :func:`dumps` of ``obj`` and a newline to the text file ``fh``."""
    fh.write(dumps(obj, indent=indent, why=why) + "\n")


def _refuse_constant(name):
    raise ValueError(f"not strict JSON: {name}")


def loads_strict(text: str):
    """Parse JSON refusing NaN/Infinity/-Infinity (what a strict parser does)."""
    return json.loads(text, parse_constant=_refuse_constant)


__all__ = ["REASONS_KEY", "dump", "dumps", "loads_strict", "strict_json", "with_null_reasons"]
