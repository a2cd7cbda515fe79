"""Checks of user input, shared by every command line of roe_sep and its configuration files.

One message format everywhere: the option or key, what is allowed, the value given --
``argument --spl-dv: expected a finite number in (0, 10] m/s, got 'nan'`` -- on one line, exit status 2.

* :func:`check_number`: a value already parsed (YAML key, cross-check of two options) -> ValueError.
* :func:`finite_float`, :func:`integer`, :func:`number_list`: argparse ``type=`` functions for a named range.
* :class:`OneLineParser`: an ``argparse.ArgumentParser`` whose usage errors are one line (``prog: error: ...``)
  instead of the usage block + error, so scripts can log them as a single line.

Beside the core (imports only :mod:`roe_sep.errors`): used by :mod:`roe_sep.cli.common` (which re-exports it),
:mod:`roe_sep.bag.replay` and :mod:`roe_sep.bag.recover` (which parse their own arguments) and the configuration
loaders of the core.
"""

import argparse
import math
import sys

from .errors import show

SEED_MAX = 2**32 - 1  # every seed of the project: numpy accepts larger, but one range keeps them reproducible


def describe_range(lo=None, hi=None, lo_open=False, hi_open=False, integer=False, *, unit="") -> str:
    """``'a finite number in (0, 10] m/s'``, ``'an integer in [1, 10000000]'``, ``'a finite number >= 0 s'``."""
    kind = "an integer" if integer else "a finite number"

    def fmt(v):
        return f"{v:d}" if integer else f"{v:g}"

    if lo is not None and hi is not None:
        text = f"{kind} in {'(' if lo_open else '['}{fmt(lo)}, {fmt(hi)}{')' if hi_open else ']'}"
    elif lo is not None:
        text = f"{kind} {'>' if lo_open else '>='} {fmt(lo)}"
    elif hi is not None:
        text = f"{kind} {'<' if hi_open else '<='} {fmt(hi)}"
    else:
        text = kind
    return f"{text} {unit}".rstrip()


def in_range(value, lo=None, hi=None, lo_open=False, hi_open=False) -> bool:
    """``value`` is a finite real number inside the (half-)open/closed range."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        try:
            value = float(value)
        except (TypeError, ValueError):
            return False
    if not math.isfinite(value):
        return False
    if lo is not None and (value <= lo if lo_open else value < lo):
        return False
    if hi is not None and (value >= hi if hi_open else value > hi):
        return False
    return True


def check_number(name, value, lo=None, hi=None, *, lo_open=False, hi_open=False, integer=False, unit=""):
    """``value`` if it is a finite number (an int when ``integer``) in range, else ValueError naming ``name``."""
    allowed = describe_range(lo, hi, lo_open, hi_open, integer, unit=unit)
    ok = not isinstance(value, bool) and isinstance(value, int if integer else (int, float))
    if not (ok and in_range(value, lo, hi, lo_open, hi_open)):
        raise ValueError(f"{name}: expected {allowed}, got {show(value)}")
    return int(value) if integer else float(value)


def _parse_float(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def finite_float(lo=None, hi=None, *, lo_open=False, hi_open=False, unit=""):
    """argparse ``type=``: a finite float in range (argparse prefixes the option name)."""
    allowed = describe_range(lo, hi, lo_open, hi_open, False, unit=unit)

    def parse(text):
        value = _parse_float(text)
        if value is None or not in_range(value, lo, hi, lo_open, hi_open):
            raise argparse.ArgumentTypeError(f"expected {allowed}, got {text!r}")
        return value

    parse.__name__ = "finite_float"
    return parse


def integer(lo=None, hi=None, *, unit=""):
    """argparse ``type=``: an integer in [lo, hi] (``'1e3'``, ``'2.0'`` and ``'nan'`` are refused)."""
    allowed = describe_range(lo, hi, integer=True, unit=unit)

    def parse(text):
        try:
            value = int(text, 10)
        except (TypeError, ValueError):
            value = None
        if value is None or not in_range(value, lo, hi):
            raise argparse.ArgumentTypeError(f"expected {allowed}, got {text!r}")
        return value

    parse.__name__ = "integer"
    return parse


def seed():
    """argparse ``type=`` of every ``--seed``: an integer in [0, 2**32 - 1]."""
    return integer(0, SEED_MAX)


def number_list(lo=None, hi=None, *, lo_open=False, hi_open=False, unit="", length=None, integer_values=False,
                max_items=10_000):
    """argparse ``type=``: comma-separated numbers, each in range; ``length`` fixes how many; returns a tuple."""
    each = describe_range(lo, hi, lo_open, hi_open, integer_values, unit=unit)
    count = f"{length} comma-separated" if length else "comma-separated"
    allowed = f"{count} values, each {each}"

    def parse(text):
        items = [x.strip() for x in str(text).split(",")]
        if items and items[-1] == "" and len(items) > 1:  # one trailing comma is harmless
            items = items[:-1]
        values = []
        for x in items:
            if integer_values:
                try:
                    v = int(x, 10)
                except ValueError:
                    v = None
            else:
                v = _parse_float(x)
            if v is None or not in_range(v, lo, hi, lo_open, hi_open):
                raise argparse.ArgumentTypeError(f"expected {allowed}, got {text!r}")
            values.append(v)
        if not values or (length and len(values) != length) or len(values) > max_items:
            raise argparse.ArgumentTypeError(f"expected {allowed}, got {text!r}")
        return tuple(values)

    parse.__name__ = "number_list"
    return parse


def one_line(text) -> str:
    """A message on one line (YAML and library errors span several): line breaks become '; '."""
    return "; ".join(part.strip() for part in str(text).splitlines() if part.strip())


class OneLineParser(argparse.ArgumentParser):
    """argparse with one-line usage errors: ``prog: error: message (see prog --help)``, exit status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {one_line(message)} (see {self.prog} --help)\n")

    def exit(self, status=0, message=None):
        if message:
            sys.stderr.write(message)
        raise SystemExit(status)


__all__ = ["OneLineParser", "SEED_MAX", "check_number", "describe_range", "finite_float", "in_range", "integer",
           "number_list", "one_line", "seed"]
