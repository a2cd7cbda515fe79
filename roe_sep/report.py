"""The run report, built from the recorded bag only (what happened is what was recorded).

Keys: ``maneuvers`` (each executed burn: purpose, spacecraft, epoch, u, dv RTN and |dv|), ``dv_total`` and
``dv_by_purpose`` (carrier burns, m/s), ``final_roe`` (truth a*ROE at the end, m), ``min_distance`` (closest
approach after the initial departure, m, with its epoch), ``dispersions`` (what the simulator drew,
:func:`dispersions_applied`), ``final_od`` (:func:`final_od_decision`) and ``ic_predicted_a_da``
(:func:`predicted_ic_drift`), ``time_to_ic`` (ejection to the IC epoch, s, when the truth meets the initial
conditions there; None when it does not), ``od`` (first solution, :func:`od_solution`: epoch, passes, 1-sigma, error
against truth, NEES, drift rate against the truth's own; ``last``: the same of the last solution), ``ic`` (truth at
the IC epoch and each initial condition), ``criteria`` (each pass/fail) and ``safe`` (the safety criteria only:
keep-out, passive safety, evaporation, closest approach, every plan approved by the monitor; ``keep_out`` and
``passive_safety`` are passive-safety verdicts: a prediction with no further burns from each check, see
``passive_safety``), ``passive_safety`` (:func:`passive_safety_verdicts`), ``actual_approach`` (what happened, from
the truth: :func:`actual_approach`), ``contingency`` (the contingency injected, as applied by the simulator or the
radar: :func:`contingency_applied`; None without one) and ``contingencies_detected`` (what the safety monitor saw of
one: :func:`contingencies_detected`).
"""

import contextlib
import gc
import json
import math
from pathlib import Path

import numpy as np

from . import interfaces, validate
from .core.od.batch import nees
from .core.od.ensemble import secular_drift
from .core.relmotion.dynamics import propagate
from .core.relmotion.orbit import mean_motion
from .core.safety.approach import actual_approach as _approach
from .core.safety.metrics import min_rn_distance
from .core.safety.monitor import ERROR_CRITERIA, MonitorLimits, in_fov
from .stamps import time_to_sec

ROE_KEYS = validate.ROE_FIELDS


def read_topics(bag_dir, topics, raw=()):
    """``{topic: [(log_time_s, msg), ...]}`` decoded with the bag's own ros2msg schemas (what mcap_ros2 decodes,
    :func:`roe_sep.bag.reader.decoded_messages`); on the topics in ``raw`` a message may be a
    :class:`~roe_sep.bag.reader.RawMessage` (serialized, with its decoder)."""
    from .bag.reader import decoded_messages

    files = sorted(Path(bag_dir).glob("*.mcap"))
    if not files:
        raise FileNotFoundError(f"no .mcap file in {bag_dir}")
    out = {t: [] for t in topics}
    for path in files:
        for topic, log_time, msg in decoded_messages(path, topics, raw):
            out[topic].append((log_time * 1e-9, msg))
    return out


class Truth:
    """The truth samples (RelativeOrbitalElements) of a run that :func:`roe_sep.validate.truth` accepts, in
    log-time order, as arrays: ``stamps`` (list, s: :func:`~roe_sep.stamps.time_to_sec` of each stamp) and
    ``times`` (the same, an array), ``roe`` (N, 6) a*ROE [m], the chief's ``a`` [m] and ``inc`` [rad] (lists, as
    decoded), ``u`` [rad] and ``a_da`` [m] (arrays), ``final_roe`` (the last sample's a*ROE as decoded, None
    without one). Built from decoded messages (:meth:`of_messages`) or straight from the serialized messages of
    a fixed layout (:func:`read_truth`): the same values either way."""

    def __init__(self, stamps, roe, a, inc, u, *, final_roe):
        self.stamps, self.times = stamps, np.array(stamps, dtype=float)
        self.roe = np.asarray(roe, dtype=float).reshape(-1, 6)
        self.a, self.inc, self.u = a, inc, np.asarray(u, dtype=float)
        self.a_da = self.roe[:, 0]
        self.final_roe = final_roe

    def __len__(self):
        return len(self.stamps)

    @classmethod
    def of_messages(cls, truth):
        """From ``[(log_time, msg), ...]`` (already validated)."""
        msgs = [m for _, m in truth]
        return cls([time_to_sec(m.header.stamp) for m in msgs], [[getattr(m, k) for k in ROE_KEYS] for m in msgs],
                   [m.chief.semi_major_axis for m in msgs], [m.chief.inclination for m in msgs],
                   [m.chief.mean_arg_latitude for m in msgs],
                   final_roe=[getattr(msgs[-1], k) for k in ROE_KEYS] if msgs else None)


