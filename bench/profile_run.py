"""Profile one ``roe-sep run`` end to end, every process of it (the runner and each node process).

A ``sitecustomize`` on ``PYTHONPATH`` (active only with ``ROE_SEP_PROFILE_DIR``) starts in every Python process of
the run and writes on exit its CPU time (user + system, ``getrusage``), the CPU time of each thread still alive and,
by ``--mode``:

* ``sample`` (default): a statistical profile of the process's CPU time. ``setitimer(ITIMER_PROF)`` fires every
  ``--interval`` s of the process's CPU time (all threads) and the handler records the main thread's Python stack,
  weighted by the process CPU since the previous sample (a signal falling due inside a long native call is handled
  at its end, in its caller's frame, the expirations meanwhile coalesced into one).
  Nearly free (no per-call overhead, unlike cProfile's 2-4x on call-heavy code) and not inflated by the machine's
  load: a sample is CPU time spent, wherever it was spent. CPU of other threads (the DDS threads, the ground_bridge's
  CCSDS writer) lands on the main thread's current frame, mostly rclpy's wait: the thread totals say how much.
* ``cprofile``: cProfile in every process (deterministic call counts; times inflated on call-heavy code).
* ``cpu``: no profiler, the per-process and per-thread CPU times only.

    python bench/profile_run.py --seed 5 --out bench/results/profile_run_seed5.txt
    python bench/profile_run.py --seed 5 -- --in-process          # the layout of a campaign's runs
"""

import argparse
import collections
import io
import json
import os
import pstats
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SITECUSTOMIZE = r'''
import os
if os.environ.get("ROE_SEP_PROFILE_DIR"):
    import atexit, collections, json, resource, signal, sys, time
    _mode = os.environ.get("ROE_SEP_PROFILE_MODE", "sample")
    _t0 = time.monotonic()
    _stacks = collections.Counter()
    _prof = None
    if _mode == "cprofile":
        import cProfile
        _prof = cProfile.Profile()
        _prof.enable()
    elif _mode == "sample":
        _last = [time.process_time()]

        def _on_prof(signum, frame):
            # weighted by the process CPU since the previous sample: a signal that falls due in a long native call
            # (a HiGHS solve, rclpy's C++ spin) runs at the next bytecode, and the timer's expirations meanwhile
            # coalesce into that one signal; an unweighted count put the acquisition LP at 0.13 CPU-s, 1.0 measured
            now = time.process_time()
            stack = []
            while frame is not None:
                code = frame.f_code
                stack.append(f"{code.co_filename}:{code.co_name}")
                frame = frame.f_back
            _stacks[";".join(reversed(stack))] += now - _last[0]
            _last[0] = now
        signal.signal(signal.SIGPROF, _on_prof)
        _interval = float(os.environ.get("ROE_SEP_PROFILE_INTERVAL", "0.005"))
        signal.setitimer(signal.ITIMER_PROF, _interval, _interval)

    def _dump():
        if _prof is not None:
            _prof.disable()
        if _mode == "sample":
            signal.setitimer(signal.ITIMER_PROF, 0, 0)
        ru = resource.getrusage(resource.RUSAGE_SELF)
        d = os.environ["ROE_SEP_PROFILE_DIR"]
        tag = "_".join(a.rsplit(".", 1)[-1] for a in sys.argv[:8] if not a.startswith("-")
                       and "/" not in a)[:60] or "python"
        base = os.path.join(d, f"{os.getpid()}_{tag}")
        if _prof is not None:
            _prof.dump_stats(base + ".prof")
        threads = {}
        tick = os.sysconf("SC_CLK_TCK")
        for tid in os.listdir("/proc/self/task"):
            try:
                with open(f"/proc/self/task/{tid}/stat") as f:
                    st = f.read()
            except OSError:
                continue
            name = st[st.index("(") + 1:st.rindex(")")]
            rest = st[st.rindex(")") + 2:].split()
            threads[name] = threads.get(name, 0.0) + (int(rest[11]) + int(rest[12])) / tick
        with open(base + ".json", "w") as f:
            json.dump({"threads": threads, "argv": sys.argv, "cpu_user": ru.ru_utime, "cpu_sys": ru.ru_stime,
                       "wall": time.monotonic() - _t0, "maxrss_kb": ru.ru_maxrss, "mode": _mode,
                       "interval": float(os.environ.get("ROE_SEP_PROFILE_INTERVAL", "0.005")),
                       "stacks": dict(_stacks)}, f)

    atexit.register(_dump)
'''

