"""The campaign table ``runs.csv``: one row per finished run, written the moment the run ends.

The header is fixed (:data:`FIELDS`). A row is appended as one complete line, flushed and fsync'ed, so an
interrupted campaign (Ctrl-C, a killed machine) leaves complete rows only; a torn last line (no newline) is ignored
when the table is read and overwritten by the next append. A seed appearing twice (``--retry-failed``) counts with
its last row. Empty cells are "no value" (e.g. no OD solution in a failed run).
"""

import csv
import io
import json
import math
import os
from pathlib import Path

import numpy as np

from ..core.safety.metrics import min_rn_distance
from ..core.safety.monitor import ERROR_CRITERIA
from ..report import IC_CHECKS, ROE_KEYS

CRITERIA = (*ERROR_CRITERIA, "min_distance", "plans_approved", "ic_reached")
FIELDS = (
    "seed", "status", "failure", "reason", "safe", *(f"crit_{c}" for c in CRITERIA),
    *(f"ic_{c}" for c in IC_CHECKS), "ic_a_da_m", "ic_pred_a_da_m", "ic_trim", "ic_trim_dv_m_s",
    "ic_final_od_sigma_m",
    "min_distance_m", "min_rn_ic_m", "min_rn_final_m", "final_de_m", "final_di_m",
    *(f"final_{k}_m" for k in ROE_KEYS),
    "dv_total_m_s", "dv_drift_stop_m_s", "dv_ic_m_s", "time_to_ic_s", "ejection_epoch_s",
    "od_epoch_s", "od_passes", "od_nees", *(f"od_err_{k}_m" for k in ROE_KEYS), "od_err_a_da_dot_m_per_day",
    "od_z_a_da_dot", "od_residual_rms", "od_measurements", "od_solutions", "od_last_epoch_s", "od_last_nees",
    "od_last_z_a_da_dot", "truth_drag_m_per_day", "dispersions", "wall_s", "domain_id",
    "contingency", "contingencies_detected", "od_nees7", "od_last_nees7",
)
TRUTH_FIELDS = (  # the actual approach, from the truth (report ``actual_approach``) and the passive-safety verdicts
    "truth_closest_m", "truth_closest_epoch_s", "truth_closest_bound_m", "truth_closest_orbit1_m", "truth_nearest_m",
    "truth_nearest_epoch_s",
    "truth_departure_epoch_s", "truth_keep_out_s", "truth_keep_out_entries", "truth_keep_out_violated",
    "ps_keep_out_first_s", "ps_passive_safety_first_s",
)
# the headers of earlier versions (before the contingencies, before the 7-state NEES, before the truth's approach):
# read as rows without them
LEGACY_HEADERS = (FIELDS[:-4], FIELDS[:-2], FIELDS)
FIELDS = FIELDS + TRUTH_FIELDS
BOOL_FIELDS = {"safe", "ic_trim", "truth_keep_out_violated", *(f"crit_{c}" for c in CRITERIA),
               *(f"ic_{c}" for c in IC_CHECKS)}
INT_FIELDS = {"seed", "od_passes", "od_measurements", "od_solutions", "domain_id", "truth_keep_out_entries"}
STR_FIELDS = {"status", "failure", "reason", "dispersions", "contingency", "contingencies_detected"}
# dispersions, contingency: the report's, as compact JSON; contingencies_detected: {name: first epoch [s]} as JSON
RUN_FIELDS = ("wall_s", "domain_id")  # how the run went on this machine, not what it computed
FAILURES = ("node_exit", "timeout", "aborted", "exception", "worker_lost")


def failure_kind(reason: str) -> str:
    """The failure class of an unfinished run from ``report['run']['reason']`` of :func:`roe_sep.run.run`."""
    if " exited early (" in reason:  # "<node> exited early (exit status 2); last log line: ..."
        return "node_exit"
    if reason.startswith("wall-time limit"):
        return "timeout"
    if reason.startswith("scenario aborted"):
        return "aborted"
    return "exception"


