"""Benchmark of ``roe-sep campaign``: the same N closed-loop runs (seeds S..S+N-1, default scenario, 3.25 days of sim
time each) on an embedded Dask cluster of 1 worker and of 2 workers, side by side in one process: wall time,
runs/hour, the speed-up, the extrapolation to 100 runs, and whether both campaigns wrote the same rows (they must:
a run's result depends on its seed only, not on the worker count or the load).

    nice -n 10 python bench/bench_campaign.py --runs 6 --domains 62-99 [--duration S] [--json]
"""

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

from roe_sep import jsonutil
from roe_sep.campaign import run_campaign
from roe_sep.campaign.table import RUN_FIELDS, Table, format_row
from roe_sep.cli.campaign import domain_range


def campaign(workers, runs, seed, duration, domains, root):
    out = root / f"w{workers}"
    t0 = time.perf_counter()
    rep = run_campaign(runs, seed, out, workers=workers, duration=duration, domains=domains, figures=False,
                       open_loop_samples=1000)
    wall = time.perf_counter() - t0
    rows = Table(out / "runs.csv").read()
    return {"workers": workers, "runs": runs, "wall_s": wall, "runs_per_hour": runs / wall * 3600.0,
            "wall_s_per_run_in_worker": rep["wall_s_per_run"], "completed": rep["completed"],
            "failed": rep["failed"], "p_safe": rep["p_safe"]["p"],
            "extrapolated_100_runs_h": 100.0 / (runs / wall * 3600.0)}, rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=6)
    ap.add_argument("--seed", type=int, default=1000)
    ap.add_argument("--duration", type=float, default=None, help="sim s per run (default: the scenario's 3.25 d)")
    ap.add_argument("--workers", default="1,2", help="comma-separated worker counts (default 1,2)")
    ap.add_argument("--domains", type=domain_range, default=(62, 99))
    ap.add_argument("--keep", help="keep the campaign directories here (default: a temporary directory)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    root = Path(args.keep or tempfile.mkdtemp(prefix="bench_campaign_"))
    results, tables = [], []
    try:
        for w in (int(x) for x in args.workers.split(",")):
            res, rows = campaign(w, args.runs, args.seed, args.duration, args.domains, root)
            results.append(res)
            tables.append({s: format_row({k: v for k, v in r.items() if k not in RUN_FIELDS})
                           for s, r in rows.items()})
            if not args.json:
                print(f"  {w} worker(s): {args.runs} runs in {res['wall_s']:7.1f} s = {res['runs_per_hour']:6.1f} "
                      f"runs/h ({res['wall_s_per_run_in_worker']:.1f} s per run in its worker, {res['failed']} "
                      f"failed); 100 runs ~ {res['extrapolated_100_runs_h']:.2f} h", flush=True)
    finally:
        if not args.keep:
            shutil.rmtree(root, ignore_errors=True)
    same = all(t == tables[0] for t in tables[1:])
    summary = {"runs": args.runs, "duration": args.duration, "results": results, "rows_identical": same,
               "speedup": results[-1]["runs_per_hour"] / results[0]["runs_per_hour"] if len(results) > 1 else None}
    if args.json:
        jsonutil.dump(summary, sys.stdout)
    else:
        if summary["speedup"] is not None:
            print(f"  speed-up {results[-1]['workers']} vs {results[0]['workers']} worker(s): "
                  f"{summary['speedup']:.2f}x; rows identical across worker counts: {same}")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
