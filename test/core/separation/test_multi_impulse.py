"""Multi-impulse design (seed 001 Sec. 3): SPL split, tangential carrier burns, burn limits, J2 diagnostics."""

import math

import numpy as np
import pytest

from roe_sep.core.relmotion.dynamics import j2_kappa, sun_synchronous_inclination
from roe_sep.core.relmotion.maneuvers import delta_roe
from roe_sep.core.relmotion.orbit import mean_motion, semi_major_axis
from roe_sep.core.relmotion.roe import e_vector_polar, i_vector_polar
from roe_sep.core.separation import multi_impulse as mi
from roe_sep.core.separation.double_impulse import SeparationConfig

D = mi.design()
A = 6378137.0 + 515e3
N = math.sqrt(3.986004418e14 / A**3)


def test_spl_split_hand_values():
    """|dv| = 1.53; normal n a di with di = tan(9.15 deg) 5 km; tangential >= e~ = 0.153; radial the rest (Eq. 12)."""
    dv = D.dv1_rtn
    assert np.linalg.norm(dv) == pytest.approx(1.53, rel=1e-12)
    assert dv[2] == pytest.approx(N * math.tan(math.radians(9.15)) * 5000.0, rel=1e-9)  # 0.88844 m/s
    assert dv[2] == pytest.approx(0.88844, abs=1e-5)
    assert D.dv_t_eq10 == pytest.approx(0.153, abs=1e-12)
    assert -dv[1] >= 0.153 and dv[1] < 0  # leading: outward drift (safety #2)
    assert dv[0] == pytest.approx(-math.sqrt(1.53**2 - dv[1] ** 2 - dv[2] ** 2), rel=1e-12)


def test_tangential_is_the_least_with_ac3_for_the_drift_free_sample():
    """At the chosen |dvT1| the drift-free (f1 = 1 - p/|dvT1|) orbit has min R-N = 150 m; smaller fails."""
    cfg = D.config
    a, inc = D.a, D.inc
    dvn = D.dv1_rtn[2]

    def rn(t):
        dv1 = np.array([mi.spl_radial(1.53, -t, dvn), -t, dvn])
        plan = mi.plan_carrier_burns(dv1, D.u1, 0.0, a, inc, sep=cfg, mcfg=D.multi, j2=True, da_dot=0.0)
        return mi.min_rn_distance(mi.drift_free_state(dv1, D.u1, a, inc, plan, sep=cfg)) * a

    t = D.dv_t_ac3
    assert rn(t) >= 149.0
    assert rn(0.9 * t) < 150.0


def test_ejection_at_pole_gives_no_dix_and_no_diy_drift():
    j = D.j2_effects()
    assert abs(j["a_dix_at_ejection"]) < 1e-6
    assert abs(j["a_diy_drift_m_per_day"]) < 1e-6
    # hand: a dix = 805.35 cos 88 deg = 28.1 m; d(diy)/dt = 2 kappa sin^2 i dix
    inc = float(sun_synchronous_inclination(A))
    per_m = 2 * float(j2_kappa(A)) * math.sin(inc) ** 2 * 86400.0
    assert j["a_diy_drift_per_m_dix_m_per_day"] == pytest.approx(per_m, rel=1e-12)
    assert j["a_diy_drift_m_per_day_if_u1_88deg"] == pytest.approx(per_m * D.dv1_rtn[2] / N * math.cos(
        math.radians(88.0)), rel=1e-9)
    assert 3.0 < j["a_diy_drift_m_per_day_if_u1_88deg"] < 4.0


def test_e_vector_rotation_about_3_5_deg_per_day_at_500_km():
    """Seed 001 Sec. 2.2: ~3.6 deg/day clockwise at 500 km SSO. Hand: kappa (5 cos^2 i - 1)."""
    a = semi_major_axis(500e3)
    inc = sun_synchronous_inclination(a)
    kap = 0.75 * mean_motion(a) * 1.08262668e-3 * (6378137.0 / a) ** 2
    rate = math.degrees(kap * (5 * math.cos(inc) ** 2 - 1) * 86400)
    assert rate == pytest.approx(-3.51, abs=0.01)
    d500 = mi.design(SeparationConfig(altitude=500e3))
    assert d500.j2_effects()["e_vector_rotation_deg_per_day"] == pytest.approx(rate, rel=1e-9)


