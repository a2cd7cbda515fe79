"""What every ``roe-sep`` subcommand shares: its output (strict JSON with ``--json`` for ground-segment scripts, else
the human table followed by the figures written) and the parsers of option values.

Every numeric option is parsed by a ``type=`` function of :mod:`roe_sep.checks` (re-exported here) that checks the
value is finite and in its range and says so on one line: ``argument --spl-dv: expected a finite number in (0, 10]
m/s, got 'nan'`` (exit status 2, see :class:`~roe_sep.checks.OneLineParser`).
"""

import sys

from .. import jsonutil
from ..checks import (  # noqa: F401  (re-exported: the option parsers of every command group)
    SEED_MAX,
    OneLineParser,
    check_number,
    finite_float,
    integer,
    number_list,
    one_line,
    seed,
)

SAMPLES_MAX = 10_000_000  # Monte Carlo samples: ~2 GB of float64 state at the largest


def emit(rep, as_json, human, why=None):
    """Write ``rep`` as strict JSON (non-finite numbers -> null, explained in ``null_reasons``; ``why`` maps paths or
    key names to the explanation) or through ``human(rep)``; list ``rep["figures"]`` after the human table."""
    if as_json:
        jsonutil.dump(rep, sys.stdout, why=why)
        return
    human(rep)
    for f in rep.get("figures", []):
        print(f"  figure: {f}")


def vec(v):
    """A vector as ``[+x.xxxxxx +y.yyyyyy ...]`` (the tables' format of impulses)."""
    return "[" + " ".join(f"{x:+.6f}" for x in v) + "]"


# drift-stop reductions |p| [m/s]: beyond 1 m/s a reduction exceeds any drift-stop burn of the design (|dvT2| is
# 0.16 m/s for the default case, seed 002 Eq. 21)
p_list = number_list(0.0, 1.0, unit="m/s")
positive_int = integer(1)
nonneg_int = integer(0)
samples = integer(1, SAMPLES_MAX)


def float_list(lo=None, hi=None, **kw):
    """Comma-separated finite numbers in a range (see :func:`roe_sep.checks.number_list`)."""
    return number_list(lo, hi, **kw)
