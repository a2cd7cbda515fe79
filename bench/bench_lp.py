"""The acquisition LP in its two forms, side by side on the problems real runs solve (issue 42): the dense path rows
(``planner.SPARSE_PATH = False``, the form before issue 42) and the sparse recursive form
(:func:`roe_sep.core.acquisition.planner._recursive_path`, the default).

``--capture`` runs ``roe-sep run --in-process`` for each seed with ``plan_acquisition`` wrapped (a
``sitecustomize`` module first on ``PYTHONPATH``; the shipped code is unchanged) and keeps every problem the
ic_planner handed it: the estimate, the chief, the drag, the configuration, the earliest burn and the burn-free
arcs, as strict JSON. Then every captured problem is solved in both forms, alternately, ``--repeat`` times (CPU
time, median), and compared:

* the continuous LP's optimum (``lp_dv``): the proof that the two forms are the same program (their optimal
  vertices may differ: the LP is degenerate);
* the quantized plan the ic_planner flies: total delta-v, burns, IC epoch;
* the CPU per plan and per LP solve.

    python bench/bench_lp.py --capture --seeds 5 1 2 3 1079 --domains 61-65 --out bench/results/bench_lp.json

``--problems FILE`` re-solves problems captured before (``bench/results/acquisition_problems.json``).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from roe_sep.core.acquisition import planner as P  # noqa: E402
from roe_sep.core.relmotion.trajectory import Chief  # noqa: E402

CAPTURE = '''
import json, os, dataclasses
import numpy as np
import roe_sep.core.acquisition.planner as _p
import roe_sep.core.decisions.ic_planner as _r
_plan = _p.plan_acquisition
def _captured(roe0, chief, da_dot=0.0, cfg=_p.AcquisitionConfig(), t_earliest=None, *, no_burns=()):
    with open(os.environ["ROE_SEP_LP_CAPTURE"], "a", encoding="utf-8") as fh:
        fh.write(json.dumps({"roe0": [float(x) for x in np.asarray(roe0)], "chief": dataclasses.asdict(chief),
                             "da_dot": float(da_dot), "cfg": dataclasses.asdict(cfg),
                             "t_earliest": None if t_earliest is None else float(t_earliest),
                             "no_burns": [[float(a), float(b)] for a, b in no_burns]}) + "\\n")
    return _plan(roe0, chief, da_dot, cfg, t_earliest, no_burns=no_burns)
_p.plan_acquisition = _captured
_r.plan_acquisition = _captured
'''


def capture(seeds, domains, keep=None):
    """The problems the ic_planner solved in ``roe-sep run --seed S --in-process`` for each seed."""
    lo, hi = (int(x) for x in domains.split("-"))
    problems = []
    with tempfile.TemporaryDirectory() as tmp:
        site = Path(tmp) / "site"
        site.mkdir()
        (site / "sitecustomize.py").write_text(CAPTURE, encoding="utf-8")
        for k, seed in enumerate(seeds):
            log = Path(tmp) / f"lps_{seed}.jsonl"
            env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), str(ROOT)]),
                   "ROE_SEP_LP_CAPTURE": str(log), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
                   "ROS_DOMAIN_ID": str(lo + k % (hi - lo + 1))}
            out = Path(keep or tmp) / f"run_{seed}"
            subprocess.run([sys.executable, "-m", "roe_sep.cli", "run", "--seed", str(seed), "--in-process",
                            "--out", str(out)], env=env, check=False, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL, timeout=1800)
            for line in log.read_text(encoding="utf-8").splitlines() if log.exists() else []:
                problems.append({"seed": seed, **json.loads(line)})
    return problems


def solve(problem, sparse_path):
    """The plan in one form: (CPU s, the plan or the refusal's text)."""
    P.SPARSE_PATH = sparse_path
    cfg = P.AcquisitionConfig(**problem["cfg"])
    chief = Chief(**problem["chief"])
    tic = time.process_time()
    try:
        plan = P.plan_acquisition(np.array(problem["roe0"]), chief, problem["da_dot"], cfg, problem["t_earliest"],
                                  no_burns=[tuple(b) for b in problem["no_burns"]])
    except P.AcquisitionInfeasible as exc:
        return time.process_time() - tic, str(exc)
    return time.process_time() - tic, plan


def compare(problems, repeat):
    rows = []
    for k, pb in enumerate(problems):
        cpu = {False: [], True: []}
        plans = {}
        for _ in range(repeat):
            for form in (False, True):
                dt, plan = solve(pb, form)
                cpu[form].append(dt)
                plans[form] = plan
        row = {"seed": pb["seed"], "problem": k, "cpu_s_dense": statistics.median(cpu[False]),
               "cpu_s_sparse": statistics.median(cpu[True])}
        dense, sparse = plans[False], plans[True]
        if isinstance(dense, str) or isinstance(sparse, str):
            row.update(refused_dense=dense if isinstance(dense, str) else None,
                       refused_sparse=sparse if isinstance(sparse, str) else None)
        else:
            row.update(lp_dv_dense=dense.lp_dv, lp_dv_sparse=sparse.lp_dv,
                       lp_rel_diff=abs(sparse.lp_dv - dense.lp_dv) / max(abs(dense.lp_dv), 1e-12),
                       total_dv_dense=dense.total_dv, total_dv_sparse=sparse.total_dv,
                       burns_dense=dense.n_burns, burns_sparse=sparse.n_burns,
                       t_final_dense=float(dense.t_final), t_final_sparse=float(sparse.t_final),
                       same_plan=bool(dense.n_burns == sparse.n_burns
                                      and np.allclose(dense.epochs, sparse.epochs)
                                      and np.allclose(dense.dv_carrier, sparse.dv_carrier)))
        rows.append(row)
    return rows


def summary(rows):
    solved = [r for r in rows if "lp_dv_dense" in r]
    dense = sum(r["cpu_s_dense"] for r in rows)
    sparse = sum(r["cpu_s_sparse"] for r in rows)
    refusals = [r for r in rows if "lp_dv_dense" not in r]
    return {
        "problems": len(rows), "solved_both": len(solved),
        "refused_both": sum(1 for r in refusals if r.get("refused_dense") and r.get("refused_sparse")),
        "refused_one": sum(1 for r in refusals if bool(r.get("refused_dense")) != bool(r.get("refused_sparse"))),
        "lp_rel_diff_max": max((r["lp_rel_diff"] for r in solved), default=None),
        "same_plan": sum(r["same_plan"] for r in solved),
        "total_dv_abs_diff_max_m_s": max((abs(r["total_dv_sparse"] - r["total_dv_dense"]) for r in solved),
                                         default=None),
        "cpu_s_dense": dense, "cpu_s_sparse": sparse, "speedup": dense / sparse if sparse else None,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--capture", action="store_true", help="capture the problems from runs of --seeds")
    ap.add_argument("--seeds", type=int, nargs="+", default=[5, 1, 2, 3, 1079])
    ap.add_argument("--domains", default="61-65", help="DDS domains LO-HI of the capturing runs")
    ap.add_argument("--problems", type=Path, default=ROOT / "bench" / "results" / "acquisition_problems.json",
                    help="the captured problems (written by --capture, read otherwise)")
    ap.add_argument("--repeat", type=int, default=3, help="solves per form and problem (CPU median)")
    ap.add_argument("--out", type=Path, help="JSON result")
    args = ap.parse_args(argv)
    if args.capture:
        problems = capture(args.seeds, args.domains)
        args.problems.write_text(json.dumps(problems, allow_nan=False) + "\n", encoding="utf-8")
    else:
        problems = json.loads(args.problems.read_text(encoding="utf-8"))
    rows = compare(problems, args.repeat)
    result = {"command": " ".join(["bench/bench_lp.py", *(argv if argv is not None else sys.argv[1:])]),
              "summary": summary(rows), "rows": rows}
    text = json.dumps(result, indent=1, allow_nan=False)
    if args.out:
        args.out.write_text(text + "\n", encoding="utf-8")
    print(json.dumps(result["summary"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