# what each phase of a process is, by the function on the stack (first match from the top of the stack down)
PHASES = (
    ("imports", ("<frozen importlib._bootstrap>:_find_and_load",)),
    ("report from the bag", ("roe_sep/run.py:report_from_bag",)),
    ("node start-up (construct, configure, activate)", ("roe_sep/nodes/spin.py:<lambda>",
                                                         "roe_sep/run.py:<lambda>")),
    ("shutdown (destroy nodes, final CCSDS set)", ("roe_sep/nodes/spin.py:serve",)),
)
NODE_FILES = ("sim", "safety_monitor", "radar_od", "ic_planner", "planner", "ejector", "recorder", "ground_bridge",
              "lockstep")


def short(frame: str) -> str:
    frame = frame.replace(str(ROOT) + "/", "")
    if "site-packages/" in frame:
        frame = frame.split("site-packages/", 1)[1]
    elif "/lib/python3" in frame:
        frame = "stdlib/" + frame.split("/lib/python3", 1)[1].split("/", 1)[1]
    return frame


def classify(frames):
    """(phase, node module) of one sampled stack (outermost first)."""
    joined = frames
    phase = "other"
    if any(f.endswith("_find_and_load") for f in joined):
        phase = "imports"
    elif any(f.startswith("roe_sep/run.py:report_from_bag") for f in joined):
        phase = "report from the bag"
    elif any(f.startswith("roe_sep/nodes/spin.py:spin") for f in joined):
        phase = "spin (lockstep loop and drain)"
    elif any(f.startswith("roe_sep/run.py:wait_for_completion") for f in joined):
        phase = "runner: waiting for the run (observer spin)"
    elif any(f.startswith("roe_sep/nodes/spin.py:serve") for f in joined):
        phase = "node start-up and shutdown (construct/configure/activate, destroy, final CCSDS set)"
    node = None
    for f in reversed(joined):  # the innermost node module on the stack
        mod = f.split(":", 1)[0]
        if mod.startswith("roe_sep/nodes/") and Path(mod).stem in NODE_FILES and Path(mod).stem != "lockstep":
            node = Path(mod).stem
            break
    if node is None and any(f.startswith("roe_sep/nodes/lockstep.py") for f in joined):
        node = "lockstep (protocol)"
    return phase, node


def summarise_samples(meta, top):
    stacks = {tuple(short(f) for f in k.split(";")): n for k, n in meta["stacks"].items()}
    total = sum(stacks.values()) or 1
    cpu = meta["cpu_user"] + meta["cpu_sys"]
    scale = cpu / total  # the process's CPU per sampled CPU (the interpreter's start precedes the timer)
    phases, nodes = collections.Counter(), collections.Counter()
    incl, excl = collections.Counter(), collections.Counter()
    for frames, n in stacks.items():
        phase, node = classify(frames)
        phases[phase] += n
        if phase == "spin (lockstep loop and drain)":
            nodes[node or "executor / rclpy (take, wait, other threads' CPU)"] += n
        for f in set(frames):
            incl[f] += n
        excl[frames[-1]] += n
    lines = [f"  {len(stacks)} distinct stacks sampled every {meta['interval'] * 1e3:g} ms of process CPU, each sample "
             f"weighted by the CPU since the previous one ({total:.2f} s of {cpu:.2f} s sampled)",
             "  by phase [CPU s, share]:"]
    lines += [f"    {k:85s} {n * scale:6.2f}  {n / total:5.1%}" for k, n in phases.most_common()]
    if nodes:
        lines.append("  the spin by node (innermost node module on the stack) [CPU s, share of the process]:")
        lines += [f"    {k:85s} {n * scale:6.2f}  {n / total:5.1%}" for k, n in nodes.most_common()]
    lines.append(f"  top {top} functions by inclusive CPU (roe_sep and libraries) [CPU s, share]:")
    skip = ("<frozen", "stdlib/runpy", "roe_sep/cli/", "roe_sep/nodes/suite.py:<module>", "<string>")
    shown = 0
    for f, n in incl.most_common():
        if f.startswith(skip) or f.endswith(":<module>") and "roe_sep/nodes/suite" in f:
            continue
        lines.append(f"    {f:85s} {n * scale:6.2f}  {n / total:5.1%}")
        shown += 1
        if shown >= top:
            break
    lines.append(f"  top {top} functions by own CPU (the innermost Python frame) [CPU s, share]:")
    lines += [f"    {f:85s} {n * scale:6.2f}  {n / total:5.1%}" for f, n in excl.most_common(top)]
    return lines


