"""Closed-loop Monte Carlo campaigns (``roe-sep campaign``): N end-to-end runs of ``roe-sep run`` with seeds S, S+1,
..., executed as Dask tasks, written one row at a time (resumable), aggregated into P(safe), dv, time to IC and the
OD consistency beside the open-loop Monte Carlo.

Modules: :mod:`.engine` (the Dask client), :mod:`.runner` (one run as a task: child process, DDS domain, seeds),
:mod:`.table` (``runs.csv``), :mod:`.aggregate` (the statistics). Layout of ``--out DIR``:

* ``campaign.json``: the settings the runs were made with (scenario content, node overrides, duration); a rerun with
  other settings is refused rather than mixed into one table.
* ``runs.csv``: one row per finished run (:data:`.table.FIELDS`); ``runs/<seed>/``: its ``report.json`` (strict
  JSON), ``overrides.yaml`` (the run's node parameters), ``params.yaml``, ``bag/``, ``logs/run.log`` (the nodes'
  output), ``campaign.log`` (the run process's), with ``--ccsds`` also ``ccsds/``; with ``--no-bags`` the bag is
  removed once the row is written (the row and report.json are the same).
* ``report.json``: the aggregate report; ``figures/``: its PNG figures.
"""

import hashlib
import json
import math
import sys
from pathlib import Path

from .. import jsonutil
from .aggregate import aggregate, open_loop
from .table import Table, failed_row

CAMPAIGN_FILE = "campaign.json"


def settings(config, overrides, duration):
    """What makes two campaigns' runs comparable: the scenario (hash of its validated content, so the embedded
    default counts too; its contingency block when it has one), the node overrides (``--contingency``: those of
    the simulator and the radar) and the duration."""
    from ..core.config import load_scenario

    loaded = load_scenario(config)
    scenario = (repr(loaded) + ("" if loaded.contingency is None else repr(loaded.contingency))).encode("utf-8")
    return {"config": str(config) if config else None, "scenario_sha256": hashlib.sha256(scenario).hexdigest(),
            "overrides": overrides or {}, "duration": duration}


def check_settings(out: Path, current: dict):
    """Record the settings of a new campaign directory; refuse to continue one made with other settings."""
    path = out / CAMPAIGN_FILE
    if path.exists():
        before = json.loads(path.read_text(encoding="utf-8"))
        diff = [k for k in ("scenario_sha256", "overrides", "duration") if before.get(k) != current[k]]
        if diff:
            raise ValueError(f"--out {out}: holds a campaign made with other {', '.join(diff)} "
                             f"(see {path}); use another --out to run these settings")
        return
    out.mkdir(parents=True, exist_ok=True)
    path.write_text(jsonutil.dumps(current, indent=2) + "\n", encoding="utf-8")


def run_campaign(runs, seed, out, workers=1, scheduler=None, *, config=None, overrides=None, duration=None,
                 timeout=1800.0, domains=(1, 100), retry_failed=False, progress=False, open_loop_samples=20000,
                 figures=True, client_factory=None, ccsds=False, bags=True, collision_radius=None):
    """Run the missing runs of seeds ``seed .. seed + runs - 1`` on Dask, append each row as it finishes, and return
    the aggregate report (also written to ``out/report.json``). ``client_factory(workers, scheduler)`` is the
    context manager giving the Dask client (default :func:`.engine.dask_client`). ``ccsds``: each run also runs
    the ground_bridge (its CCSDS set in ``runs/<seed>/ccsds/``); ``bags`` False: each run's bag is removed once its
    row is written; ``collision_radius`` [m]: of the truth's collision count (default: the bodies',
    :data:`~roe_sep.core.safety.approach.COLLISION_RADIUS`)."""
    out = Path(out)
    check_settings(out, settings(config, overrides, duration))
    table = Table(out / "runs.csv")
    seeds = list(range(seed, seed + runs))
    done = table.read()
    todo = [s for s in seeds if s not in done or (retry_failed and done[s]["status"] != "ok")]
    executed = 0
    if todo:
        executed = _execute(todo, out, table, workers, scheduler, config=config, overrides=overrides,
                            duration=duration, timeout=timeout, domains=domains,
                            progress=progress, initial=runs - len(todo), total=runs, client_factory=client_factory,
                            ccsds=ccsds, bags=bags)
    rows_by_seed = table.read()
    rows = [rows_by_seed[s] for s in seeds if s in rows_by_seed]
    rep = {"seeds": [seed, seed + runs - 1], "executed_now": executed, "skipped_done": runs - len(todo),
           "workers": None if scheduler else workers, "scheduler": scheduler,
           **aggregate(rows, **({} if collision_radius is None else {"collision_radius": collision_radius})),
           "open_loop": open_loop(config, overrides, samples=open_loop_samples)}
    rep["wall_s_per_run"] = _mean([r.get("wall_s") for r in rows])
    if figures and rows:
        from ..core.config import load_scenario
        from ..plots.campaign import write_campaign_figures

        sep = load_scenario(config).separation
        rep["figures"] = [str(p) for p in write_campaign_figures(rows, out / "figures", sep.min_rn_distance,
                                                                 (sep.a_dl_min, sep.a_dl_max))]
    (out / "report.json").write_text(jsonutil.dumps(rep, indent=2) + "\n", encoding="utf-8")
    return rep


def _mean(values):
    vals = [v for v in values if v is not None and math.isfinite(v)]
    return sum(vals) / len(vals) if vals else None


def _execute(todo, out, table, workers, scheduler, *, config, overrides, duration, timeout, domains, progress,
             initial, total, client_factory, ccsds=False, bags=True):
    from distributed import as_completed

    from .engine import dask_client
    from .runner import execute

    specs = [{"seed": s, "run_dir": str((out / "runs" / str(s)).resolve()),
              "config": str(Path(config).resolve()) if config else None, "overrides": overrides or {},
              "duration": duration, "timeout": float(timeout), "domains": list(domains), "ccsds": bool(ccsds),
              "bags": bool(bags)}
             for s in todo]
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=total, initial=initial, unit="run", file=sys.stderr, dynamic_ncols=True,
                   desc="campaign")
    executed = 0
    try:
        with (client_factory or dask_client)(workers, scheduler) as client:
            if scheduler and not client.nthreads():  # the tasks queue on the scheduler until a worker joins
                print(f"roe-sep campaign: the cluster at {scheduler} has no worker yet; the runs start when one "
                      "joins", file=sys.stderr, flush=True)
            futures = {client.submit(execute, spec, key=f"roe-sep-run-{spec['seed']}-{out.resolve()}", pure=False,
                                     retries=0): spec["seed"] for spec in specs}
            for fut in as_completed(futures):
                s = futures[fut]
                try:
                    row = fut.result()
                except Exception as exc:  # noqa: BLE001  (the worker died under the run: a row, not a crash)
                    row = failed_row(s, "worker_lost", f"{type(exc).__name__}: {exc}"[:300])
                table.append(row)
                executed += 1
                if bar is not None:
                    state = (("safe" if row["safe"] else "UNSAFE") if row["status"] == "ok"
                             else f"failed ({row['failure']})")
                    bar.set_postfix_str(f"seed {s}: {state}")
                    bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    return executed
