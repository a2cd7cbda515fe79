"""Benchmark: the streamed Monte Carlo (`roe-sep mc`) at 1e6 / 1e7 (/ 1e8) samples, side by side in one run.

Each case is one ``roe-sep mc --json`` process run under ``bench/proctree.py``, which samples the whole process tree
(main process, Dask scheduler and workers) from /proc every second: wall time, CPU time of the tree (user + system,
all processes) and the peak resident set of the tree. Cases per size: chunked in-process with the default chunk
(2e4), chunks of 1e4 and 1e6 (at 1e6 samples), 1 and 2 Dask workers, and the in-memory sweep (every sample held,
``roe_sep.core.montecarlo.sweep.sweep``) where it fits (``--in-memory-max``).

Rates: ``samples/s/core`` = samples / wall / cores used (the issue's measure; inflated by other load on a shared
machine) and ``samples/CPU-s`` = samples / CPU time of the tree (contention-independent; includes the main
process's scheduler and reduction work when workers are used). Ratios are against the default in-process case of
the same size. The counts of every row must be identical for every chunk size and worker count (same seed):
checked and reported. ``--max-samples`` caps the sizes (10^8 takes ~7 CPU-min); ``--include FILE`` adds a
separately measured case (a JSON written by this bench's ``--single``), marked with its source.

    python bench/bench_stream.py --sizes 1e6,1e7 --out-json bench_stream.json --out-md bench_stream.md
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from roe_sep.core.montecarlo.streaming import DEFAULT_CHUNK_SIZE  # noqa: E402

IN_MEMORY = ("import sys; from roe_sep.core.montecarlo.sweep import MonteCarloConfig, sweep; "
             "from roe_sep.core.separation.double_impulse import design; "
             "sweep(design(), MonteCarloConfig(samples=int(sys.argv[1])))")


def measured(cmd, nice=0):
    """(proctree report, stdout text) of ``cmd``."""
    with tempfile.TemporaryDirectory() as tmp:
        tree, out = Path(tmp) / "tree.json", Path(tmp) / "out.json"
        pre = ["nice", "-n", str(nice)] if nice else []
        subprocess.run([*pre, sys.executable, str(ROOT / "bench" / "proctree.py"), "--out", str(tree), "--stdout",
                        str(out), "--", *cmd], check=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
        rep = json.loads(tree.read_text())
        if rep["returncode"] != 0:
            raise RuntimeError(f"{cmd} failed with status {rep['returncode']}")
        return rep, out.read_text()


def counts(rep):
    """Every count of every row: what must not depend on the chunking or the workers."""
    return [{k: v for k, v in row.items() if k.startswith("n_")} for row in rep["rows"]]


def row(label, samples, tree, cores, cnt, source="this run"):
    cpu = max(tree["cpu_s_children_rusage"], tree["cpu_s_tree_sampled"])
    return {"case": label, "samples": samples, "cores": cores, "wall_s": tree["wall_s"], "cpu_s": cpu,
            "peak_rss_tree_mb": tree["peak_rss_tree_mb"],
            "peak_rss_per_process_mb": [round(p["peak_rss_mb"], 1) for p in tree["processes"]
                                        if p["peak_rss_mb"] > 20],
            "samples_per_s_per_core": samples / tree["wall_s"] / cores, "samples_per_cpu_s": samples / cpu,
            "counts": cnt, "source": source}


def case(samples, chunk=None, workers=None, nice=0):
    cmd = [sys.executable, "-m", "roe_sep.cli", "mc", "--json", "--samples", str(samples)]
    if chunk:
        cmd += ["--chunk-size", str(chunk)]
    if workers:
        cmd += ["--workers", str(workers)]
    tree, out = measured(cmd, nice)
    label = f"chunked {chunk or DEFAULT_CHUNK_SIZE:.0e}"
    label += f", {workers} worker{'s' if workers > 1 else ''}" if workers else ", in-process"
    return row(label, samples, tree, workers or 1, counts(json.loads(out)))


def in_memory(samples, nice=0):
    tree, _ = measured([sys.executable, "-c", IN_MEMORY, str(samples)], nice)
    return row("in-memory sweep()", samples, tree, 1, None)


def table_md(rows):
    lines = ["| case | samples | wall [s] | CPU [s] | samples/s/core (wall) | samples/CPU-s | wall ratio | "
             "CPU ratio | peak RSS tree [MB] | identical counts | source |", "|" + "---|" * 11]
    for r in rows:
        lines.append(f"| {r['case']} | {r['samples']:.0e} | {r['wall_s']:.1f} | {r['cpu_s']:.1f} | "
                     f"{r['samples_per_s_per_core']:,.0f} | {r['samples_per_cpu_s']:,.0f} | "
                     f"{r.get('wall_ratio', float('nan')):.2f} | {r.get('cpu_ratio', float('nan')):.2f} | "
                     f"{r['peak_rss_tree_mb']:.0f} | {r['identical_counts']} | {r['source']} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1e6,1e7", help="sample counts, comma-separated")
    ap.add_argument("--max-samples", type=float, default=1e8, help="skip sizes above this")
    ap.add_argument("--in-memory-max", type=float, default=1e6, help="largest in-memory case (1.7 GB per 1e6)")
    ap.add_argument("--nice", type=int, default=0, help="run every case under nice -n NICE")
    ap.add_argument("--include", action="append", default=[], help="add a case measured apart (--single JSON)")
    ap.add_argument("--single", nargs=3, metavar=("SAMPLES", "WORKERS", "OUT"),
                    help="measure one chunked case (WORKERS 0: in-process) and write its row to OUT")
    ap.add_argument("--out-json")
    ap.add_argument("--out-md")
    args = ap.parse_args(argv)
    if args.single:
        n, w, out = int(float(args.single[0])), int(args.single[1]), args.single[2]
        r = case(n, workers=w or None, nice=args.nice)
        Path(out).write_text(json.dumps(r, indent=2) + "\n")
        return 0
    rows = []
    for path in args.include:
        extra = json.loads(Path(path).read_text())
        extra["source"] = extra.get("source") if extra.get("source") != "this run" else f"separate run ({path})"
        rows.append(extra)
    sizes = [int(float(s)) for s in args.sizes.split(",") if float(s) <= args.max_samples]
    for size in sizes:
        jobs = [lambda: case(size, nice=args.nice)]
        if size <= 1e6:
            jobs += [lambda: case(size, chunk=10_000, nice=args.nice),
                     lambda: case(size, chunk=1_000_000, nice=args.nice)]
        jobs += [lambda: case(size, workers=1, nice=args.nice), lambda: case(size, workers=2, nice=args.nice)]
        if size <= args.in_memory_max:
            jobs.append(lambda: in_memory(size, args.nice))
        for job in jobs:
            rows.append(job())
            write(rows, args)  # after every case: a long run that is stopped keeps what it measured
    return write(rows, args, show=True)


def write(rows, args, show=False):
    rows = [dict(r) for r in rows]
    for r in rows:
        same = [x for x in rows if x["samples"] == r["samples"] and x["counts"] is not None]
        ref = next((x for x in rows if x["samples"] == r["samples"] and x["case"].endswith("in-process")
                    and x["case"].startswith(f"chunked {DEFAULT_CHUNK_SIZE:.0e}")), None)
        r["identical_counts"] = None if r["counts"] is None or len(same) < 2 else all(
            x["counts"] == r["counts"] for x in same)
        if ref is not None:
            r["wall_ratio"] = r["wall_s"] / ref["wall_s"]
            r["cpu_ratio"] = r["cpu_s"] / ref["cpu_s"]
    for r in rows:
        r.pop("counts")
    md = table_md(rows)
    if show:
        print(md)
    if args.out_json:
        Path(args.out_json).write_text(json.dumps(rows, indent=2, allow_nan=False) + "\n")
    if args.out_md:
        Path(args.out_md).write_text(md)
    return 0 if all(r["identical_counts"] in (True, None) for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
