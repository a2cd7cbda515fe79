"""``roe-sep ops``: the operational plan of the separation day (seed 001 Sec. 5)."""

import argparse
import sys
from pathlib import Path

from .common import emit


def _date(text):
    import datetime

    try:
        return datetime.date.fromisoformat(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--date expects YYYY-MM-DD, got {text!r}") from None

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
    p.add_argument("--days", type=float, default=2.0, help="length of the plan [days] (default 2)")
    p.add_argument("--plot", metavar="PNG", help="write the timeline figure (like seed 001 Fig. 7)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_ops)