def row_from_report(seed: int, rep: dict) -> dict:
    """The table row of one run's report (:func:`roe_sep.report.build_report` + ``run``)."""
    run = rep.get("run") or {}
    completed = bool(run.get("completed"))
    reason = str(run.get("reason", ""))
    row = {"seed": seed, "status": "ok" if completed else "failed", "failure": "" if completed else
           failure_kind(reason), "reason": reason, "safe": bool(rep.get("safe")) and completed}
    for c in CRITERIA:
        row[f"crit_{c}"] = bool((rep.get("criteria") or {}).get(c))
    row["min_distance_m"] = rep.get("min_distance")
    ic = rep.get("ic") or {}
    row["min_rn_ic_m"] = ic.get("min_rn_distance")
    row.update({f"ic_{c}": v for c, v in (ic.get("checks") or {}).items()})  # empty: no IC epoch evaluated
    row["ic_a_da_m"] = ic["roe"][0] if ic.get("roe") else None  # truth drift at the IC epoch
    row["ic_pred_a_da_m"] = rep.get("ic_predicted_a_da")  # what the last information predicted there
    final_od = rep.get("final_od")
    if final_od:
        row.update(ic_trim=final_od["trim"], ic_trim_dv_m_s=final_od["trim_dv"],
                   ic_final_od_sigma_m=final_od["sigma_a_da"])
    if rep.get("dispersions"):
        row["dispersions"] = json.dumps(rep["dispersions"], separators=(",", ":"), allow_nan=False)
    if rep.get("contingency"):
        row["contingency"] = json.dumps(rep["contingency"], separators=(",", ":"), allow_nan=False)
    if rep.get("contingencies_detected"):
        row["contingencies_detected"] = json.dumps({d["name"]: d["epoch"] for d in rep["contingencies_detected"]},
                                                   separators=(",", ":"), allow_nan=False)
    final = rep.get("final_roe")
    if final:
        row["min_rn_final_m"] = float(min_rn_distance(final))  # Eq. 25 is homogeneous: a*ROE in, meters out
        row["final_de_m"] = math.hypot(final[2], final[3])
        row["final_di_m"] = math.hypot(final[4], final[5])
        row.update({f"final_{k}_m": v for k, v in zip(ROE_KEYS, final)})
    by = rep.get("dv_by_purpose") or {}
    row.update(dv_total_m_s=rep.get("dv_total"), dv_drift_stop_m_s=by.get("drift_stop"),
               dv_ic_m_s=by.get("ic_acquisition"), time_to_ic_s=rep.get("time_to_ic"),
               ejection_epoch_s=rep.get("ejection_epoch"),
               truth_drag_m_per_day=rep.get("truth_drag_a_da_dot_m_per_day"))
    row.update(_truth_cells(rep))
    od = rep.get("od")
    if od:
        rate_err = od.get("a_da_dot_error")
        row.update(od_epoch_s=od.get("epoch"), od_passes=od.get("passes"), od_nees=od.get("nees"),
                   od_nees7=od.get("nees7"),
                   od_err_a_da_dot_m_per_day=None if rate_err is None else rate_err * 86400.0,
                   od_z_a_da_dot=od.get("a_da_dot_z"), od_solutions=od.get("solutions"),
                   od_residual_rms=od.get("residual_rms"), od_measurements=od.get("measurements"))
        row.update({f"od_err_{k}_m": v for k, v in zip(ROE_KEYS, od.get("error") or ())})
        last = od.get("last") or {}
        row.update(od_last_epoch_s=last.get("epoch"), od_last_nees=last.get("nees"), od_last_nees7=last.get("nees7"),
                   od_last_z_a_da_dot=last.get("a_da_dot_z"))
    return row


def _truth_cells(rep: dict) -> dict:
    """The :data:`TRUTH_FIELDS` of a report (none of a report without ``actual_approach``: recorded before it)."""
    out = {}
    ps = rep.get("passive_safety") or {}
    out["ps_keep_out_first_s"] = (ps.get("keep_out") or {}).get("first_failed_epoch")
    out["ps_passive_safety_first_s"] = (ps.get("passive_safety") or {}).get("first_failed_epoch")
    ap = rep.get("actual_approach")
    if not ap:
        return out
    closest = ap.get("closest_approach") or {}
    out.update(truth_closest_m=closest.get("distance"), truth_closest_epoch_s=closest.get("epoch"),
               truth_closest_bound_m=closest.get("bound"),
               truth_closest_orbit1_m=(ap.get("after_first_orbit") or {}).get("distance"),
               truth_nearest_m=(ap.get("nearest") or {}).get("distance"),
               truth_nearest_epoch_s=(ap.get("nearest") or {}).get("epoch"),
               truth_departure_epoch_s=ap.get("departure_epoch"), truth_keep_out_s=ap.get("keep_out_time"),
               truth_keep_out_entries=ap.get("keep_out_entries"), truth_keep_out_violated=ap.get("keep_out_violated"))
    return out