def _truth(truth):
    """A :class:`Truth` (as it is, or of ``[(log_time, msg), ...]``)."""
    return truth if isinstance(truth, Truth) else Truth.of_messages(truth)


_TRUTH_FIELDS = {"header.stamp.sec": ("i", "I"), "header.stamp.nanosec": ("i", "I"), "covariance": ("d",),
                 **{k: ("d",) for k in ROE_KEYS}, **{f"chief.{k}": ("d",) for k, *_ in validate.ELEMENT_BOUNDS}}
_DTYPE = {"d": "<f8", "i": "<i4", "I": "<u4"}


def read_truth(items):
    """The :class:`Truth` of the truth topic's ``[(log_time, msg or RawMessage), ...]`` (:func:`read_topics` with
    the topic ``raw``): when every message is serialized with one schema of fixed layout (fixed-size fields and
    strings of the same lengths, :func:`roe_sep.bag.cdr.fixed_layout`) they are read as one NumPy record array and
    validated by :func:`roe_sep.validate.roe_accepted`, no object per message; else each is decoded in order (and
    raises what decoding raises) and validated by :func:`roe_sep.validate.truth`."""
    from .bag.reader import RawMessage

    arrays = _truth_arrays([m for _, m in items])
    if arrays is not None:
        return arrays
    decoded = [(t, m.decode(m.data) if isinstance(m, RawMessage) else m) for t, m in items]
    return Truth.of_messages(_valid_items(interfaces.TRUTH_ROE_TOPIC, decoded))