def test_anti_parallel_target_and_pair_hand_values():
    np.testing.assert_allclose(mi.anti_parallel_target([-3.0, -1.0], [0.0, 2.0], 0.5), [0.0, -1.0])
    np.testing.assert_allclose(mi.anti_parallel_target([-3.0, -1.0], [0.0, 2.0], 2.0), [0.0, -2.0])
    # dde = (+1e-4, 0), da = -1e-5: first burn at u = pi, x1 = (S - D)/2 < 0 (outward), x2 = (S + D)/2 at u = 0
    u_a, x1, x2 = mi.tangential_pair(-1e-5, [1e-4, 0.0], N, A)
    assert u_a == pytest.approx(-math.pi) or u_a == pytest.approx(math.pi)
    d, s = N * A * 1e-4 / 2, N * A * 1e-5 / 2
    assert (x1, x2) == pytest.approx(((s - d) / 2, (s + d) / 2))
    total = delta_roe([0, x1, 0], u_a, A, N) + delta_roe([0, x2, 0], u_a + math.pi, A, N)
    np.testing.assert_allclose(total[[0, 2, 3]], [1e-5, 1e-4, 0.0], atol=1e-15)


def test_final_orbit_is_anti_parallel_drift_free_and_passively_safe():
    assert D.plan.burns[1].purpose == "e_vector_pair"
    fin = D.plan.roe_final * D.a
    de, phi = e_vector_polar(fin)
    di, theta = i_vector_polar(fin)
    assert abs(math.degrees(abs(((phi - theta) + math.pi) % (2 * math.pi) - math.pi)) - 180.0) < 1.0
    assert abs(fin[0]) < 10.0  # quantization + drag over the pair
    assert min(de, di) >= 150.0
    assert all(b.purpose == "drift_reduction" for b in D.plan.burns[:1])
    assert D.plan.burns[1].dv_relative_rtn[1] < 0  # the pair first lowers da (outward)


def test_thrusted_dv_near_the_tangential_lower_bound():
    """Tangential burns: sum |dvT| >= n a |Delta de| / 2; the radial SPL part's de_x = dvR/(n a) must be undone,
    so the total is ~|dvR1|/2 (seed 001: ~40 % of the ejection vs 95 % for the double impulse)."""
    bound = abs(D.dv1_rtn[0]) / 2
    assert bound - 0.005 <= D.thrusted_dv_total <= bound + 0.02
    assert D.thrusted_to_ejection_ratio == pytest.approx(D.thrusted_dv_total / 1.53)
    assert D.thrusted_to_ejection_ratio < 0.5


@pytest.mark.parametrize("leading", [True, False])
@pytest.mark.parametrize("u1", [90.0, 270.0])
@pytest.mark.parametrize("max_burn,spl", [(0.3, 1.53), (0.1, 1.53), (0.05, 1.53), (0.3, 1.45), (0.3, 1.7)])
def test_property_every_burn_within_limits_and_quantized(leading, u1, max_burn, spl):
    mcfg = mi.MultiImpulseConfig(spl_dv=spl, u1_deg=u1, max_burn=max_burn)
    d = mi.design(SeparationConfig(leading=leading), mcfg)
    assert d.plan.burns
    for b in d.plan.burns:
        dv = b.dv_carrier_rtn
        assert dv[0] == 0.0 and dv[2] == 0.0  # purely tangential
        assert abs(dv[1]) <= max_burn + 1e-12
        q = dv[1] / 1e-3
        assert abs(q - round(q)) < 1e-9
    assert [b.epoch for b in d.plan.burns] == sorted(b.epoch for b in d.plan.burns)


def test_property_split_burn():
    rng = np.random.default_rng(1)
    for dv in rng.uniform(-2.0, 2.0, 300):
        for mx in (0.3, 0.1, 0.0375):
            parts = mi.split_burn(dv, mx, 1e-3)
            assert all(abs(p) <= mx + 1e-12 and abs(p / 1e-3 - round(p / 1e-3)) < 1e-9 for p in parts)
            assert sum(parts) == pytest.approx(float(mi.quantize(dv, 1e-3)), abs=1e-9)
            assert len(parts) == math.ceil(round(abs(dv) / 1e-3) / math.floor(mx / 1e-3 + 1e-9))
    assert mi.split_burn(0.0004, 0.3, 1e-3) == []
    assert mi.split_burn(0.65, 0.3, 1e-3) == pytest.approx([0.217, 0.217, 0.216])


def test_bad_input_names_the_parameter():
    with pytest.raises(ValueError, match="max_burn"):
        mi.design(mcfg=mi.MultiImpulseConfig(max_burn=-0.3))
    with pytest.raises(ValueError, match="dv_quantum"):
        mi.design(mcfg=mi.MultiImpulseConfig(dv_quantum=0.5))
    with pytest.raises(ValueError, match="Eq. 12"):
        mi.design(mcfg=mi.MultiImpulseConfig(spl_dv=0.5))