def failed_row(seed: int, failure: str, reason: str) -> dict:
    """The row of a run that produced no report (an exception, a lost worker)."""
    return {"seed": seed, "status": "failed", "failure": failure, "reason": reason, "safe": False,
            **{f"crit_{c}": False for c in CRITERIA}}


def _cell(value):
    """One cell: "" for no value (None, NaN, inf), true/false, the shortest round-trip repr of a float; NumPy
    scalars as their Python values (a report built in memory holds them)."""
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (float, np.floating)):
        return repr(float(value)) if math.isfinite(value) else ""
    if isinstance(value, np.integer):
        return str(int(value))
    return str(value)


def _parse(name, text):
    if text == "":
        return "" if name in STR_FIELDS else None
    if name in STR_FIELDS:
        return text
    if name in BOOL_FIELDS:
        return text == "true"
    if name in INT_FIELDS:
        return int(text)
    return float(text)


def format_row(row: dict) -> str:
    """One CSV line (with its newline) of a row, every field of :data:`FIELDS` in order."""
    unknown = set(row) - set(FIELDS)
    if unknown:
        raise KeyError(f"row fields not in the table header: {sorted(unknown)}")
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([_cell(row.get(f)) for f in FIELDS])
    return buf.getvalue()


class Table:
    """``runs.csv`` of a campaign directory: read the done rows, append a finished one durably."""

    def __init__(self, path):
        self.path = Path(path)

    def read(self) -> dict:
        """``{seed: row}`` of the complete rows (the last row of a seed wins); {} without a table."""
        if not self.path.exists():
            return {}
        text = self.path.read_text(encoding="utf-8")
        if not text:
            return {}
        complete = text if text.endswith("\n") else text[: text.rfind("\n") + 1]  # drop a torn last line
        reader = csv.reader(io.StringIO(complete))
        header = next(reader, None)
        fields = tuple(header) if header is not None and tuple(header) in LEGACY_HEADERS else FIELDS
        if header is not None and tuple(header) != fields:
            raise ValueError(f"{self.path}: table header {header[:4]}... is not the header of this roe_sep version "
                             f"(expected {len(FIELDS)} columns starting {list(FIELDS[:4])}); use another --out")
        rows = {}
        for cells in reader:
            if len(cells) != len(fields):
                continue
            row = {f: _parse(f, c) for f, c in zip(fields, cells)}
            row.update({f: _parse(f, "") for f in FIELDS if f not in row})  # a legacy row: the newer cells empty
            rows[row["seed"]] = row
        return rows

    def append(self, row: dict):
        """Append one complete line, flush and fsync (write the header first if the table is new; cut a torn last
        line left by a crash so the new row starts on its own line)."""
        line = format_row(row)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._upgrade()
        with open(self.path, "a+", encoding="utf-8", newline="") as fh:
            fh.seek(0, os.SEEK_END)
            size = fh.tell()
            if size == 0:
                fh.write(format_header())
            else:
                fh.seek(0)
                text = fh.read()
                if not text.endswith("\n"):
                    fh.truncate(len(text[: text.rfind("\n") + 1].encode("utf-8")))
                    fh.seek(0, os.SEEK_END)
            fh.write(line)
            fh.flush()
            os.fsync(fh.fileno())


    def _upgrade(self):
        """A table with a legacy header (:data:`LEGACY_HEADERS`) rewritten with this header, every row with the
        newer cells empty, atomically; a campaign started before them goes on in its directory."""
        if not self.path.exists():
            return
        with open(self.path, encoding="utf-8", newline="") as fh:
            first = fh.readline()
        if not first or tuple(next(csv.reader([first]))) not in LEGACY_HEADERS:
            return
        rows = self.read()
        tmp = self.path.with_suffix(".csv.tmp")
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(format_header())
            for row in rows.values():
                fh.write(format_row(row))
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, self.path)


def format_header() -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(FIELDS)
    return buf.getvalue()
