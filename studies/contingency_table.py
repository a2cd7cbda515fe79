"""Study: the contingency table and its figures from the contingency campaigns (docs/contingencies.md).

Each case is one campaign directory of ``roe-sep campaign --contingency NAME --runs 100 --seed 1000 --workers 2``
(bags kept: the figures need each run's ``/sim/truth/rtn``), the nominal campaign of the same seeds beside them.
Writes the table as Markdown and strict JSON (:mod:`roe_sep.campaign.contingency_table`) and one figure per
campaign: the distance between the spacecraft against time since the ejection, every run
(:func:`roe_sep.plots.campaign.fig_distance_vs_time`), the runs in which the ground saw the contingency grey and
the others red (for the nominal case: red where a criterion failed).

    python studies/contingency_table.py --case "nominal=/tmp/cont/nominal" \\
        --case "spl_weak, hold=/tmp/cont/spl_weak" ... --md docs/contingency_table.md \\
        --json bench/results/contingency_table.json --figures docs/figures/contingencies

``--from-json FILE`` instead of the cases re-renders the tables from recorded rows (a row recorded before a column
shows "n/a" there): ``python studies/contingency_table.py --from-json bench/results/contingency_table.json
--md bench/results/contingency_table.md --compact-md bench/results/contingency_table_compact.md``.
"""

import argparse
import json
import math
import re
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from roe_sep import interfaces  # noqa: E402
from roe_sep.campaign.contingency_table import (  # noqa: E402
    EXPECTED_DETECTIONS,
    compact_markdown,
    markdown,
    summarize,
)
from roe_sep.campaign.table import Table  # noqa: E402
from roe_sep.core.safety.approach import COLLISION_RADIUS  # noqa: E402
from roe_sep.core.safety.monitor import MonitorLimits  # noqa: E402
from roe_sep.plots.campaign import fig_distance_grid, fig_distance_vs_time  # noqa: E402
from roe_sep.report import read_topics  # noqa: E402
from roe_sep.stamps import time_to_sec  # noqa: E402

STEP_S = 300.0
"""s, the figures' sampling of each run's distance (the truth topic is every 60 s; the closest approach of each run
is the simulator's, in the table)."""


def distance_series(bag, ejection_epoch):
    """(hours since the ejection, distance [m]) of a run's truth, every :data:`STEP_S`, from the ejection on."""
    msgs = read_topics(bag, [interfaces.TRUTH_RTN_TOPIC])[interfaces.TRUTH_RTN_TOPIC]
    t = np.array([time_to_sec(m.header.stamp) for _, m in msgs])
    d = np.array([math.hypot(m.position.x, m.position.y, m.position.z) for _, m in msgs])
    keep = t >= ejection_epoch
    t, d = t[keep], d[keep]
    if t.size:
        grid = np.arange(t[0], t[-1] + 1.0, STEP_S)
        idx = np.searchsorted(t, grid)
        idx = np.minimum(idx, t.size - 1)
        t, d = t[idx], d[idx]
    return (t - ejection_epoch) / 3600.0, d


def flagged(row, name):
    """Red in the figure: not seen by the ground (a contingency), or a failed criterion (nominal)."""
    if name is None:
        return not row["safe"]
    found = json.loads(row["contingencies_detected"] or "{}")
    return not any(k in found for k in EXPECTED_DETECTIONS.get(name, ()))


def write_tables(summaries, md, compact_md):
    """The Markdown table and the README's short one of the rows, where asked."""
    if md:
        md.write_text(markdown(summaries), encoding="utf-8")
    if compact_md:
        compact_md.write_text(compact_markdown(summaries), encoding="utf-8")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--case", action="append", metavar="LABEL=DIR",
                   help="a campaign directory and its label in the table (repeat; in table order)")
    p.add_argument("--md", type=Path, help="write the Markdown table here")
    p.add_argument("--compact-md", type=Path, help="write the README's short table here")
    p.add_argument("--json", type=Path, help="write the rows as strict JSON here")
    p.add_argument("--figures", type=Path, help="write one distance-vs-time figure per case into this directory")
    p.add_argument("--grid", type=Path, help="write the cases' figures as the panels of one figure here")
    p.add_argument("--from-json", type=Path, help="re-render the tables from these recorded rows (no campaign)")
    p.add_argument("--collision-radius", type=float, default=COLLISION_RADIUS,
                   help="m, a collision: the truth's closest approach below it (default: the bodies', %(default).3f)")
    args = p.parse_args(argv)
    if args.from_json:
        if args.case:
            p.error("--from-json or --case, not both")
        write_tables(json.loads(args.from_json.read_text(encoding="utf-8")), args.md, args.compact_md)
        return
    if not args.case:
        p.error("--case is required (or --from-json)")
    summaries, panels = [], []
    keep_out = MonitorLimits().keep_out
    for case in args.case:
        label, _, directory = case.partition("=")
        rows = Table(Path(directory) / "runs.csv").read()
        if not rows:
            p.error(f"{directory}: no runs.csv rows")
        s = summarize(rows, label, args.collision_radius)
        summaries.append(s)
        if args.figures or args.grid:
            series = []
            for seed, row in sorted(rows.items()):
                bag = Path(directory) / "runs" / str(seed) / "bag"
                if row["status"] != "ok" or not bag.exists() or row["ejection_epoch_s"] is None:
                    continue
                t_h, d = distance_series(bag, row["ejection_epoch_s"])
                rep = json.loads((Path(directory) / "runs" / str(seed) / "report.json").read_text(encoding="utf-8"))
                t_min = (None if rep["min_distance_epoch"] is None
                         else (rep["min_distance_epoch"] - row["ejection_epoch_s"]) / 3600.0)
                closest = (t_min, rep["min_distance"] if t_min is not None else None)
                series.append((t_h, d, flagged(row, s["contingency"]), closest))
            split = ("safe", "unsafe") if s["contingency"] is None else ("seen by the ground", "not seen")
            panels.append((label, series, split))
            if args.figures:
                args.figures.mkdir(parents=True, exist_ok=True)
                slug = re.sub(r"[^a-z0-9]+", "_", label.lower()).strip("_")
                s["figure"] = str(args.figures / f"{slug}.png")
                fig_distance_vs_time(series, s["figure"], label, keep_out, split)
        print(f"{label}: {s['completed']} runs", file=sys.stderr)
    if args.grid:
        fig_distance_grid(panels, args.grid, keep_out)
    write_tables(summaries, args.md, args.compact_md)
    text = json.dumps(summaries, indent=1, allow_nan=False)
    if args.json:
        args.json.write_text(text + "\n", encoding="utf-8")
    else:
        print(text)


if __name__ == "__main__":
    main()