def test_cli_design_and_mc_multi_impulse(capsys):
    import json

    from roe_sep.cli import main

    assert main(["design", "--strategy", "multi_impulse", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    for key in ("ejection_dv_rtn", "maneuvers", "thrusted_dv_total", "thrusted_to_ejection_ratio"):
        assert key in rep
    assert all({"dv_rtn", "u_deg", "epoch", "purpose"} <= m.keys() for m in rep["maneuvers"])
    assert main(["design", "--strategy", "multi_impulse"]) == 0
    assert "thrusted dv" in capsys.readouterr().out
    assert main(["mc", "--strategy", "multi_impulse", "--samples", "2000", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    # 2000 samples of seed 0: one nearly drift-free sample, above the 150 m of AC3 (seed 001 Sec. 4) as all are
    assert rep["ac1"] == 1.0 and rep["ac2"] == 1.0 and rep["ac3"] == 1.0
    assert (rep["n_drift_free"], rep["n_ac3_fail"]) == (1, 0) and rep["min_rn_min"] > 150.0
    assert main(["mc", "--strategy", "multi_impulse", "--p", "0.05"]) == 2
    assert "--p applies to the double_impulse" in capsys.readouterr().err


@pytest.mark.dds
def test_planner_node_multi_impulse_strategy(ros_context):
    """The planner process publishes every multi-impulse carrier burn as one ManeuverPlan (strategy parameter)."""
    from roe_sep_msgs.msg import EjectionEvent, ManeuverPlan
    from rosutil import rclpy, spin_until, start_node, stop_node, wait_exit

    from roe_sep import interfaces
    from roe_sep.nodes.convert import array_to_vector, sec_to_time, time_to_sec, vector_to_array

    code, out = wait_exit(start_node("planner", "-p", "strategy:=triple"))
    assert code == 2 and "'strategy'" in out
    node = rclpy.create_node("ground_multi_test")
    plans = []
    node.create_subscription(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, plans.append, interfaces.LATCHED)
    pub = node.create_publisher(EjectionEvent, interfaces.EJECTION_TOPIC, interfaces.LATCHED)
    planner = start_node("planner", "-p", "strategy:=multi_impulse")
    try:
        ev = EjectionEvent(dv_magnitude=1.53)
        ev.header.stamp = sec_to_time(1000.0)
        ev.ejection.epoch = sec_to_time(1000.0)
        ev.ejection.mean_arg_latitude = D.u1
        ev.ejection.dv_rtn = array_to_vector(D.dv1_rtn)
        ev.ejection.spacecraft, ev.ejection.purpose = "picosatellite", "ejection"
        ev.chief.semi_major_axis, ev.chief.inclination, ev.chief.mean_arg_latitude = D.a, D.inc, D.u1
        pub.publish(ev)
        assert spin_until(node, lambda: len(plans) >= 1, timeout=30)
        plan = plans[-1]
        assert plan.strategy == "multi_impulse"
        assert [m.purpose for m in plan.maneuvers] == [b.purpose for b in D.plan.burns]
        for m, b in zip(plan.maneuvers, D.plan.burns):
            np.testing.assert_allclose(vector_to_array(m.dv_rtn), b.dv_carrier_rtn, atol=1e-12)
            assert time_to_sec(m.epoch) == pytest.approx(1000.0 + b.epoch, abs=1e-3)
            assert abs(vector_to_array(m.dv_rtn)[1]) <= 0.3
        assert plan.p_reduction == pytest.approx(D.plan.p)
        # the PlanSeparation service designs the same plan (zero fields = the defaults), ejection first
        from roe_sep_msgs.srv import PlanSeparation

        client = node.create_client(PlanSeparation, interfaces.PLAN_SERVICE)
        assert client.wait_for_service(timeout_sec=20)
        future = client.call_async(PlanSeparation.Request(u1=D.u1, ejection_epoch=sec_to_time(1000.0)))
        assert spin_until(node, future.done, timeout=30)
        res = future.result()
        assert res.success, res.message
        assert res.plan.strategy == "multi_impulse"
        ejection, *burns = res.plan.maneuvers
        assert ejection.purpose == "ejection"
        np.testing.assert_allclose(vector_to_array(ejection.dv_rtn), D.dv1_rtn, atol=1e-12)
        assert [m.purpose for m in burns] == [b.purpose for b in D.plan.burns]
        for m, b in zip(burns, D.plan.burns):
            np.testing.assert_allclose(vector_to_array(m.dv_rtn), b.dv_carrier_rtn, atol=1e-12)
        future = client.call_async(PlanSeparation.Request(u1=D.u1, spl_dv=-1.0))
        assert spin_until(node, future.done, timeout=30)
        assert not future.result().success and "spl_dv" in future.result().message
    finally:
        code, out = stop_node(planner)
        node.destroy_node()
    assert code == 0, out
