"""``roe-sep``: the command line of roe_sep. Human tables by default, ``--json`` for ground-segment scripts.

One module per command group, each with a ``register(subparsers)``: :mod:`.design` (``design``, ``mc``), :mod:`.ops`
(``ops``), :mod:`.run` (``run``, ``replay``, ``bag``), :mod:`.nonlinear` (``propagate``, ``validate``) and
:mod:`.analysis` (``deploy-sweep``, ``cluster``), :mod:`.collision` (``collision``); :mod:`.common` holds the output
and the option parsers they share.
``python -m roe_sep.cli`` is the same as ``roe-sep``.
"""

import argparse
import sys

from ..core.config import ConfigError
from ..core.separation.double_impulse import InfeasibleDesignError
from . import analysis, collision, design, nonlinear, ops, run


def build_parser():
    parser = argparse.ArgumentParser(prog="roe-sep", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    design.register(sub)
    ops.register(sub)
    run.register_run(sub)
    nonlinear.register(sub)
    analysis.register(sub)
    run.register_bag(sub)
    collision.register(sub)
    return parser


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    delegated = run.delegated(argv)
    if delegated is not None:
        return delegated
    args = build_parser().parse_args(argv)
    try:
        code = args.func(args)
    except (ConfigError, InfeasibleDesignError, ValueError, FileNotFoundError) as exc:
        print(f"roe-sep: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # e.g. `roe-sep mc --json | head`
        sys.stderr.close()
        return 0
    return code or 0

