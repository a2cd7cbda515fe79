"""Benchmark: the 100,000-sample Monte Carlo p sweep, vectorized vs a per-sample loop, side by side.

The loop runs the same core functions one sample at a time (bench/mc_loop.py) on ``--loop-samples`` samples; its
cost is linear in the sample count, so its time for the full sample count is extrapolated from that subset. Also
times the whole ``roe-sep mc --json`` command (interpreter start-up included), the issue's < 2 s goal.
"""

import argparse
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from mc_loop import sweep_per_sample  # noqa: E402
from timing import best_of  # noqa: E402

from roe_sep import jsonutil  # noqa: E402
from roe_sep.core.montecarlo.sweep import DEFAULT_P_VALUES, MonteCarloConfig, draw, sweep  # noqa: E402
from roe_sep.core.separation.double_impulse import design  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=100_000)
    ap.add_argument("--loop-samples", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)

    d = design()
    ps = list(DEFAULT_P_VALUES)
    mc = MonteCarloConfig(samples=args.samples)
    t_vec, _ = best_of(lambda: sweep(d, mc, ps), args.repeat)

    mc_loop = MonteCarloConfig(samples=args.loop_samples)
    draws = draw(d, mc_loop)
    t_loop_subset, _ = best_of(lambda: sweep_per_sample(d, mc_loop, draws, ps), 1)
    t_loop = t_loop_subset * args.samples / args.loop_samples

    cli = [sys.executable, "-m", "roe_sep.cli", "mc", "--json", "--samples", str(args.samples)]
    t_cli, _ = best_of(lambda: subprocess.run(cli, check=True, capture_output=True), args.repeat)

    result = {
        "samples": args.samples,
        "p_values": len(ps),
        "vectorized_s": t_vec,
        "loop_s_extrapolated": t_loop,
        "loop_samples_measured": args.loop_samples,
        "speedup": t_loop / t_vec,
        "cli_mc_json_wall_s": t_cli,
        "vectorized_sample_p_pairs_per_s": args.samples * len(ps) / t_vec,
    }
    if args.json:
        print(jsonutil.dumps(result))
    else:
        print(f"Monte Carlo p sweep, {args.samples} samples x {len(ps)} p values (best of {args.repeat})")
        print(f"  vectorized        {t_vec:8.3f} s   ({result['vectorized_sample_p_pairs_per_s']:.3g} sample-p/s)")
        print(f"  per-sample loop   {t_loop:8.1f} s   (measured on {args.loop_samples} samples, extrapolated)")
        print(f"  ratio             {result['speedup']:8.0f} x")
        print(f"  roe-sep mc --json {t_cli:8.3f} s wall (goal < 2 s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
