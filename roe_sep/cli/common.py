"""What every ``roe-sep`` subcommand shares: its output (indented JSON with ``--json`` for ground-segment scripts,
else the human table followed by the figures written) and the parsers of common option values."""

import argparse
import json
import math
import sys


def emit(rep, as_json, human):
    """Write ``rep`` as JSON or through ``human(rep)``; list ``rep["figures"]`` after the human table."""
    if as_json:
        json.dump(rep, sys.stdout, indent=2)
        sys.stdout.write("\n")
        return
    human(rep)
    for f in rep.get("figures", []):
        print(f"  figure: {f}")


def vec(v):
    """A vector as ``[+x.xxxxxx +y.yyyyyy ...]`` (the tables' format of impulses)."""
    return "[" + " ".join(f"{x:+.6f}" for x in v) + "]"


def p_list(text):
    try:
        values = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"--p expects comma-separated numbers in m/s, got {text!r}") from None
    if not values or not all(math.isfinite(v) and v >= 0 for v in values):
        raise argparse.ArgumentTypeError(f"--p expects non-negative finite values in m/s, got {text!r}")
    return values


def positive_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def nonneg_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {text!r}")
    return value


def float_list(what):
    def parse(text):
        try:
            values = [float(x) for x in text.split(",") if x.strip()]
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what}: expected comma-separated numbers, got {text!r}") from None
        if not values or not all(math.isfinite(v) for v in values):
            raise argparse.ArgumentTypeError(f"{what}: expected finite numbers, got {text!r}")
        return tuple(values)

    return parse