def _truth_arrays(raws):
    """:func:`read_truth` of a fixed layout, None where it does not apply (the messages then go one by one)."""
    from .bag import cdr
    from .bag.reader import RawMessage

    if not raws or not all(isinstance(r, RawMessage) for r in raws):
        return None
    first = raws[0]
    if not isinstance(first.decode, cdr.Decoder) or any(
            r.decode is not first.decode or (r.schema.name, r.schema.data) != (first.schema.name, first.schema.data)
            for r in raws):
        return None
    size = len(first.data)
    if any(len(r.data) != size or not r.data[1] & 1 for r in raws):  # one length, little-endian CDR
        return None
    try:
        first.decode(first.data)  # the layout's sample decodes (in bounds, its strings UTF-8)
        fields, strings, end = cdr.fixed_layout(first.decode.msgdefs, first.schema.name, first.data)
    except Exception:  # noqa: BLE001 -- UnsupportedSchema, or a message mcap_ros2 refuses: one by one
        return None
    if end > size:
        return None
    for offset in strings:  # the same string lengths, hence one layout; the strings themselves decode
        head = first.data[offset:offset + 4]
        n = int.from_bytes(head, "little")
        text = slice(offset + 4, offset + 4 + n - 1) if n > 1 else slice(0, 0)
        for r in raws:
            if r.data[offset:offset + 4] != head:
                return None
            if r.data[text] != first.data[text]:
                try:
                    r.data[text].decode("utf-8")
                except UnicodeDecodeError:
                    return None
    layout = {path: (off, code, count) for path, off, code, count in fields}
    names, formats, offsets = [], [], []
    for path, codes in _TRUTH_FIELDS.items():
        off, code, count = layout.get(path, (None, None, None))
        if code not in codes or count != (36 if path == "covariance" else None):
            return None
        names.append(path)
        formats.append((_DTYPE[code], (count,)) if count else _DTYPE[code])
        offsets.append(off)
    arr = np.frombuffer(b"".join(r.data for r in raws),
                        dtype=np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": size}))
    ok = validate.roe_accepted(arr["header.stamp.sec"], arr["header.stamp.nanosec"],
                               {k: arr[f"chief.{k}"] for k, *_ in validate.ELEMENT_BOUNDS},
                               {k: arr[k] for k in ROE_KEYS}, arr["covariance"])
    arr = arr[ok]
    roe = np.stack([arr[k] for k in ROE_KEYS], axis=-1).reshape(-1, 6)
    return Truth([s + n * 1e-9 for s, n in zip(arr["header.stamp.sec"].tolist(),
                                                arr["header.stamp.nanosec"].tolist())],
                 roe, arr["chief.semi_major_axis"].tolist(), arr["chief.inclination"].tolist(),
                 arr["chief.mean_arg_latitude"], final_roe=roe[-1].tolist() if len(roe) else None)


def truth_at(truth, t, truth_da_dot):
    """Truth a*ROE [m] at ``t`` from the last truth sample at or before it (the simulator publishes one right after
    every burn, so none lies in between) and the true drag drift [m/day]; None without a sample. ``truth``: a
    :class:`Truth` or ``[(log_time, msg), ...]``."""
    truth = _truth(truth)
    before = np.flatnonzero(truth.times <= t)
    if not before.size or not math.isfinite(truth_da_dot):
        return None
    i = int(before[-1])
    a = truth.a[i]
    roe = truth.roe[i] / a
    return propagate(roe, t - truth.stamps[i], a, truth.inc[i], True, da_dot=truth_da_dot / a / 86400.0) * a


CHECKS = {interfaces.TRUTH_ROE_TOPIC: validate.truth, interfaces.EXECUTED_TOPIC: validate.executed,
          interfaces.TRUTH_RTN_TOPIC: validate.truth_rtn,
          interfaces.OD_TOPIC: validate.orbit_determination, interfaces.DRIFT_STOP_PLAN_TOPIC: validate.plan,
          interfaces.ACQUISITION_PLAN_TOPIC: validate.plan, interfaces.PLAN_CHECK_TOPIC: validate.safety_status,
          interfaces.SAFETY_TOPIC: validate.safety_status}


def _valid_items(topic, msgs, checks=CHECKS):
    """The ``(log_time, msg)`` of a topic that its check (:data:`CHECKS`) accepts."""
    check = checks.get(topic)
    kept = []
    for item in msgs:
        try:
            if check is not None:
                check(item[1])
        except ValueError:
            continue
        kept.append(item)
    return kept


def valid_only(data):
    """Drop what the nodes themselves reject (:mod:`roe_sep.validate`): a bag records every message on a topic,
    also a foreign publisher's garbage, which must not enter the report."""
    out = {topic: _valid_items(topic, msgs) for topic, msgs in data.items()}
    out[interfaces.PLAN_CHECK_TOPIC] = [(t, m) for t, m in out[interfaces.PLAN_CHECK_TOPIC]
                                        if m.source.startswith("plan:")]
    return out


def planner_model_error(plans, truth, truth_da_dot):
    """The planner's prediction against truth: the aimed a*ROE of the last plan on a topic (its ``aimed`` field,
    stamped with the epoch it is aimed at) minus the truth there [m]; None without a plan or truth. The planners
    never see the truth: this is their model error plus, for the blind drift-stop, the ejection's dispersion."""
    if not plans:
        return None
    truth = _truth(truth)
    aimed = plans[-1][1].aimed
    t = time_to_sec(aimed.header.stamp)
    if not len(truth) or t > truth.stamps[-1]:
        return None  # aimed beyond the end of the run: no truth there
    true = truth_at(truth, t, truth_da_dot)
    if true is None:
        return None
    predicted = np.array([getattr(aimed, k) for k in ROE_KEYS])
    return {"epoch": t, "predicted": predicted.tolist(), "truth": true.tolist(),
            "error": (predicted - true).tolist()}


IC_CHECKS = ("within_run", "along_track", "drift", "ei_parallel", "min_rn_distance", "fov")  # initial_conditions


def initial_conditions(truth, plans, ic_burns, truth_da_dot, limits, *, drift_tolerance=5.0, ei_tolerance_deg=10.0,
                       run_end=None):
    """The experiment's initial conditions checked on truth at the IC epoch of the last acquisition plan: mean
    along-track separation in [a_dl_min, a_dl_max], |a da| <= ``drift_tolerance`` m, e/i (anti-)parallel within
    ``ei_tolerance_deg`` with the minimum R-N distance (Eq. 25) of at least ``min_rn_distance``, in the FOV."""
    if not plans or not ic_burns:
        return None
    t_ic = time_to_sec(plans[-1][1].aimed.header.stamp)
    roe = truth_at(truth, t_ic, truth_da_dot)
    if roe is None:
        return None
    ei = math.degrees(math.atan2(roe[2] * roe[5] - roe[3] * roe[4], roe[2] * roe[4] + roe[3] * roe[5]))
    ei_off = min(abs(ei), 180.0 - abs(ei))  # deviation from parallel or anti-parallel
    rn = float(min_rn_distance(roe))
    checks = dict(zip(IC_CHECKS, (
        run_end is None or t_ic <= run_end,  # within_run: an IC epoch after the run's end is not reached yet
        bool(limits.a_dl_min <= abs(roe[1]) <= limits.a_dl_max),
        bool(abs(roe[0]) <= drift_tolerance),
        bool(ei_off <= ei_tolerance_deg),
        bool(rn >= limits.min_rn_distance),
        bool(in_fov(roe, limits)),
    ), strict=True))
    return {"epoch": t_ic, "roe": roe.tolist(), "ei_angle_deg": ei, "min_rn_distance": rn, "checks": checks,
            "reached": all(checks.values())}


def truth_secular_drift(truth, t, burn_epochs):
    """The truth's secular a*da [m] and drift rate [m/s] at ``t`` (:func:`~roe_sep.core.od.ensemble.secular_drift`,
    the comparand of the OD's secular state) over the truth samples after the latest burn at or before ``t`` up to
    ``t``; None over too short a span."""
    truth = _truth(truth)
    start = max((b for b in burn_epochs if b <= t), default=-math.inf)
    span = np.flatnonzero((start < truth.times) & (truth.times <= t))
    if not span.size:
        return None
    period = 2.0 * math.pi / float(mean_motion(truth.a[int(span[-1])]))
    return secular_drift(truth.times[span], truth.a_da[span], t, period, truth.u[span])


def od_solution(msg, truth, truth_da_dot, burn_epochs=None):
    """One OD solution against the truth at its epoch: ``estimate``, ``sigma`` and ``error`` (a*ROE, m), ``nees``
    (6 dof: the ROE block of the covariance), ``nees7`` (7 dof: ROE and drift rate, :func:`od_covariance7`), the
    drift rate ``a_da_dot`` with its
    ``a_da_dot_sigma`` and ``a_da_dot_error`` against the truth's drift rate ``a_da_dot_truth`` (m/s), and
    ``a_da_dot_z``, the error in sigmas (standard normal for an honest covariance). The truth is its secular state
    (:func:`truth_secular_drift` given the epochs of the executed burns ``burn_epochs``: its mean ROE with the
    secular a*da and drift rate), else (or without a long enough burn-free span) its mean ROE and the
    simulator's drag ``truth_da_dot`` [m/day]. No error without truth at the epoch."""
    est = msg.estimate
    cov = np.asarray(est.covariance, dtype=float).reshape(6, 6)
    t_od = time_to_sec(est.header.stamp)
    out = {"epoch": t_od, "passes": int(msg.passes), "measurements": int(msg.measurements),
           "residual_rms": float(msg.residual_rms), "estimate": [getattr(est, k) for k in ROE_KEYS],
           "sigma": np.sqrt(np.clip(np.diag(cov), 0, None)).tolist(), "a_da_dot": float(msg.a_da_dot),
           "a_da_dot_sigma": float(msg.a_da_dot_sigma)}
    at_od = truth_at(truth, t_od, truth_da_dot)
    if at_od is not None:
        secular = None if burn_epochs is None else truth_secular_drift(truth, t_od, burn_epochs)
        if secular is not None:
            at_od[0] = secular[0]
        out["error"] = (np.array(out["estimate"]) - at_od).tolist()
        out["nees"] = nees(out["estimate"], at_od, cov) if np.any(cov) else None
        out["a_da_dot_truth"] = secular[1] if secular is not None else truth_da_dot / 86400.0
        out["a_da_dot_error"] = float(msg.a_da_dot - out["a_da_dot_truth"])
        out["a_da_dot_z"] = out["a_da_dot_error"] / msg.a_da_dot_sigma if msg.a_da_dot_sigma > 0 else None
        cov7 = od_covariance7(msg)
        out["nees7"] = (nees([*out["estimate"], msg.a_da_dot], [*at_od, out["a_da_dot_truth"]], cov7)
                        if cov7 is not None else None)
    return out


def od_covariance7(msg):
    """The 7x7 covariance [m^2, m^2/s, m^2/s^2] of (a*ROE, a*da_dot) of an OD message: the ROE block, the drift
    rate's cross terms and variance; None when the message carries no cross terms (recorded before them) or no
    covariance."""
    cross = np.asarray(getattr(msg, "a_da_dot_covariance", ()), dtype=float)
    roe = np.asarray(msg.estimate.covariance, dtype=float).reshape(6, 6)
    if cross.shape != (6,) or not np.any(roe) or not msg.a_da_dot_sigma > 0:
        return None
    cov = np.zeros((7, 7))
    cov[:6, :6], cov[:6, 6], cov[6, :6], cov[6, 6] = roe, cross, cross, msg.a_da_dot_sigma ** 2
    return cov


def dispersions_applied(text):
    """The simulator's dispersions as drawn (its final status value ``dispersions_applied``, JSON): ``drag_factor``
    (differential ballistic coefficient factor), ``ejection_delay_s``, ``burns`` ([spacecraft, magnitude factor,
    attitude errors RTN rad] per executed burn, the SPL ejection first) and the ``configured`` distributions; None
    when the status carries none."""
    if not text:
        return None
    try:
        out = json.loads(text)
    except ValueError:
        return None
    return out if isinstance(out, dict) else None


def contingency_applied(diagnostics):
    """The run's contingency as applied: the value ``contingency_applied`` (JSON: name, parameters as
    drawn, configured, events) of the last status of the simulator or of the radar that carries it, the simulator's
    first (a contingency acts on one side only); None without one."""
    for node in ("roe_sep/sim", "roe_sep/radar"):
        for status in reversed([s for _, d in diagnostics for s in d.status if s.name == node]):
            text = next((kv.value for kv in status.values if kv.key == "contingency_applied"), None)
            if text:
                out = dispersions_applied(text)
                if out is not None:
                    return out
    return None


CONTINGENCY_STATUS = "roe_sep/safety_monitor/contingency"
MITIGATION_STATUS = "roe_sep/planner/contingency"  # what the planner acted on (drift_stop_replaced, weak_ejection)
RADAR_STATUS = "roe_sep/radar/contingency"  # what the radar station reported (radar_pass_missed)
ACQUISITION_STATUS = "roe_sep/ic_planner/contingency"  # what the ic_planner acted on (blind_acquisition)
OD_STATUS = "roe_sep/radar_od/contingency"  # what radar_od acted on (range_bias_estimated)


def contingencies_detected(diagnostics):
    """What the safety monitor detected (its named diagnostics ``roe_sep/safety_monitor/contingency``,
    :mod:`roe_sep.core.safety.anomaly`), what the planner, the ic_planner and radar_od acted on
    (``roe_sep/planner/contingency``, ``roe_sep/ic_planner/contingency``, ``roe_sep/radar_od/contingency``) and what
    the radar station reported (``roe_sep/radar/contingency``): per name its first finding, ``{name, epoch [s], text,
    count}``, in the order of their first epochs; [] when nothing was found."""
    found = {}
    for _, d in diagnostics:
        for s in d.status:
            if s.name not in (CONTINGENCY_STATUS, MITIGATION_STATUS, RADAR_STATUS, ACQUISITION_STATUS, OD_STATUS):
                continue
            values = {kv.key: kv.value for kv in s.values}
            name = values.get("contingency")
            try:
                epoch = float(values.get("epoch_s", "nan"))
            except ValueError:
                epoch = math.nan
            if not name or not math.isfinite(epoch):
                continue
            if name not in found or epoch < found[name]["epoch"]:
                found[name] = {"name": name, "epoch": epoch, "text": s.message,
                               "count": found.get(name, {}).get("count", 0)}
            found[name]["count"] += 1
    return sorted(found.values(), key=lambda x: (x["epoch"], x["name"]))


FINAL_OD_KEYS = ("trim_dv", "predicted_a_da", "sigma_a_da", "threshold", "t_final")


def final_od_decision(diagnostics):
    """The ic_planner's drift-trim decision from the final OD (its status values ``final_*``, the last one
    published): ``trim`` (flown or not), ``trim_dv`` [m/s], ``predicted_a_da`` (at the IC epoch then in force, before
    the trim) with its 1-sigma ``sigma_a_da`` and the ``threshold`` [m], ``t_final`` [s]; None without a decision."""
    for status in reversed([s for _, d in diagnostics for s in d.status if s.name == "roe_sep/ic_planner"]):
        values = {kv.key: kv.value for kv in status.values}
        if "final_trim" in values:
            try:
                out = {k: float(values[f"final_{k}"]) for k in FINAL_OD_KEYS}
            except (KeyError, ValueError):
                return None
            return {"trim": values["final_trim"] == "True", **out}
    return None


def ejection_estimate(msgs, ejection):
    """The last ejection estimate of the footage (geometry_msgs/TwistWithCovarianceStamped on
    ``/separation/ejection_estimate``) against the executed ejection ``ejection`` (the report's maneuver, None
    without one): dv RTN [m/s], its 1-sigma per axis, |dv| and its sigma, the release epoch [s], the errors of |dv|
    [m/s] and in its sigmas and the NEES of the vector (chi-square, 3 dof); None without an estimate or with a
    non-finite one."""
    if not msgs:
        return None
    m = msgs[-1][1]
    lin = m.twist.twist.linear
    dv = np.array([lin.x, lin.y, lin.z], dtype=float)
    cov = np.array([[m.twist.covariance[6 * i + j] for j in range(3)] for i in range(3)], dtype=float)
    if not (np.all(np.isfinite(dv)) and np.all(np.isfinite(cov))) or not np.linalg.norm(dv) > 0.0:
        return None
    mag = float(np.linalg.norm(dv))
    sigma = math.sqrt(max(float(dv @ cov @ dv), 0.0)) / mag
    out = {"dv_rtn": dv.tolist(), "sigma_rtn": np.sqrt(np.clip(np.diag(cov), 0.0, None)).tolist(), "dv": mag,
           "sigma_dv": sigma, "release_epoch": time_to_sec(m.header.stamp), "error_dv": None, "error_sigmas": None,
           "nees": None}
    if ejection is not None:
        err = dv - np.array(ejection["dv_rtn"], dtype=float)
        out["error_dv"] = mag - ejection["dv"]
        out["error_sigmas"] = out["error_dv"] / sigma if sigma > 0.0 else None
        try:
            out["nees"] = float(err @ np.linalg.solve(cov, err))
        except np.linalg.LinAlgError:
            pass
    return out


def predicted_ic_drift(final_od, ic_model_error):
    """a da [m] at the IC epoch as the last information predicted it: the final OD's prediction when it flew no trim
    (the IC epoch unchanged), else the aimed value of the last plan (the trim's); None without either."""
    if final_od is not None and not final_od["trim"]:
        return final_od["predicted_a_da"]
    return ic_model_error["predicted"][0] if ic_model_error else None


def passive_safety_verdicts(truth_checks):
    """The passive-safety verdicts of the safety monitor on the truth (its ``/safety/status`` of source ``truth``,
    a check every ``check_period``: each a prediction over its horizon with no further burns, so a burn already
    commanded that prevents an approach does not count): per ERROR criterion ``held`` (no check failed it),
    ``checks``, ``failed_checks`` and the ``first_failed_epoch`` [s] (None: never failed)."""
    out = {}
    for name in ERROR_CRITERIA:
        failed = [time_to_sec(s.header.stamp) for s in truth_checks if name in s.violations]
        out[name] = {"held": bool(truth_checks) and not failed, "checks": len(truth_checks),
                     "failed_checks": len(failed), "first_failed_epoch": min(failed) if failed else None}
    return out


def actual_approach(rtn, truth, ejection_epoch, keep_out):
    """What happened, from the truth's relative states (``/sim/truth/rtn``, ``[(log_time, msg), ...]``, every
    ``truth_period`` and right after each burn) from the ejection on
    (:func:`roe_sep.core.safety.approach.actual_approach`: HCW between the samples, the chief's mean motion of the
    truth's first ``a``): ``closest_approach`` (smallest local minimum of the distance after the departure from the
    keep-out sphere, or after the ejection for a pair that never left it: ``distance`` [m], ``epoch`` [s],
    ``at_end`` (still approaching at the end), ``bound`` [m], the refinement's), ``nearest`` (the same over every
    local minimum after the ejection, before the departure too: the comparand of a collision), ``after_first_orbit``
    (the closest from one orbit after the ejection), ``departure_epoch``, ``keep_out_time`` [s] and
    ``keep_out_entries`` after the departure, ``keep_out_violated``, ``keep_out_radius`` [m], ``sampling``
    (``truth_step`` the largest sampling interval, ``scan_step`` [s], ``refine_error`` [m]: the largest mismatch of
    the HCW arcs); None without an ejection or two truth samples after it."""
    if ejection_epoch is None or not len(truth):
        return None
    msgs = [m for _, m in rtn]
    t = np.array([time_to_sec(m.header.stamp) for m in msgs], dtype=float)
    pos = np.array([[m.position.x, m.position.y, m.position.z] for m in msgs], dtype=float).reshape(-1, 3)
    vel = np.array([[m.velocity.x, m.velocity.y, m.velocity.z] for m in msgs], dtype=float).reshape(-1, 3)
    n = float(mean_motion(truth.a[0]))
    ap = _approach(t, pos, vel, n, keep_out, start=ejection_epoch)
    if ap is None:
        return None
    orbit = ejection_epoch + 2.0 * math.pi / n
    later = ap.minima[ap.minima[:, 0] >= max(orbit, ap.departure_epoch or orbit)]
    k = int(np.argmin(later[:, 1])) if later.size else None
    return {
        "closest_approach": None if ap.closest_distance is None else {
            "distance": ap.closest_distance, "epoch": ap.closest_epoch, "at_end": ap.closest_at_end,
            "bound": ap.closest_error_m},
        "nearest": None if ap.nearest[0] is None else {
            "distance": ap.nearest[0], "epoch": ap.nearest[1], "bound": ap.nearest[2]},
        "after_first_orbit": None if k is None else {
            "distance": float(later[k, 1]), "epoch": float(later[k, 0]), "bound": float(later[k, 2])},
        "departure_epoch": ap.departure_epoch,
        "keep_out_time": ap.keep_out_s,
        "keep_out_entries": ap.keep_out_entries,
        "keep_out_violated": ap.keep_out_violated,
        "keep_out_radius": float(keep_out),
        "sampling": {"truth_step": ap.truth_step_s, "scan_step": ap.step, "refine_error": ap.refine_error_m},
    }


@contextlib.contextmanager
def paused_gc():
    """No cyclic garbage collection inside: building a report makes some 100,000 objects (the decoded messages)
    that all live until it is built, and every full collection meanwhile would only walk them and the rest of the
    heap again (a third of the report's CPU time). Collection resumes on exit (if it was on)."""
    if not gc.isenabled():
        yield
        return
    gc.disable()
    try:
        yield
    finally:
        gc.enable()


def build_report(bag_dir, duration=None, limits: MonitorLimits = MonitorLimits()):
    with paused_gc():
        return _build_report(bag_dir, duration, limits)


def _build_report(bag_dir, duration, limits):
    topics = (interfaces.EXECUTED_TOPIC, interfaces.TRUTH_ROE_TOPIC, interfaces.TRUTH_RTN_TOPIC,
              interfaces.DIAGNOSTICS_TOPIC,
              interfaces.SAFETY_TOPIC, interfaces.PLAN_CHECK_TOPIC, interfaces.OD_TOPIC,
              interfaces.ACQUISITION_PLAN_TOPIC, interfaces.DRIFT_STOP_PLAN_TOPIC, interfaces.EJECTION_ESTIMATE_TOPIC)
    data = read_topics(bag_dir, topics, raw=(interfaces.TRUTH_ROE_TOPIC,))
    truth = read_truth(data.pop(interfaces.TRUTH_ROE_TOPIC))
    data = valid_only(data)

    maneuvers = []
    for _, m in data[interfaces.EXECUTED_TOPIC]:
        dv = [m.dv_rtn.x, m.dv_rtn.y, m.dv_rtn.z]
        maneuvers.append({"purpose": m.purpose, "spacecraft": m.spacecraft, "epoch": time_to_sec(m.epoch),
                          "u_deg": math.degrees(m.mean_arg_latitude), "dv_rtn": dv, "dv": float(np.linalg.norm(dv))})
    maneuvers.sort(key=lambda x: x["epoch"])
    carrier = [m for m in maneuvers if m["spacecraft"] == "carrier"]
    by_purpose = {}
    for m in carrier:
        by_purpose[m["purpose"]] = by_purpose.get(m["purpose"], 0.0) + m["dv"]
    ejection = next((m for m in maneuvers if m["purpose"] == "ejection"), None)
    ic_burns = [m for m in carrier if m["purpose"] == "ic_acquisition"]

    final_roe = truth.final_roe

    sim_status = [s for _, d in data[interfaces.DIAGNOSTICS_TOPIC] for s in d.status if s.name == "roe_sep/sim"]
    late = [s.message for s in sim_status if "executed late" in s.message or "not executed" in s.message]
    # the simulator's final status (scenario complete/aborted) holds the run's closest approach; the last one
    # received when the run did not end
    final_status = next((s for s in reversed(sim_status) if s.message.startswith("scenario ")),
                        sim_status[-1] if sim_status else None)
    values = {kv.key: kv.value for kv in final_status.values} if final_status else {}
    min_distance = float(values.get("min_distance_m", "nan"))

    truth_checks = [s for _, s in data[interfaces.SAFETY_TOPIC] if s.source == "truth"]
    failed_ever = {name for s in truth_checks for name in s.violations}
    last = truth_checks[-1] if truth_checks else None
    plan_checks = [s for _, s in data[interfaces.PLAN_CHECK_TOPIC]]
    criteria = {name: bool(truth_checks) and name not in failed_ever for name in ERROR_CRITERIA}
    criteria["min_distance"] = not math.isnan(min_distance) and min_distance >= limits.keep_out  # inf: no approach
    criteria["plans_approved"] = bool(plan_checks) and all(s.safe for s in plan_checks)
    safe = all(criteria[name] for name in (*ERROR_CRITERIA, "min_distance", "plans_approved"))
    # what was seen to fail, as opposed to a criterion without evidence yet (a run stopped early)
    seen = set(failed_ever) & set(ERROR_CRITERIA)
    if not math.isnan(min_distance) and min_distance < limits.keep_out:
        seen.add("min_distance")
    if any(not s.safe for s in plan_checks):
        seen.add("plans_approved")
    truth_da_dot = float(values.get("truth_a_da_dot_m_per_day", "nan"))
    ic = initial_conditions(truth, data[interfaces.ACQUISITION_PLAN_TOPIC], ic_burns, truth_da_dot, limits,
                            run_end=duration)
    criteria["ic_reached"] = bool(ic and ic["reached"])
    model_error = {
        "drift_stop": planner_model_error(data[interfaces.DRIFT_STOP_PLAN_TOPIC], truth, truth_da_dot),
        "ic": planner_model_error(data[interfaces.ACQUISITION_PLAN_TOPIC], truth, truth_da_dot),
    }

    final_od = final_od_decision(data[interfaces.DIAGNOSTICS_TOPIC])
    od = data[interfaces.OD_TOPIC]
    od_report = None
    if od:
        burn_epochs = [m["epoch"] for m in maneuvers]
        od_report = {**od_solution(od[0][1], truth, truth_da_dot, burn_epochs), "solutions": len(od),
                     "last": od_solution(od[-1][1], truth, truth_da_dot, burn_epochs)}

    return {
        "safe": bool(safe),
        "criteria": criteria,
        "violations_seen": sorted(seen),
        "maneuvers": maneuvers,
        "dv_total": float(sum(m["dv"] for m in carrier)),
        "dv_by_purpose": by_purpose,
        "ejection_epoch": ejection["epoch"] if ejection else None,
        # ejection to the IC epoch, when the truth meets the ICs there (None: not reached, or no plan or ejection)
        "time_to_ic": (ic["epoch"] - ejection["epoch"]) if (ic and ic["reached"] and ejection) else None,
        "final_roe": final_roe,
        "final_epoch": truth.stamps[-1] if len(truth) else None,
        "min_distance": min_distance if math.isfinite(min_distance) else None,  # None: no approach after departure
        "min_distance_epoch": float(values.get("min_distance_time_s", "nan")),
        "truth_drag_a_da_dot_m_per_day": truth_da_dot,
        "dispersions": dispersions_applied(values.get("dispersions_applied")),
        "contingency": contingency_applied(data[interfaces.DIAGNOSTICS_TOPIC]),
        "contingencies_detected": contingencies_detected(data[interfaces.DIAGNOSTICS_TOPIC]),
        "passive_safety": passive_safety_verdicts(truth_checks),
        "actual_approach": actual_approach(data[interfaces.TRUTH_RTN_TOPIC], truth,
                                           ejection["epoch"] if ejection else None, limits.keep_out),
        "od": od_report,
        # the ground filter's executed ejection from the footage against the executed one (None: no footage)
        "ejection_estimate": ejection_estimate(data[interfaces.EJECTION_ESTIMATE_TOPIC], ejection),
        "ic": ic,
        "model_error": model_error,  # planners' prediction - truth [m] at the drift-stop and at the IC epoch
        "final_od": final_od,  # the drift-trim decision of the OD just before the IC epoch
        "ic_predicted_a_da": predicted_ic_drift(final_od, model_error["ic"]),
        "execution_warnings": late,  # burns executed late or dropped (unapproved), from the simulator
        "end_violations": list(last.violations) if last is not None else None,  # informational (drag drift on)
        "plan_checks": [{"source": s.source, "plan_stamp": time_to_sec(s.plan_stamp), "safe": s.safe,
                         "violations": list(s.violations)} for s in plan_checks],
        "duration": duration,
    }
