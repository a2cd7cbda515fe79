"""``roe-sep ops``: the operational plan of the separation day (seed 001 Sec. 5)."""

import argparse
import sys
from pathlib import Path

from .common import emit, finite_float


def _span():
    import datetime

    # DE421 covers 1899-07-29 .. 2053-10-09; the plan needs up to 7 days after the date
    return datetime.date(1900, 1, 1), datetime.date(2053, 9, 30)


EPHEMERIS_SPAN = _span()


def _date(text):
    import datetime

    first, last = EPHEMERIS_SPAN
    try:
        day = datetime.date.fromisoformat(text)
    except ValueError:
        day = None
    if day is None or not first <= day <= last:
        raise argparse.ArgumentTypeError(f"expected a date YYYY-MM-DD from {first} to {last} (the DE421 ephemeris), "
                                         f"got {text!r}")
    return day

def cmd_ops(args):
    from ..core.ops import plan as ops

    cfg = ops.load_ops_config(args.ops_config)
    if args.tle:
        cfg = ops.with_tle(cfg, args.tle)
    rep = ops.plan(cfg, args.date, days=args.days)
    if args.plot:
        from ..plots.ops import fig_timeline

        fig_timeline(rep, Path(args.plot))
        rep["figure"] = args.plot
    emit(rep, args.json, lambda r: ops.print_plan(r, sys.stdout))

def register(subparsers):
    """Add ``ops`` to the ``roe-sep`` subparsers."""
    p = subparsers.add_parser("ops", help="operational plan of the separation day (seed 001 Sec. 5)")
    p.add_argument("--date", required=True, type=_date, help="separation date YYYY-MM-DD (UTC)")
    p.add_argument("--tle", help="carrier TLE file (2 or 3 lines); default: mean elements of config/ops.yaml")
    p.add_argument("--ops-config", help="stations/radar/camera/orbit YAML (default: config/ops.yaml)")
    p.add_argument("--days", type=finite_float(0.0, 7.0, lo_open=True, unit="days"), default=2.0,
                   help="length of the plan [days] in (0, 7] (default 2)")
    p.add_argument("--plot", metavar="PNG", help="write the timeline figure (like seed 001 Fig. 7)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_ops)
