"""One run of a campaign as a Dask task: :func:`roe_sep.run.run` in a process of its own, in a DDS domain of its
own, with the seed's dispersions; returns the run's table row (never raises: a failure is a row with its reason).

Layout. The run's process runs every node of the run in itself, on one EventsExecutor (``run(in_process=True)``):
the same nodes, parameters and lockstep as ``roe-sep run``, hence the same row as ``roe-sep run --seed S+k`` in its
default two processes (test_campaign). It is forked from the worker's fork server (:mod:`.forkserver`), which has
imported what a run imports and computed the planner's start-up sweep once, so a run pays neither; the ground_bridge
(CCSDS export) only listens, and a run has it with ``ccsds``.

Isolation. The run's nodes and its observer live in a process of their own, in a process group of their own: the
worker's own signals (Ctrl-C on the terminal) never reach them, the worker kills the whole group when the run exceeds
its wall-time limit, and the kernel kills the run when its fork server dies, and the fork server when its worker dies
(``PR_SET_PDEATHSIG``, SIGKILL: :mod:`roe_sep.children`), so an interrupted campaign leaves no node behind. The DDS
domain is taken from a range with an exclusive ``flock`` per domain in the temporary directory, so concurrent runs on
one host (any number of workers, any number of campaigns) never share a domain; discovery stays on loopback
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``), so workers on other hosts cannot collide either. The lock is the
kernel's: a dead worker releases it.

Seeds. The simulator's ``seed`` is the run seed (SPL magnitude and direction, carrier burn execution and attitude
errors, differential drag); the radar noise is seeded with :func:`radar_seed` of the run seed, an independent
stream (written into the run's ``overrides.yaml``, so ``roe-sep run --seed S --params overrides.yaml`` repeats the
run alone).
"""

import contextlib
import fcntl
import json
import os
import shutil
import signal
import subprocess
import tempfile
import time
from pathlib import Path

import yaml

from .. import jsonutil
from ..run import radar_seed
from . import forkserver
from .table import failed_row, row_from_report

KILL_MARGIN = 120.0  # wall s beyond the run's own time limit before the worker kills the run's process group


def run_overrides(seed: int, base: dict, ccsds: bool = False) -> dict:
    """The node parameter overrides of one run: the campaign's ``--params`` plus the run's radar-noise seed; with
    ``ccsds`` (the run has a ground_bridge) its OEM/TDM/CDM written once, at the end of the run (``write_period``
    0, unless ``--params`` sets it): nobody follows a campaign run live, and the periodic updates of a whole run's
    XML OEM cost about 4 of a run's CPU seconds. The run's CCSDS set is the same."""
    out = {node: dict(values) for node, values in (base or {}).items()}
    out.setdefault("radar", {})["seed"] = radar_seed(seed)
    if ccsds:
        out.setdefault("ground_bridge", {}).setdefault("write_period", 0.0)
    return out


def write_overrides(path: Path, overrides: dict):
    path.write_text(yaml.safe_dump({n: {"ros__parameters": v} for n, v in overrides.items()}, sort_keys=True),
                    encoding="utf-8")


@contextlib.contextmanager
def domain_lock(lo: int, hi: int, wait=600.0):
    """An exclusive DDS domain id in [lo, hi] for the duration of the block (``flock`` on a per-domain file)."""
    lock_dir = Path(tempfile.gettempdir()) / "roe_sep_campaign_domains"
    lock_dir.mkdir(exist_ok=True)
    start = time.monotonic()
    while True:
        for d in range(lo, hi + 1):
            fh = open(lock_dir / f"{d}.lock", "w")
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                fh.close()
                continue
            try:
                yield d
            finally:
                fcntl.flock(fh, fcntl.LOCK_UN)
                fh.close()
            return
        if time.monotonic() - start > wait:
            raise RuntimeError(f"no free DDS domain in [{lo}, {hi}] within {wait:g} s")
        time.sleep(0.5)


def _last_line(path: Path) -> str:
    try:
        lines = [ln.strip() for ln in path.read_text(encoding="utf-8", errors="replace").splitlines() if ln.strip()]
    except OSError:
        return ""
    return lines[-1][:300] if lines else ""


def execute(spec: dict) -> dict:
    """The Dask task: run seed ``spec['seed']`` into ``spec['run_dir']`` (an unfinished earlier attempt there is
    removed first) and return its row. ``spec``: seed, run_dir, config, overrides, duration, timeout, domains,
    ccsds, bags (False: the bag of a completed run is removed once its report is read)."""
    seed = int(spec["seed"])
    run_dir = Path(spec["run_dir"])
    t0 = time.monotonic()
    domain = None
    try:
        if run_dir.exists():
            shutil.rmtree(run_dir)
        run_dir.mkdir(parents=True)
        ccsds = bool(spec.get("ccsds"))
        write_overrides(run_dir / "overrides.yaml", run_overrides(seed, spec.get("overrides"), ccsds))
        with domain_lock(*spec["domains"]) as domain:
            child = {k: spec.get(k) for k in ("config", "duration", "timeout")}
            child.update(seed=seed, out=str(run_dir), params=str(run_dir / "overrides.yaml"), domain_id=domain,
                         ccsds=ccsds)
            srv = forkserver.server()  # the run is forked from this worker's warm fork server
            srv.warm(spec.get("config"), child["params"])
            proc = srv.spawn([json.dumps(child)], run_dir / "campaign.log")
            try:
                code = proc.wait(timeout=float(spec["timeout"]) + KILL_MARGIN)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
                row = failed_row(seed, "timeout", f"run killed after {spec['timeout'] + KILL_MARGIN:g} wall s")
                return _finish(row, t0, domain)
            finally:
                if proc.poll() is None:  # the worker is being torn down (task cancelled): take the run with it
                    os.killpg(proc.pid, signal.SIGKILL)
        report_path = run_dir / "report.json"
        if code != 0 or not report_path.exists():
            why = _last_line(run_dir / "campaign.log") or f"exit status {code}"
            return _finish(failed_row(seed, "exception", f"run process failed: {why}"), t0, domain)
        rep = json.loads(report_path.read_text(encoding="utf-8"))  # run() may write NaN; the campaign's copy is strict
        report_path.write_text(jsonutil.dumps(rep, indent=2) + "\n", encoding="utf-8")
        row = row_from_report(seed, rep)
        row["reason"] = row["reason"][:300]  # a node's death: the runner names it with its last log line
        if not spec.get("bags", True) and row["status"] == "ok":  # a failed run keeps its bag for the diagnosis
            shutil.rmtree(run_dir / "bag", ignore_errors=True)
        return _finish(row, t0, domain)
    except Exception as exc:  # noqa: BLE001  (a run's failure is a row, never a lost campaign)
        return _finish(failed_row(seed, "exception", f"{type(exc).__name__}: {exc}"[:300]), t0, domain)


def _finish(row, t0, domain):
    row["wall_s"] = time.monotonic() - t0
    row["domain_id"] = domain
    return row