def summarise_cprofile(prof, top):
    out = io.StringIO()
    stats = pstats.Stats(str(prof), stream=out)
    lines = []
    for key, title in (("tottime", "own time"), ("cumulative", "cumulative time")):
        out.seek(0)
        out.truncate()
        stats.sort_stats(key).print_stats(top)
        body = out.getvalue()
        body = body[body.find("   ncalls"):]
        lines.append(f"  top {top} by {title} (cProfile, wall clock):")
        lines.extend("    " + ln.replace(str(ROOT) + "/", "").replace(sys.prefix + "/", "")
                     for ln in body.rstrip().splitlines())
    return lines


def summarise(meta_file: Path, top: int) -> str:
    meta = json.loads(meta_file.read_text())
    cpu = meta["cpu_user"] + meta["cpu_sys"]
    lines = [f"process: {' '.join(Path(a).name if '/' in a else a for a in meta['argv'][:12])}",
             f"  CPU {cpu:.2f} s (user {meta['cpu_user']:.2f} + sys {meta['cpu_sys']:.2f}), wall {meta['wall']:.2f} s,"
             f" peak RSS {meta['maxrss_kb'] / 1024:.0f} MB",
             "  threads alive at exit [CPU s] (threads ended before, e.g. DDS's, only in the total): " + ", ".join(
                 f"{k} {v:.2f}" for k, v in sorted(meta.get("threads", {}).items(), key=lambda kv: -kv[1]) if v)]
    if meta["mode"] == "sample":
        lines += summarise_samples(meta, top)
    elif meta["mode"] == "cprofile":
        lines += summarise_cprofile(meta_file.with_suffix(".prof"), top)
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--mode", choices=("sample", "cprofile", "cpu"), default="sample")
    ap.add_argument("--interval", type=float, default=0.005, help="CPU s between samples (sample mode)")
    ap.add_argument("--out", type=Path, help="summary file (default: stdout)")
    ap.add_argument("--top", type=int, default=30)
    ap.add_argument("--keep", type=Path, help="keep the profiles and the run's output here")
    ap.add_argument("--campaign-layout", action="store_true",
                    help="profile a campaign's run instead: every node in one process, no ground_bridge "
                         "(roe_sep.run.run(in_process=True, ground_bridge=False), as roe_sep.campaign.child), after "
                         "what the fork server does once for all its runs (forkserver.preload, the start-up sweep)")
    ap.add_argument("extra", nargs="*", help="further roe-sep run arguments (after --)")
    args = ap.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="roe_sep_profile_")) if args.keep is None else args.keep
    work.mkdir(parents=True, exist_ok=True)
    site = work / "site"
    site.mkdir(exist_ok=True)
    (site / "sitecustomize.py").write_text(SITECUSTOMIZE)
    profdir = work / "prof"
    profdir.mkdir(exist_ok=True)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(site), str(ROOT)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH")
                                                                    else []))
    env.update(ROE_SEP_PROFILE_DIR=str(profdir), ROE_SEP_PROFILE_MODE=args.mode,
               ROE_SEP_PROFILE_INTERVAL=str(args.interval))
    cmd = [sys.executable, "-m", "roe_sep.cli", "run", "--seed", str(args.seed), "--out", str(work / "run"),
           *args.extra]
    if args.campaign_layout:
        # as the worker's fork server prepares every run it forks: imports, caches and the planner's start-up sweep
        # (its CPU lands in the phases "imports" and "other", not in the run's)
        cmd = [sys.executable, "-c", "import sys; from roe_sep.campaign import forkserver as f; f.preload(); "
               "f._warm({}); from roe_sep.run import run; "
               "run(out=sys.argv[1], seed=int(sys.argv[2]), in_process=True, ground_bridge=False)",
               str(work / "run"), str(args.seed)]
    t0 = time.monotonic()
    subprocess.run(cmd, env=env, cwd=ROOT, check=False, stdout=subprocess.DEVNULL)  # -m: cwd first on sys.path
    wall = time.monotonic() - t0
    metas = sorted(profdir.glob("*.json"), key=lambda p: int(p.name.split("_", 1)[0]))
    total_cpu = sum(json.loads(m.read_text())["cpu_user"] + json.loads(m.read_text())["cpu_sys"] for m in metas)
    what = "a campaign's run (in process, no ground_bridge)" if args.campaign_layout else "roe-sep run"
    head = (f"{what} --seed {args.seed} {' '.join(args.extra)} (bench/profile_run.py --mode {args.mode}), "
            f"{len(metas)} processes; wall {wall:.1f} s (inflated by the machine's load), CPU {total_cpu:.2f} s "
            f"over the processes")
    text = head + "\n\n" + "\n\n".join(summarise(m, args.top) for m in metas) + "\n"
    if args.out:
        args.out.write_text(text)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()
