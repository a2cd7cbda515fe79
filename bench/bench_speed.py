"""Speed of a closed-loop run and of a small campaign, two versions of the code side by side in one run.

Each version is a git revision extracted to a temporary directory (``git archive``; the working tree itself for
``--new .``), run with its own ``PYTHONPATH`` in the same venv, alternately (base, new, base, new, ...) so that a
change of the machine's load hits both alike:

* ``roe-sep run --seed S`` (default layout, cold: a fresh interpreter per run), ``--repeat`` times each: the median
  wall time, the CPU time of the whole process tree (user + system of every process, from the children's rusage:
  each process is waited for by its parent) and the peak resident set of the tree (sum over the processes alive at
  one sample of ``/proc``, every 0.2 s: :mod:`proctree`);
* ``roe-sep campaign --runs N --workers W --no-bags --no-figures`` (``--campaign-runs 0``: none; ``--bags yes``
  keeps the bags, ``both`` runs both pairs): runs per hour by wall time, CPU-s per run over the tree (Dask's start-up
  included: a small campaign overstates it), peak RSS of the tree (the sum over its processes, and their
  proportional set, which counts the pages forked runs share with their server once: :func:`proctree.pss`);
* identity: every run's ``report.json`` without ``run`` (how the run went on this machine) and the campaign's
  ``runs.csv`` without its machine columns (:data:`roe_sep.campaign.table.RUN_FIELDS`) must be the same for both.

The planner's stored start-up sweep (``ROE_SEP_CACHE_DIR``) is filled once before the measurement for each version
(what a second cold run finds; its key has a digest of the core's source, so each version has its own). Each tree's
``roe_sep`` is byte-compiled first (``compileall``): an installed package, or a user's second run, imports compiled
modules, and a shell with ``PYTHONDONTWRITEBYTECODE`` would otherwise compile every module in every process.

    python bench/bench_speed.py --base 52bc6b4 --new . --repeat 5 --campaign-runs 100 --bags both \\
        --workers 2 --domains 31-39 --out bench/results/bench_speed.json
"""

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
import proctree  # noqa: E402

MACHINE_COLUMNS = ("wall_s", "domain_id")  # roe_sep.campaign.table.RUN_FIELDS (not imported: either version's)


def extract(rev, into):
    """The tree of ``rev`` in ``into`` (``.``: the working tree itself); returns the directory."""
    if rev == ".":
        return ROOT
    into.mkdir(parents=True)
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive, check=True)
    return into


