"""Run a command and sample its whole process tree every ``--interval`` seconds from /proc (Linux): peak resident
set of the tree (sum over every process alive at one sample) and its proportional set (``Pss``, shared pages counted
once: :func:`pss`), each process's own peak (VmHWM), and the tree's CPU
time (utime + stime of every process, its last sample; the tree total is also cross-checked with the children's
rusage of the command). Writes one JSON object (``--out`` or stdout).

    python bench/proctree.py --out run.json -- roe-sep mc --samples 100000000 --workers 2 --json

Used for the Dask runs, where ``/usr/bin/time`` on the main process alone misses the workers' memory.
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import time

TICK = os.sysconf("SC_CLK_TCK")
PAGE = os.sysconf("SC_PAGE_SIZE")


def children_map():
    kids = {}
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat") as f:
                stat = f.read()
        except OSError:
            continue
        rest = stat[stat.rindex(")") + 2:].split()
        kids.setdefault(int(rest[1]), []).append((int(name), rest))
    return kids


def tree(root, kids):
    out, todo = [], [root]
    while todo:
        pid = todo.pop()
        for child, rest in kids.get(pid, []):
            out.append((child, rest))
            todo.append(child)
    return out


def sample(root):
    """{pid: (rss bytes, cpu s, name, hwm bytes)} of root and its descendants."""
    kids = children_map()
    procs = tree(root, kids)
    try:
        with open(f"/proc/{root}/stat") as f:
            stat = f.read()
        procs.append((root, stat[stat.rindex(")") + 2:].split()))
    except OSError:
        pass
    out = {}
    for pid, rest in procs:
        cpu = (int(rest[11]) + int(rest[12])) / TICK  # utime, stime
        rss = int(rest[21]) * PAGE
        hwm, name = 0, ""
        try:
            with open(f"/proc/{pid}/status") as f:
                for line in f:
                    if line.startswith("VmHWM:"):
                        hwm = int(line.split()[1]) * 1024
                    elif line.startswith("Name:"):
                        name = line.split()[1]
        except OSError:
            pass
        out[pid] = (rss, cpu, name, hwm)
    return out


def pss(pid) -> int:
    """Proportional set size of a process [bytes] (``Pss`` of ``/proc/PID/smaps_rollup``: each shared page counted
    once over the processes that share it), 0 when it cannot be read. The honest total of a tree of forked processes,
    whose RSS sum counts the pages they share with their parent once per process."""
    try:
        with open(f"/proc/{pid}/smaps_rollup") as f:
            return next((int(line.split()[1]) * 1024 for line in f if line.startswith("Pss:")), 0)
    except OSError:
        return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--interval", type=float, default=1.0)
    ap.add_argument("--out", help="JSON result file (default stdout)")
    ap.add_argument("--stdout", help="file for the command's stdout (default: discarded)")
    ap.add_argument("cmd", nargs=argparse.REMAINDER)
    args = ap.parse_args(argv)
    cmd = args.cmd[1:] if args.cmd[:1] == ["--"] else args.cmd
    sink = open(args.stdout, "w") if args.stdout else subprocess.DEVNULL
    t0 = time.time()
    proc = subprocess.Popen(cmd, stdout=sink)
    peak_tree, peak_at, peak_pss, last, hwm, samples = 0, 0.0, 0, {}, {}, 0
    while proc.poll() is None:
        s = sample(proc.pid)
        samples += 1
        tot = sum(v[0] for v in s.values())
        if tot > peak_tree:
            peak_tree, peak_at = tot, time.time() - t0
        peak_pss = max(peak_pss, sum(pss(pid) for pid in s))
        for pid, v in s.items():
            last[pid] = v
            hwm[pid] = max(hwm.get(pid, 0), v[3], v[0])
        time.sleep(args.interval)
    wall = time.time() - t0
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    rep = {
        "cmd": cmd,
        "returncode": proc.returncode,
        "wall_s": wall,
        "cpu_s_children_rusage": ru.ru_utime + ru.ru_stime,
        "cpu_s_tree_sampled": sum(v[1] for v in last.values()),
        "peak_rss_tree_mb": peak_tree / 2**20,
        "peak_rss_tree_at_s": peak_at,
        "peak_pss_tree_mb": peak_pss / 2**20,
        "max_rss_children_rusage_mb": ru.ru_maxrss / 1024,
        "processes": [{"pid": pid, "name": last[pid][2], "peak_rss_mb": hwm[pid] / 2**20, "cpu_s": last[pid][1]}
                      for pid in sorted(last)],
        "samples": samples,
        "interval_s": args.interval,
    }
    text = json.dumps(rep, indent=2)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text + "\n")
    else:
        print(text)
    return proc.returncode


if __name__ == "__main__":
    sys.exit(main())
