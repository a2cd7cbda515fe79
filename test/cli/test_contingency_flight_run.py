"""The contingencies of issue 41 part 6 in the closed loop (``roe_sep.run.run`` over DDS, as ``roe-sep run --seed 5
--config c.yaml`` with a ``contingency:`` block), each on a short run around the drift-stop: what the simulator
injected is in the report and acts on the truth, and the ground sees what it can. The pure parts:
test/core/truth/test_contingency_flight.py."""

import pytest
from rosutil import rclpy  # noqa: F401  (skips without rclpy)

from roe_sep.run import run

EJECTION = 604.4  # s, seed 5's executed ejection (test_golden)
DRIFT_STOP = 9156.4  # s, its drift-stop's epoch
ORBIT = 5690.0  # s, about


RESPONSE_OFF = "planner:\n  ros__parameters:\n    collision_avoidance: false\n    ejection_completion: false\n"


def short_run(tmp_path, name, block, duration=12000.0, params=None):
    """Seed 5 for ``duration`` [s] with the ``contingency:`` block ``block`` (YAML lines; ``block`` None: none) and
    the node-parameter YAML text ``params``, completed: the report and its findings by name."""
    config = None
    if block is not None:
        config = tmp_path / f"{name}.yaml"
        config.write_text("contingency:\n" + "".join(f"  {line}\n" for line in block), encoding="utf-8")
    params_file = None
    if params is not None:
        params_file = tmp_path / f"{name}_params.yaml"
        params_file.write_text(params, encoding="utf-8")
    rep = run(config=config, out=tmp_path / name, params=params_file, seed=5, duration=duration, timeout=900)
    assert rep["run"]["completed"], rep["run"]["reason"]
    return rep, {d["name"]: d for d in rep["contingencies_detected"]}


@pytest.mark.dds
def test_ejection_pointing_minus_7_deg_comes_back_at_one_orbit(tmp_path):
    """-7 deg about N cancels the design's along-track ejection component (-6.98 deg): no drift, the pair is back
    at the carrier one orbit after the release (6.1 m, seed 5), before the drift-stop; the planner's response to the
    footage off (the next test has it)."""
    rep, _ = short_run(tmp_path, "pointing", ["name: ejection_pointing", "angle_deg: -7.0"], params=RESPONSE_OFF)
    c = rep["contingency"]
    assert c["parameters"] == {"angle_deg": -7.0} and "turned by -7.00 deg about N" in c["events"][0]
    ejection = rep["maneuvers"][0]
    assert ejection["purpose"] == "ejection" and abs(ejection["dv_rtn"][1]) < 0.005  # the nominal T: -0.14 m/s
    closest = rep["actual_approach"]["closest_approach"]
    assert closest["distance"] < 20.0 and closest["epoch"] - EJECTION == pytest.approx(ORBIT, abs=100.0)


@pytest.mark.dds
def test_ejection_pointing_minus_7_deg_gets_the_cam(tmp_path):
    """The same turn with the planner's response (the default): the footage measures the ejection off its command
    in direction, its trajectory back inside the keep-out, so the carrier flies a CAM, one completion pulse and the
    CAM's reversal before the drift-stop; the truth never comes back inside the keep-out."""
    rep, detected = short_run(tmp_path, "pointing_cam", ["name: ejection_pointing", "angle_deg: -7.0"])
    assert "ejection_off" in detected and "in direction" in detected["ejection_off"]["text"]
    purposes = [m["purpose"] for m in rep["maneuvers"] if m["spacecraft"] == "carrier"]
    assert purposes[:4] == ["collision_avoidance", "ejection_completion", "collision_avoidance_reversal",
                            "drift_stop"]
    cam = rep["maneuvers"][1]
    assert cam["epoch"] - detected["ejection_off"]["epoch"] == pytest.approx(300.0, abs=1e-3)
    ap = rep["actual_approach"]
    assert not ap["keep_out_violated"] and ap["closest_approach"]["distance"] > 1000.0


@pytest.mark.dds
def test_carrier_safe_mode_loses_the_drift_stop_and_the_replacement_flies(tmp_path):
    """Safe mode for 6 h from the release: the drift-stop commanded into it is lost (the monitor's burn_missing);
    the planner's replacement three orbits later falls after the window and flies."""
    rep, detected = short_run(tmp_path, "safe_mode", ["name: carrier_safe_mode", "start_h: 0.0", "hours: 6.0"],
                              duration=30000.0)
    events = rep["contingency"]["events"]
    assert events[0].startswith("carrier safe mode from t = 604.4 s") and len(events) == 2
    assert f"drift_stop commanded at t = {DRIFT_STOP:.1f} s: not executed (carrier safe mode" in events[1]
    assert "burn_missing" in detected and "drift_stop_replaced" in detected
    stops = [m for m in rep["maneuvers"] if m["purpose"] == "drift_stop"]
    assert len(stops) == 1 and (stops[0]["epoch"] - DRIFT_STOP) / ORBIT == pytest.approx(3.0, abs=0.02)


@pytest.mark.dds
def test_drift_stop_overperformance_is_executed_and_seen(tmp_path):
    rep, detected = short_run(tmp_path, "over", ["name: drift_stop_overperformance", "magnitude: 1.3"])
    assert "1.300 of its magnitude" in rep["contingency"]["events"][0]
    ds = next(m for m in rep["maneuvers"] if m["purpose"] == "drift_stop")
    assert ds["dv"] == pytest.approx(1.3 * 1.3406, abs=1e-3)  # seed 5's drift-stop as executed: 1.3406 m/s
    assert "burn_magnitude" in detected and detected["burn_magnitude"]["epoch"] == pytest.approx(ds["epoch"], abs=0.1)


@pytest.mark.dds
def test_density_storm_drags_the_truth_only(tmp_path):
    """A storm five times the density over the 3 h after the release: the plans and burns are the nominal run's
    (nothing on the ground sees the truth's drag), the truth's da decays faster than in the nominal run."""
    nominal, _ = short_run(tmp_path, "nominal", None)
    rep, _ = short_run(tmp_path, "storm", ["name: density_storm", "factor: 5.0", "start_h: 0.0", "hours: 3.0"])
    assert rep["contingency"]["events"] == ["density storm x5.000 from t = 604.4 s to t = 11404.4 s"]
    assert [(m["epoch"], m["dv_rtn"]) for m in rep["maneuvers"]] == \
        [(m["epoch"], m["dv_rtn"]) for m in nominal["maneuvers"]]
    da, da0 = rep["final_roe"][0], nominal["final_roe"][0]
    drift = nominal["truth_drag_a_da_dot_m_per_day"] * 3.0 / 24.0  # the nominal differential drag over 3 h [m]
    assert drift < 0.0 and da - da0 == pytest.approx(4.0 * drift, rel=0.3)
