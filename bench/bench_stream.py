"""Benchmark: the streamed Monte Carlo at 1e6 / 1e7 (/ 1e8) samples, side by side in one run.

Each case is one ``roe-sep mc --json`` process under GNU time (wall time, peak RSS of the main process; with
``--workers`` the worker processes are separate and their memory is per worker): chunked in-process with the
default chunk (2e4), chunks of 1e4 and 1e6, 1 and 2 Dask workers, and the in-memory sweep (every sample held,
``roe_sep.core.montecarlo.sweep.sweep``) where it fits. samples/s per core = samples / wall / cores used. The counts
of every row must be identical for the chunk sizes and worker counts (same seed): checked and reported.
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


def timed(cmd):
    """(wall [s], peak RSS [MB], stdout) of ``cmd`` under GNU time."""
    with tempfile.NamedTemporaryFile("r", suffix=".time") as tf:
        out = subprocess.run(["/usr/bin/time", "-f", "%e %M", "-o", tf.name, *cmd], check=True, capture_output=True,
                             text=True, env={**os.environ, "PYTHONPATH": str(ROOT)}).stdout
        wall, rss_kb = Path(tf.name).read_text().split()[-2:]
    return float(wall), float(rss_kb) / 1024.0, out


def counts(rep):
    """Every count of every row: what must not depend on the chunking or the workers."""
    return [{k: v for k, v in row.items() if k.startswith("n_")} for row in rep["rows"]]


def case(samples, chunk=None, workers=None):
    cmd = [sys.executable, "-m", "roe_sep.cli", "mc", "--json", "--samples", str(samples)]
    if chunk:
        cmd += ["--chunk-size", str(chunk)]
    if workers:
        cmd += ["--workers", str(workers)]
    wall, rss, out = timed(cmd)
    cores = workers or 1
    label = f"chunked {chunk or DEFAULT_CHUNK_SIZE:.0e}"
    if workers:
        label += f", {workers} worker{'s' if workers > 1 else ''}"
    return {"case": label, "samples": samples, "wall_s": wall, "peak_rss_mb": rss, "cores": cores,
            "samples_per_s_per_core": samples / wall / cores, "counts": counts(json.loads(out))}


def in_memory(samples):
    wall, rss, _ = timed([sys.executable, "-c", IN_MEMORY, str(samples)])
    return {"case": "in-memory sweep()", "samples": samples, "wall_s": wall, "peak_rss_mb": rss, "cores": 1,
            "samples_per_s_per_core": samples / wall, "counts": None}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1e6,1e7", help="sample counts (1e8 takes ~20-60 min on this machine)")
    ap.add_argument("--in-memory-max", type=float, default=1e6, help="largest in-memory case (1.7 GB per 1e6)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    rows = []
    for size in (int(float(s)) for s in args.sizes.split(",")):
        group = [case(size)]
        if size <= 1e6:
            group += [case(size, chunk=10_000), case(size, chunk=1_000_000)]
        group += [case(size, workers=1), case(size, workers=2)]
        if size <= args.in_memory_max:
            group.append(in_memory(size))
        ref = group[0]["counts"]
        for r in group:
            r["identical_counts"] = None if r["counts"] is None else r["counts"] == ref
            r.pop("counts")
        rows += group
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        print(f"{'case':28s}{'samples':>12s}{'wall [s]':>10s}{'RSS [MB]':>10s}{'samples/s/core':>16s}  identical")
        for r in rows:
            print(f"{r['case']:28s}{r['samples']:12.0e}{r['wall_s']:10.1f}{r['peak_rss_mb']:10.0f}"
                  f"{r['samples_per_s_per_core']:16.0f}  {r['identical_counts']}")
    return 0 if all(r["identical_counts"] in (True, None) for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
