"""Run every benchmark in bench/ (``make bench``)."""

import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
BENCHMARKS = ["bench_mc.py", "bench_nodes.py", "bench_nonlinear.py", "bench_cluster.py", "bench_stream.py"]

if __name__ == "__main__":
    rc = 0
    for name in BENCHMARKS:
        print(f"== {name}", flush=True)
        rc |= subprocess.call([sys.executable, str(HERE / name)])
    sys.exit(rc)
