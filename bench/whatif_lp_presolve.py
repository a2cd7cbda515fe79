"""What keeping the campaign's rows identical costs: the same code with the acquisition LP solved without HiGHS's
presolve, side by side with the code as shipped, in one run.

The acquisition LP (``roe_sep.core.acquisition.highs.solve_lp``) is solved with linprog's options, presolve on. Its
path rows make it dense (about 400,000 nonzeros), and presolve is about 90 % of each solve: without it a solve is
about 10× cheaper, but the LP is degenerate, so HiGHS may stop at another optimal vertex of the same cost, and the
plan, and the run's rows, change. This bench measures both sides of that trade on one campaign:

* runs per hour and CPU per run (as ``bench_speed.py`` measures them) for the shipped code (``on``) and the same
  tree with ``highs.PRESOLVE = "off"`` (set in every process of the campaign by a ``sitecustomize`` module put first
  on ``PYTHONPATH``; the shipped code is unchanged), alternately, ``--pairs`` times;
* how many rows differ, and the campaign's statistics that matter to a flight-dynamics team (IC reached with its
  95 % interval, total delta-v, |a da| at the IC epoch, safety) side by side.

    python bench/whatif_lp_presolve.py --runs 100 --workers 2 --pairs 1 --domains 61-69 \\
        --out bench/results/whatif_lp_presolve.json

``--variant parallel-rows-off`` keeps presolve on with only its parallel-rows-and-columns rule off
(``highs.PRESOLVE_RULES_OFF = 1 << 13``, HiGHS's ``presolve_rule_off`` bit 13): the rule's search over the dense
rows is about a third of a solve, and on this LP it mostly merges the two halves of a ranged row that linprog's form
splits. In the JSON, ``off`` is the variant measured (``variant`` names it).
"""

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
from bench_speed import measured, rows_of  # noqa: E402

VARIANTS = {  # what the patched campaign changes, as a sitecustomize module run first in every process
    "presolve-off": 'import roe_sep.core.acquisition.highs as _highs\n_highs.PRESOLVE = "off"\n',
    "parallel-rows-off": 'import roe_sep.core.acquisition.highs as _highs\n_highs.PRESOLVE_RULES_OFF = 1 << 13\n',
}


def statistics_of(report):
    """The campaign report's figures compared side by side."""
    d = report["distributions"]
    pick = ("p50", "p95", "max", "mean")
    return {"ic_reached": report["criteria"]["ic_reached"], "p_safe": report["p_safe"],
            "failed": report["failed"], "dv_total_m_s": {k: d["dv_total"][k] for k in pick},
            "dv_ic_m_s": {k: d["dv_ic"][k] for k in pick},
            "abs_a_da_ic_m": {k: d["abs_a_da_ic"][k] for k in pick},
            "min_distance_m": {k: d["min_distance"][k] for k in ("min", "p5", "p50")}}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=100)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=1000, help="first seed of the campaign")
    ap.add_argument("--pairs", type=int, default=1, help="campaigns per variant, alternating")
    ap.add_argument("--domains", default="61-69", help="DDS domains LO-HI of the campaigns' runs")
    ap.add_argument("--variant", choices=sorted(VARIANTS), default="presolve-off",
                    help="what the compared campaign changes (default presolve-off)")
    ap.add_argument("--out", required=True, help="JSON results")
    args = ap.parse_args(argv)

    results = {"on": [], "off": []}
    label = {"on": "shipped", "off": args.variant}
    rows, reports = {}, {}
    with tempfile.TemporaryDirectory(prefix="whatif_lp_") as tmp:
        tmp = Path(tmp)
        patch = tmp / "patch"
        patch.mkdir()
        (patch / "sitecustomize.py").write_text(VARIANTS[args.variant])
        for k in range(args.pairs):
            for variant in ("on", "off"):
                out = tmp / f"{variant}{k}"
                env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
                           PYTHONPATH=os.pathsep.join(([str(patch)] if variant == "off" else []) + [str(ROOT)]))
                cmd = [sys.executable, "-m", "roe_sep.cli", "campaign", "--runs", str(args.runs), "--workers",
                       str(args.workers), "--seed", str(args.seed), "--no-bags", "--no-figures", "--domains",
                       args.domains, "--out", str(out)]
                m = measured(cmd, env, ROOT)
                if m["returncode"] != 0:
                    raise SystemExit(f"campaign {variant} #{k} failed with exit status {m['returncode']}")
                m["runs_per_h"] = args.runs / m["wall_s"] * 3600.0
                m["cpu_s_per_run"] = m["cpu_s"] / args.runs
                results[variant].append(m)
                rows[variant] = rows_of(out / "runs.csv")
                reports[variant] = json.loads((out / "report.json").read_text())
                print(f"{label[variant]} #{k}: {m['runs_per_h']:.0f} runs/h, {m['cpu_s_per_run']:.2f} CPU-s per "
                      f"run, peak proportional set {m['peak_pss_mb']:.0f} MB", flush=True)
    differ = sum(a != b for a, b in zip(rows["on"], rows["off"]))
    fields = [f for f in rows["on"][0] if any(a[f] != b[f] for a, b in zip(rows["on"], rows["off"]))]
    def rates(variant):
        return ", ".join(f"{m['runs_per_h']:.0f}" for m in results[variant])

    ratio = (sum(m["runs_per_h"] for m in results["off"]) / sum(m["runs_per_h"] for m in results["on"]))
    lines = [f"campaign {args.runs} runs from seed {args.seed}, {args.workers} workers, no bags, {args.pairs} pair(s):",
             f"  presolve on (shipped): {rates('on')} runs/h",
             f"  {args.variant.replace('-', ' ')}: {rates('off')} runs/h (off/on {ratio:.2f})",
             f"  rows that differ: {differ} of {len(rows['on'])}"]
    print("\n".join(lines))
    doc = {"command": " ".join(sys.argv), "variant": args.variant, "runs": args.runs, "workers": args.workers,
           "seed": args.seed,
           "summary": lines, "measures": results, "rows_differing": differ, "fields_differing": fields,
           "statistics": {v: statistics_of(reports[v]) for v in ("on", "off")}}
    Path(args.out).write_text(json.dumps(doc, indent=2, allow_nan=False) + "\n")


if __name__ == "__main__":
    main()
