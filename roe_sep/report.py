"""The run report, built from the recorded bag only (what happened is what was recorded).

Keys: ``maneuvers`` (each executed burn: purpose, spacecraft, epoch, u, dv RTN and |dv|), ``dv_total`` and
``dv_by_purpose`` (carrier burns, m/s), ``final_roe`` (truth a*ROE at the end, m), ``min_distance`` (closest
approach after the initial departure, m, with its epoch), ``time_to_ic`` (ejection to the last acquisition burn, s),
``od`` (first solution: epoch, passes, 1-sigma and error against truth), ``criteria`` (each pass/fail) and ``safe``.
"""

import math
from pathlib import Path

import numpy as np

from .core.dynamics import propagate
from .core.monitor import ERROR_CRITERIA, MonitorLimits
from .nodes import qos

ROE_KEYS = ("a_da", "a_dl", "a_dex", "a_dey", "a_dix", "a_diy")


def _stamp(t):
    return t.sec + t.nanosec * 1e-9


def read_topics(bag_dir, topics):
    """``{topic: [(log_time_s, msg), ...]}`` decoded with the bag's own ros2msg schemas (mcap_ros2)."""
    from mcap_ros2.reader import read_ros2_messages

    files = sorted(Path(bag_dir).glob("*.mcap"))
    if not files:
        raise FileNotFoundError(f"no .mcap file in {bag_dir}")
    out = {t: [] for t in topics}
    for path in files:
        for m in read_ros2_messages(str(path), topics=list(topics)):
            out[m.channel.topic].append((m.log_time_ns * 1e-9, m.ros_msg))
    return out


def build_report(bag_dir, duration=None, limits: MonitorLimits = MonitorLimits()):
    topics = (qos.EXECUTED_TOPIC, qos.TRUTH_ROE_TOPIC, qos.DIAGNOSTICS_TOPIC, qos.SAFETY_TOPIC,
              qos.PLAN_CHECK_TOPIC, qos.OD_TOPIC, qos.ACQUISITION_PLAN_TOPIC, qos.DRIFT_STOP_PLAN_TOPIC)
    data = read_topics(bag_dir, topics)

    maneuvers = []
    for _, m in data[qos.EXECUTED_TOPIC]:
        dv = [m.dv_rtn.x, m.dv_rtn.y, m.dv_rtn.z]
        maneuvers.append({"purpose": m.purpose, "spacecraft": m.spacecraft, "epoch": _stamp(m.epoch),
                          "u_deg": math.degrees(m.mean_arg_latitude), "dv_rtn": dv, "dv": float(np.linalg.norm(dv))})
    maneuvers.sort(key=lambda x: x["epoch"])
    carrier = [m for m in maneuvers if m["spacecraft"] == "carrier"]
    by_purpose = {}
    for m in carrier:
        by_purpose[m["purpose"]] = by_purpose.get(m["purpose"], 0.0) + m["dv"]
    ejection = next((m for m in maneuvers if m["purpose"] == "ejection"), None)
    ic_burns = [m for m in carrier if m["purpose"] == "ic_acquisition"]

    truth = data[qos.TRUTH_ROE_TOPIC]
    final = truth[-1][1] if truth else None
    final_roe = [getattr(final, k) for k in ROE_KEYS] if final else None

    sim_status = [s for _, d in data[qos.DIAGNOSTICS_TOPIC] for s in d.status if s.name == "roe_sep/sim"]
    values = {kv.key: kv.value for kv in sim_status[-1].values} if sim_status else {}
    min_distance = float(values.get("min_distance_m", "nan"))

    truth_checks = [s for _, s in data[qos.SAFETY_TOPIC] if s.source == "truth"]
    failed_ever = {name for s in truth_checks for name in s.violations}
    last = truth_checks[-1] if truth_checks else None
    plan_checks = [s for _, s in data[qos.PLAN_CHECK_TOPIC]]
    criteria = {name: bool(truth_checks) and name not in failed_ever for name in ERROR_CRITERIA}
    criteria["min_distance"] = math.isfinite(min_distance) and min_distance >= limits.keep_out
    criteria["plans_approved"] = bool(plan_checks) and all(s.safe for s in plan_checks)
    if last is not None:
        for name in ("drift_direction", "radar_separability", "fov"):
            criteria[f"{name}_at_end"] = name not in last.violations
    ic_reached = bool(ic_burns) and final_roe is not None and \
        limits.a_dl_min <= abs(final_roe[1]) <= limits.a_dl_max and last is not None and last.in_fov
    criteria["ic_reached"] = ic_reached
    safe = all(criteria[name] for name in (*ERROR_CRITERIA, "min_distance", "plans_approved"))

    truth_da_dot = float(values.get("truth_a_da_dot_m_per_day", "nan"))
    od = data[qos.OD_TOPIC]
    od_report = None
    if od:
        first = od[0][1]
        est = first.estimate
        cov = np.asarray(est.covariance, dtype=float).reshape(6, 6)
        t_od = _stamp(est.header.stamp)
        od_report = {"epoch": t_od, "passes": int(first.passes), "measurements": int(first.measurements),
                     "residual_rms": float(first.residual_rms),
                     "estimate": [getattr(est, k) for k in ROE_KEYS],
                     "sigma": np.sqrt(np.clip(np.diag(cov), 0, None)).tolist(),
                     "solutions": len(od)}
        before = [m for _, m in truth if _stamp(m.header.stamp) <= t_od]
        if before and math.isfinite(truth_da_dot):
            ref = before[-1]  # the sim publishes right after every burn: no burn between ref and t_od
            a = ref.chief.semi_major_axis
            roe = np.array([getattr(ref, k) for k in ROE_KEYS]) / a
            at_od = propagate(roe, t_od - _stamp(ref.header.stamp), a, ref.chief.inclination, True,
                              truth_da_dot / a / 86400.0) * a
            err = np.array(od_report["estimate"]) - at_od
            od_report["error"] = err.tolist()
            od_report["nees"] = float(err @ np.linalg.solve(cov, err)) if np.any(cov) else None

    return {
        "safe": bool(safe),
        "criteria": criteria,
        "maneuvers": maneuvers,
        "dv_total": float(sum(m["dv"] for m in carrier)),
        "dv_by_purpose": by_purpose,
        "ejection_epoch": ejection["epoch"] if ejection else None,
        "time_to_ic": (ic_burns[-1]["epoch"] - ejection["epoch"]) if (ic_burns and ejection) else None,
        "final_roe": final_roe,
        "final_epoch": _stamp(final.header.stamp) if final else None,
        "min_distance": min_distance,
        "min_distance_epoch": float(values.get("min_distance_time_s", "nan")),
        "truth_drag_a_da_dot_m_per_day": truth_da_dot,
        "od": od_report,
        "plan_checks": [{"source": s.source, "plan_stamp": _stamp(s.plan_stamp), "safe": s.safe,
                         "violations": list(s.violations)} for s in plan_checks],
        "duration": duration,
    }
