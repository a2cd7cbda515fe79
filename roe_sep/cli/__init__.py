"""``roe-sep``: the command line of roe_sep. Human tables by default, ``--json`` for ground-segment scripts.

One module per command group, each with a ``register(subparsers)``: :mod:`.design` (``design``, ``mc``), :mod:`.ops`
(``ops``), :mod:`.run` (``run``, ``replay``, ``bag``), :mod:`.nonlinear` (``propagate``, ``validate``) and
:mod:`.analysis` (``deploy-sweep``, ``cluster``), :mod:`.collision` (``collision``), :mod:`.export` (``export``:
CCSDS navigation data messages of a bag), :mod:`.od` (``od``: the relative OD offline from TDM files),
:mod:`.campaign` (``campaign``); :mod:`.common` holds the output and the
option parsers they share.
``python -m roe_sep.cli`` is the same as ``roe-sep``.
"""

import os
import sys

from ..checks import OneLineParser, one_line
from ..children import exit_status
from ..errors import RoeSepError
from . import analysis, campaign, collision, design, export, nonlinear, od, ops, run

EXIT_BAD_INPUT = 2  # bad option, bad file, infeasible design: the one-line message names it
EXIT_INTERNAL = 3  # an exception nobody expected: a bug, reported on one line (ROE_SEP_DEBUG=1: the traceback)


def build_parser():
    parser = OneLineParser(prog="roe-sep", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    design.register(sub)
    ops.register(sub)
    run.register_run(sub)
    nonlinear.register(sub)
    analysis.register(sub)
    run.register_bag(sub)
    collision.register(sub)
    export.register(sub)
    od.register(sub)
    campaign.register(sub)
    return parser


def _os_error(exc: OSError) -> str:
    where = f"{exc.filename}: " if exc.filename else ""
    return f"{where}{exc.strerror or exc}"


def main(argv=None):
    """``roe-sep``: exit 0 on success, 1 when the result is negative (unsafe run, infeasible cluster program, damaged
    bag), 2 on bad input (one line naming the option, the value and what is allowed), 3 on an internal error."""
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        delegated = run.delegated(argv)
        if delegated is not None:
            return delegated
        args = build_parser().parse_args(argv)
        code = args.func(args)
    except (RoeSepError, ValueError) as exc:  # roe_sep.errors, and a bare ValueError of an argument check
        print(f"roe-sep: error: {one_line(exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except BrokenPipeError:  # e.g. `roe-sep mc --json | head`
        sys.stderr.close()
        return 0
    except OSError as exc:  # a file that cannot be read or written (--plots, --out, --config ...)
        print(f"roe-sep: error: {one_line(_os_error(exc))}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt as exc:  # Ctrl-C; SIGTERM/SIGHUP too under children.guarded() (run, replay, campaign)
        print("roe-sep: interrupted", file=sys.stderr)
        return exit_status(exc)
    except Exception as exc:  # noqa: BLE001  (last resort: one line, never a traceback on the terminal)
        if os.environ.get("ROE_SEP_DEBUG"):
            raise
        print(f"roe-sep: internal error: {type(exc).__name__}: {one_line(exc)} (a bug; rerun with ROE_SEP_DEBUG=1 "
              "for the traceback)", file=sys.stderr)
        return EXIT_INTERNAL
    return code or 0


def entry():
    """The ``roe-sep`` command: :func:`main`, then the process ends without the C-level teardown once ROS is shut
    down (:func:`roe_sep.process_exit.exit_process`: ``roe-sep run`` does not wait 0.1 s for Fast DDS at its end)."""
    from ..process_exit import exit_process

    exit_process(main())