def measured(cmd, env, cwd, interval=0.2):
    """Run ``cmd`` in ``cwd``; wall [s], CPU of the process tree [s], peak RSS and proportional set of the tree
    [MB], return code.
    ``cwd`` is the version's tree: ``python -m`` puts the working directory first on ``sys.path``, before
    ``PYTHONPATH``, and every node process inherits it."""
    before = os.times()
    t0 = time.monotonic()
    proc = subprocess.Popen(cmd, env=env, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    peak = peak_pss = 0
    while proc.poll() is None:
        tree = proctree.sample(proc.pid)
        peak = max(peak, sum(v[0] for v in tree.values()))
        peak_pss = max(peak_pss, sum(proctree.pss(pid) for pid in tree))
        time.sleep(interval)
    wall = time.monotonic() - t0
    after = os.times()
    cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
    return {"wall_s": wall, "cpu_s": cpu, "peak_rss_mb": peak / 2**20, "peak_pss_mb": peak_pss / 2**20,
            "returncode": proc.returncode}


def environment(tree, domain, cache):
    env = dict(os.environ)
    env["PYTHONPATH"] = str(tree)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env["ROS_DOMAIN_ID"] = str(domain)
    env["ROE_SEP_CACHE_DIR"] = str(cache)
    return env


def report_of(path):
    rep = json.loads(Path(path).read_text())
    rep.pop("run", None)
    return rep


def rows_of(path):
    with open(path, newline="") as f:
        rows = [{k: v for k, v in r.items() if k not in MACHINE_COLUMNS} for r in csv.DictReader(f)]
    return sorted(rows, key=lambda r: int(r["seed"]))


def summary(samples):
    return {key: statistics.median(s[key] for s in samples) for key in ("wall_s", "cpu_s", "peak_rss_mb",
                                                                          "peak_pss_mb")} | {
        "all": samples}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="git revision of the reference code")
    ap.add_argument("--new", default=".", help="git revision of the new code ('.': the working tree, default)")
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=3, help="cold runs per version (median)")
    ap.add_argument("--campaign-runs", type=int, default=4, help="runs of the campaign per version (0: none)")
    ap.add_argument("--campaign-seed", type=int, default=1000)
    ap.add_argument("--bags", choices=("no", "yes", "both"), default="no",
                    help="campaigns without bags (--no-bags), with them, or both (a pair of campaigns each)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--domains", default="31-39", help="DDS domains LO-HI (the runs take the first, the campaigns "
                                                       "the range)")
    ap.add_argument("--out", type=Path, help="JSON result (default: stdout only)")
    ap.add_argument("--keep", type=Path, help="keep the trees and outputs here (default: a temporary directory)")
    args = ap.parse_args(argv)
    lo, hi = (int(x) for x in args.domains.split("-"))
    work = Path(tempfile.mkdtemp(prefix="roe_sep_bench_speed_")) if args.keep is None else args.keep
    work.mkdir(parents=True, exist_ok=True)
    trees = {"base": extract(args.base, work / "base"), "new": extract(args.new, work / "new")}
    for tree in trees.values():  # what an installed package or a second run imports: compiled modules
        subprocess.run([sys.executable, "-m", "compileall", "-q", str(tree / "roe_sep")], check=True)
    cache = work / "cache"
    py = sys.executable
    result = {"base": args.base, "new": args.new, "seed": args.seed, "load_average_start": os.getloadavg()}

    # fill each version's stored start-up sweep (a cold run of a machine that ran the scenario before; the key has a
    # digest of the core's source, so each version has its own)
    for side in ("base", "new"):
        subprocess.run([py, "-c", "from roe_sep.core.config import load_scenario\n"
                        "from roe_sep.nodes.parameters import table\nfrom roe_sep.nodes.planner import startup_p\n"
                        "d = table('planner')\nstartup_p(load_scenario(None), d['mc_samples'].default, "
                        "d['mc_seed'].default)"], env=environment(trees[side], lo, cache), cwd=trees[side],
                       check=False)

    runs = {"base": [], "new": []}
    for k in range(args.repeat):
        for side in ("base", "new"):
            out = work / f"run_{side}_{k}"
            cmd = [py, "-m", "roe_sep.cli", "run", "--seed", str(args.seed), "--out", str(out)]
            m = measured(cmd, environment(trees[side], lo, cache), trees[side])
            m["report"] = str(out / "report.json")
            runs[side].append(m)
            print(f"run {side} #{k}: wall {m['wall_s']:.2f} s, CPU {m['cpu_s']:.2f} s, peak RSS "
                  f"{m['peak_rss_mb']:.0f} MB, exit {m['returncode']}", file=sys.stderr, flush=True)
    result["run"] = {side: summary(v) for side, v in runs.items()}
    reports = [report_of(m["report"]) for side in runs for m in runs[side]]
    result["run_reports_identical"] = all(r == reports[0] for r in reports)

    modes = {"no": (False,), "yes": (True,), "both": (False, True)}[args.bags] if args.campaign_runs else ()
    for bags in modes:
        camp = {}
        for side in ("base", "new"):
            out = work / f"campaign_{side}{'_bags' if bags else ''}"
            cmd = [py, "-m", "roe_sep.cli", "campaign", "--runs", str(args.campaign_runs), "--seed",
                   str(args.campaign_seed), "--workers", str(args.workers), *(() if bags else ("--no-bags",)),
                   "--no-figures", "--domains", args.domains, "--out", str(out)]
            m = measured(cmd, environment(trees[side], lo, cache), trees[side], interval=0.5)
            m["runs_per_hour"] = args.campaign_runs / m["wall_s"] * 3600.0
            m["cpu_s_per_run"] = m["cpu_s"] / args.campaign_runs
            m["rows"] = str(out / "runs.csv")
            camp[side] = m
            print(f"campaign {side}{' with bags' if bags else ''}: {args.campaign_runs} runs, wall {m['wall_s']:.1f} s "
                  f"({m['runs_per_hour']:.0f} runs/h), CPU {m['cpu_s']:.1f} s ({m['cpu_s_per_run']:.2f} per run), "
                  f"peak RSS {m['peak_rss_mb']:.0f} MB (proportional {m['peak_pss_mb']:.0f} MB), exit "
                  f"{m['returncode']}", file=sys.stderr, flush=True)
        camp["rows_identical"] = rows_of(camp["base"]["rows"]) == rows_of(camp["new"]["rows"])
        camp["runs"], camp["workers"], camp["bags"] = args.campaign_runs, args.workers, bags
        result["campaign_bags" if bags else "campaign"] = camp
    result["load_average_end"] = os.getloadavg()

    b, n = result["run"]["base"], result["run"]["new"]
    lines = [f"roe-sep run --seed {args.seed}, median of {args.repeat} (cold; wall inflated by the load, load average "
             f"{result['load_average_start'][0]:.1f} -> {result['load_average_end'][0]:.1f}):",
             f"  base {args.base[:12]}: wall {b['wall_s']:.2f} s, CPU {b['cpu_s']:.2f} s, peak RSS "
             f"{b['peak_rss_mb']:.0f} MB",
             f"  new  {args.new[:12]}: wall {n['wall_s']:.2f} s, CPU {n['cpu_s']:.2f} s, peak RSS "
             f"{n['peak_rss_mb']:.0f} MB",
             f"  new/base: wall {n['wall_s'] / b['wall_s']:.2f}, CPU {n['cpu_s'] / b['cpu_s']:.2f}; reports identical "
             f"(every key but run): {result['run_reports_identical']}"]
    for key in ("campaign", "campaign_bags"):
        if key not in result:
            continue
        c = result[key]
        lines += [f"campaign {args.campaign_runs} runs, {args.workers} workers, {'with' if c['bags'] else 'no'} bags:",
                  *(f"  {side}: {c[side]['runs_per_hour']:.0f} runs/h, {c[side]['cpu_s_per_run']:.2f} CPU-s per run "
                    f"(Dask start-up included), peak RSS {c[side]['peak_rss_mb']:.0f} MB (proportional "
                    f"{c[side]['peak_pss_mb']:.0f} MB)" for side in ("base", "new")),
                  f"  new/base runs per hour {c['new']['runs_per_hour'] / c['base']['runs_per_hour']:.2f}, CPU per run "
                  f"{c['new']['cpu_s_per_run'] / c['base']['cpu_s_per_run']:.2f}; rows identical: "
                  f"{c['rows_identical']}"]
    result["summary"] = lines
    print("\n".join(lines))
    if args.out:
        args.out.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
