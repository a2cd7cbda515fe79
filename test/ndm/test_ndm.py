"""CCSDS navigation data messages (roe_sep.ndm): frames against independent two-body computations, the set of the
reference bag read back through the library, the OPM Delta-v against the plans, the TDM fed back into the batch
OD, malformed TDMs, atomic files and the ``roe-sep export`` command."""

import json
import math
import os
import time
from pathlib import Path

import numpy as np
import pytest
from oracle import kepler_to_cartesian

from roe_sep import interfaces
from roe_sep.cli import main
from roe_sep.cli.export import read_run
from roe_sep.core.constants import MU_EARTH, R_EARTH
from roe_sep.core.frames import gcrf_to_eme2000, gcrs_to_itrs
from roe_sep.core.od.batch import DragModel, RadarBatch, batch_least_squares
from roe_sep.core.od.radar import TIRA, julian_date
from roe_sep.core.od.sensor import chief_from_samples
from roe_sep.core.relmotion.maneuvers import delta_roe
from roe_sep.core.relmotion.orbit import mean_motion
from roe_sep.core.relmotion.roe import kepler_to_roe, roe_to_kepler
from roe_sep.core.truth.nonlinear import vallado_band
from roe_sep.ndm import frames
from roe_sep.ndm import messages as ndm
from roe_sep.ndm.dataset import Options, Truth, approved, kepler, kepler_rows, roe_of, roe_rows, vec
from roe_sep.nodes.parameters import table
from roe_sep.stamps import time_to_sec

BAG = Path(__file__).resolve().parents[2] / "bags" / "default_run"
EPOCH = "2016-07-01T00:00:00"
A = 6893137.0
INC = math.radians(97.46)


def cartesian_to_kepler(r, v):
    """[a, e, i, raan, argp, M] of an inertial state (Vallado Alg. 9), the test's own inverse of the oracle."""
    h = np.cross(r, v)
    n = np.cross([0.0, 0.0, 1.0], h)
    rn, vn = np.linalg.norm(r), np.linalg.norm(v)
    e_vec = ((vn**2 - MU_EARTH / rn) * r - np.dot(r, v) * v) / MU_EARTH
    e = np.linalg.norm(e_vec)
    a = 1.0 / (2.0 / rn - vn**2 / MU_EARTH)
    i = math.acos(h[2] / np.linalg.norm(h))
    raan = math.atan2(n[1], n[0])
    argp = math.atan2(np.dot(np.cross(n, e_vec), h) / np.linalg.norm(h), np.dot(n, e_vec))
    nu = math.atan2(np.dot(np.cross(e_vec, r), h) / np.linalg.norm(h), np.dot(e_vec, r))
    ecc = 2.0 * math.atan2(math.sqrt(1 - e) * math.sin(nu / 2), math.sqrt(1 + e) * math.cos(nu / 2))
    return np.array([a, e, i, raan, argp, ecc - e * math.sin(ecc)])


def propagate_two_body(el, dt):
    out = np.array(el, dtype=float)
    out[5] += math.sqrt(MU_EARTH / el[0] ** 3) * dt
    return out


# --- frames -------------------------------------------------------------------------------------------------------
def test_eme2000_is_the_gcrf_turned_by_the_frame_bias():
    """The export's EME2000 = B r_GCRF with ERFA's frame bias (bp00's rb): a rotation of 23 mas, 0.8 m at the
    carrier's radius; the carrier's state is rotated by it and by nothing else."""
    import erfa

    b = gcrf_to_eme2000()
    np.testing.assert_allclose(b, erfa.bp00(2451545.0, 0.0)[0], atol=0)
    angle = math.acos((np.trace(b) - 1.0) / 2.0)
    assert angle / (math.pi / 180 / 3600) * 1e3 == pytest.approx(23.0, abs=1.0)  # mas
    chief = np.array([A, 0.0, INC, 1.1, 0.0, 0.7])
    r, _ = frames.chief_state(chief, EPOCH, 1000.0)
    r0, _ = kepler_to_cartesian(chief)
    assert 0.5 < np.linalg.norm(r - r0) < 1.0 and np.linalg.norm(r - b @ r0) < 1e-6


def test_rtn_velocity_is_the_rotating_frame_derivative_of_two_body_states():
    """inertial_to_rtn of two independently propagated two-body orbits: its velocity is d(rho)/dt in the rotating
    frame (central differences), and rtn_to_inertial inverts it exactly."""
    chief = np.array([A, 0.001, INC, 1.1, 0.4, 0.3])
    deputy = np.array([A + 120.0, 0.0012, INC + 1e-4, 1.1002, 0.5, 0.2995])

    def rel(dt):
        rc, vc = kepler_to_cartesian(propagate_two_body(chief, dt))
        rd, vd = kepler_to_cartesian(propagate_two_body(deputy, dt))
        return frames.inertial_to_rtn(rc, vc, rd, vd), (rc, vc, rd, vd)

    (rho, rho_dot), (rc, vc, rd, vd) = rel(0.0)
    h = 0.5
    numeric = (rel(h)[0][0] - rel(-h)[0][0]) / (2 * h)
    assert np.linalg.norm(rho) > 3000.0
    assert np.max(np.abs(rho_dot - numeric)) < 1e-6  # m/s; the omega x rho term alone is ~3.5 m/s here
    r2, v2 = frames.rtn_to_inertial(rc, vc, rho, rho_dot)
    assert np.max(np.abs(r2 - rd)) < 1e-7 and np.max(np.abs(v2 - vd)) < 1e-10


def test_deputy_state_of_roe_matches_two_body_to_second_order():
    """Chief mean elements as a circular two-body orbit plus the linear ROE map: the picosatellite's EME2000 state
    agrees with the two-body state of its own Keplerian elements (roe_to_kepler) to O(rho^2 / a)."""
    roe = np.array([-40.0, 900.0, -20.0, -590.0, 14.0, 400.0]) / A
    chief = np.array([A, 0.0, INC, 1.1, 0.0, 0.7])
    t = 3600.0
    rd, vd = frames.deputy_state(roe, chief, EPOCH, t)
    rd0, vd0 = kepler_to_cartesian(roe_to_kepler(chief, roe))
    p = gcrf_to_eme2000()
    rho = np.linalg.norm(roe) * A
    rc, vc = frames.chief_state(chief, EPOCH, t)
    rc0, vc0 = kepler_to_cartesian(chief)
    assert np.linalg.norm(rd - p @ rd0) < 3.0 * rho**2 / A + 0.1  # 0.4 m for 1.2 km
    # the velocities carry the J2 secular rates (du/dt = 1.0013 n): relative velocities agree
    assert np.linalg.norm((vd - vc) - p @ (vd0 - vc0)) < 3.0 * rho**2 / A * mean_motion(A) + 5e-3
    assert np.linalg.norm(rc - p @ rc0) < 1e-6 and 5.0 < np.linalg.norm(vc - p @ vc0) < 15.0


def test_inertial_dv_changes_the_roe_as_gauss_eq2():
    """A carrier Delta-v in its RTN frame, rotated to inertial and added to an independent two-body state, changes
    the orbit as seed 002 Eq. (2) predicts (-dv: the carrier's burn on the relative orbit), to second order."""
    chief = np.array([A, 0.0, INC, 1.1, 0.0, 0.9])
    dv_rtn = np.array([0.05, -0.08, 0.03])
    r, v = kepler_to_cartesian(chief)
    dv = frames.dv_rtn_to_inertial(r, v, dv_rtn)
    assert np.allclose(frames.dv_inertial_to_rtn(r, v, dv), dv_rtn, atol=1e-15)
    after = cartesian_to_kepler(r, v + dv)
    before = cartesian_to_kepler(r, v)
    picosat_rel = kepler_to_roe(after, before)  # the picosatellite stays: its ROE w.r.t. the burnt carrier
    expected = delta_roe(-dv_rtn, chief[4] + chief[5], A, mean_motion(A))
    assert np.max(np.abs(picosat_rel - expected)) * A < 0.02  # m, vs changes of ~100 m
    assert np.max(np.abs(expected)) * A > 50.0


def test_roe_covariance_maps_like_samples():
    """The ROE covariance mapped to EME2000 equals the sample covariance of mapped ROE samples (the map is
    linear in the ROE)."""
    rng = np.random.default_rng(3)
    chief = np.array([A, 0.0, INC, 1.1, 0.0, 0.7])
    cov = np.diag(np.array([3.0, 20.0, 5.0, 5.0, 4.0, 4.0]) ** 2) / A**2
    samples = rng.multivariate_normal(np.full(6, 1e-4), cov, 20000)
    r, v = frames.deputy_state(samples, np.broadcast_to(chief, (20000, 6)), EPOCH, 100.0)
    emp = np.cov(np.hstack([r, v]).T)
    mapped = frames.roe_covariance_to_inertial(cov, chief, EPOCH, 100.0)
    sig = np.sqrt(np.diag(mapped))
    assert np.max(np.abs(emp - mapped) / np.outer(sig, sig)) < 0.05


def test_epochs_are_iso_strings_both_ways():
    assert frames.utc_string(EPOCH, 9156.408687832) == "2016-07-01T02:32:36.408688"
    assert frames.sim_time(EPOCH, "2016-07-01T02:32:36.408688") == pytest.approx(9156.408688, abs=1e-9)
    assert frames.sim_time(EPOCH, "2016-183T02:32:36.5Z") == pytest.approx(9156.5)
    with pytest.raises(ValueError, match="not a CCSDS UTC epoch"):
        frames.sim_time(EPOCH, "yesterday")


# --- the set of the reference bag -----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def run():
    return read_run(BAG)


@pytest.fixture(scope="module", params=["xml", pytest.param("kvn", marks=pytest.mark.slow)])  # kvn: make test
def exported(request, tmp_path_factory):
    out = tmp_path_factory.mktemp(f"ndm_{request.param}")
    assert main(["export", str(BAG), "--out", str(out), "--format", request.param]) == 0
    return request.param, out


def set_names(run):
    """The files of the reference bag's set: two OPMs (RTN and EME2000) per approved plan, then the executed burns'
    OPM, the ephemeris, the radar TDM and the closest approach's CDM."""
    plans = [f"plan{k:02d}_{p.strategy}{frame}.opm" for k, (_, p) in enumerate(approved(run), start=1)
             for frame in ("", "_eme2000")]
    return [*plans, "executed_carrier.opm", "ephemeris.oem", "radar.tdm", "closest_approach.cdm"]


def test_truth_rows_equal_the_per_message_arrays_to_the_bit(run):
    """roe_rows/kepler_rows (Truth's arrays; roe_of/kepler are one row of them) are the per-message formulas, each
    message's fields through NumPy alone, bit for bit, and empty for none."""
    msgs = run[interfaces.TRUTH_ROE_TOPIC]
    assert len(msgs) > 100
    want = np.array([np.array([m.a_da, m.a_dl, m.a_dex, m.a_dey, m.a_dix, m.a_diy], dtype=float)
                     / m.chief.semi_major_axis for m in msgs])
    assert np.array_equal(roe_rows(msgs).view(np.uint64), want.view(np.uint64))
    assert all(np.array_equal(roe_of(m).view(np.uint64), w.view(np.uint64)) for m, w in zip(msgs[:50], want))
    want = np.array([np.array([c.semi_major_axis, c.eccentricity, c.inclination, c.raan, c.arg_perigee,
                               c.mean_arg_latitude - c.arg_perigee], dtype=float) for c in (m.chief for m in msgs)])
    assert np.array_equal(kepler_rows([m.chief for m in msgs]).view(np.uint64), want.view(np.uint64))
    assert all(np.array_equal(kepler(m.chief).view(np.uint64), w.view(np.uint64)) for m, w in zip(msgs[:50], want))
    assert roe_rows([]).shape == (0, 6) and kepler_rows([]).shape == (0, 6)
    assert len(Truth([])) == 0


def test_export_writes_the_set_and_it_reads_back(exported, run):
    fmt, out = exported
    names = sorted(p.name for p in out.iterdir())
    assert len(approved(run)) >= 3  # the separation plan and at least two acquisition plans
    assert names == sorted(f"{n}.{fmt}" for n in set_names(run))
    for p in out.iterdir():
        text = p.read_text()
        assert "NP.FLOAT64" not in text and "np.float64" not in text
        msg = ndm.read_message(p)
        assert type(msg).__name__ in ("Opm", "Oem", "Tdm", "Cdm")
    oem = ndm.read_message(out / f"ephemeris.oem.{fmt}")
    segs = oem.body.segment
    assert {s.metadata.ref_frame for s in segs} == {"EME2000"} and {s.metadata.time_system for s in segs} == {"UTC"}
    ids = [s.metadata.object_id for s in segs]
    assert ids[0] == "CARRIER" and "PICOSATELLITE" in ids and "PICOSATELLITE-OD" in ids
    od = [s for s in segs if s.metadata.object_id == "PICOSATELLITE-OD"]
    assert len(od) == 5 and all(len(s.data.covariance_matrix) == 1 for s in od)
    assert all("T" in s.metadata.start_time and " " not in s.metadata.start_time for s in segs)


def test_oem_truth_reproduces_the_relative_orbit(exported, run):
    """Carrier and picosatellite truth states of the OEM, back through inertial_to_rtn, give the bag's truth RTN
    state of the linear map at the same epoch: radial and along-track to 0.1 m, normal to 2e-4 of the distance. The
    carrier's velocity carries the nodal regression (the derivative of its positions), so the plane of r x v is
    tilted from the mean orbit's by up to r (d raan/dt) / v = 1.8e-4 rad: a reader's RTN frame is that one."""
    fmt, out = exported
    segs = ndm.read_message(out / f"ephemeris.oem.{fmt}").body.segment

    def states(seg):
        return {round(frames.sim_time(EPOCH, s.epoch), 3): (np.array([s.x.value, s.y.value, s.z.value]) * 1e3,
                                                            np.array([s.x_dot.value, s.y_dot.value,
                                                                      s.z_dot.value]) * 1e3)
                for s in seg.data.state_vector}

    carrier, pico = {}, {}
    for s in segs:
        if s.metadata.object_id == "CARRIER":
            carrier.update(states(s))
        elif s.metadata.object_id == "PICOSATELLITE":
            pico.update(states(s))
    truth = Truth(run[interfaces.TRUTH_ROE_TOPIC])
    k = int(np.searchsorted(truth.t, 100000.0))
    t = round(float(truth.t[k]), 3)
    rho, rho_dot = frames.inertial_to_rtn(*carrier[t], *pico[t])
    exp_rho, exp_dot = frames.roe_rtn_state(truth.roe[k], truth.chief[k])
    assert np.max(np.abs(rho - exp_rho)[:2]) < 0.1 and abs(rho[2] - exp_rho[2]) < 2e-4 * np.linalg.norm(exp_rho)
    assert np.max(np.abs(rho_dot - exp_dot)) < 0.01
    # the carrier's state from its mean elements (near-circular, radial distance a): a of that truth sample, which
    # the nonlinear truth's drag lowers over the run
    assert np.linalg.norm(carrier[t][0]) == pytest.approx(truth.chief[k, 0], abs=1e-3)


def test_opm_dv_equals_the_plans_to_one_micrometer_per_second(exported, run):
    """Every approved plan's OPM: RTN dv as planned, and the EME2000 dv rotated back with the OPM's own carrier
    state (propagated two-body to the burn epoch) as planned; the executed OPM carries the executed burns."""
    fmt, out = exported
    plans = approved(run)
    assert [p.strategy for _, p in plans] == ["double_impulse"] + ["ic_acquisition"] * (len(plans) - 1)
    assert len(plans) >= 3
    worst = 0.0
    for k, (_, plan) in enumerate(plans, start=1):
        burns = [m for m in plan.maneuvers if m.spacecraft == "carrier" and np.any(vec(m.dv_rtn))]
        for suffix in ("", "_eme2000"):
            opm = ndm.read_message(out / f"plan{k:02d}_{plan.strategy}{suffix}.opm.{fmt}")
            seg = opm.body.segment
            mans = seg.data.maneuver_parameters
            assert len(mans) == len(burns)
            assert seg.metadata.ref_frame == "EME2000" and seg.metadata.time_system == "UTC"
            sv = seg.data.state_vector
            r0 = np.array([sv.x.value, sv.y.value, sv.z.value]) * 1e3
            v0 = np.array([sv.x_dot.value, sv.y_dot.value, sv.z_dot.value]) * 1e3
            t0 = frames.sim_time(EPOCH, sv.epoch)
            mass = seg.data.spacecraft_parameters.mass.value
            for m, b in zip(mans, burns):
                t = frames.sim_time(EPOCH, m.man_epoch_ignition)
                assert t == pytest.approx(time_to_sec(b.epoch), abs=1e-6)
                dv = np.array([m.man_dv_1.value, m.man_dv_2.value, m.man_dv_3.value]) * 1e3
                assert m.man_delta_mass.value < 0 and m.man_duration.value == 0.0
                mass += m.man_delta_mass.value
                if suffix:
                    assert m.man_ref_frame == "EME2000"
                    assert abs(np.linalg.norm(dv) - np.linalg.norm(vec(b.dv_rtn))) < 1e-9
                    if t == pytest.approx(t0, abs=1e-6):  # the OPM's own state is at the first burn: RTN back
                        worst = max(worst, float(np.max(np.abs(frames.dv_inertial_to_rtn(r0, v0, dv)
                                                                - vec(b.dv_rtn)))))
                else:
                    assert m.man_ref_frame == "RTN"
                    worst = max(worst, float(np.max(np.abs(dv - vec(b.dv_rtn)))))
            assert 0.0 < seg.data.spacecraft_parameters.mass.value - mass < 1.0
    assert worst < 1e-6
    # the EME2000 file's own carrier state at each burn: the RTN dv back exactly (same state, same rotation)
    executed = {time_to_sec(m.epoch): vec(m.dv_rtn) for m in run[interfaces.EXECUTED_TOPIC]
                if m.spacecraft == "carrier"}
    opm = ndm.read_message(out / f"executed_carrier.opm.{fmt}").body.segment.data.maneuver_parameters
    report = json.loads(BAG.with_suffix(".report.json").read_text())
    assert len(opm) == len(executed) == sum(m["spacecraft"] == "carrier" for m in report["maneuvers"]) >= 3
    for m in opm:
        t = frames.sim_time(EPOCH, m.man_epoch_ignition)
        dv = np.array([m.man_dv_1.value, m.man_dv_2.value, m.man_dv_3.value]) * 1e3
        key = min(executed, key=lambda e: abs(e - t))
        assert abs(key - t) < 1e-6 and np.max(np.abs(dv - executed[key])) < 1e-6


def test_eme2000_dv_is_the_rtn_dv_rotated_with_the_carrier_state(run):
    """The inertial dv of an OPM equals M dv_rtn with the carrier's exported state at the burn (1e-6 m/s)."""
    from roe_sep.ndm.dataset import plan_opm

    truth = Truth(run[interfaces.TRUTH_ROE_TOPIC])
    _, plan = approved(run)[0]
    inertial = plan_opm(plan, truth, Options(), frames.INERTIAL_FRAME).body.segment.data
    m = inertial.maneuver_parameters[0]
    sv = inertial.state_vector  # the state is at the first burn
    r = np.array([sv.x.value, sv.y.value, sv.z.value]) * 1e3
    v = np.array([sv.x_dot.value, sv.y_dot.value, sv.z_dot.value]) * 1e3
    dv = np.array([m.man_dv_1.value, m.man_dv_2.value, m.man_dv_3.value]) * 1e3
    assert np.max(np.abs(frames.dv_inertial_to_rtn(r, v, dv) - vec(plan.maneuvers[0].dv_rtn))) < 1e-9


def test_cdm_is_the_runs_closest_approach(exported):
    fmt, out = exported
    cdm = ndm.read_message(out / f"closest_approach.cdm.{fmt}")
    rel = cdm.body.relative_metadata_data
    # the simulator's own tracking (10 s steps) of the nonlinear truth reported 2755.275 m at t = 6340 s; the set
    # maps the truth's ROE to positions linearly (first order in rho/a, seed 002 Eq. 2): the difference is of the
    # order of the second-order term rho^2/a = 1.1 m (measured 1.19 m)
    rho, a = 2755.275, 6893137.0
    assert rel.miss_distance.value == pytest.approx(rho, abs=2.0 * rho**2 / a)
    assert frames.sim_time(EPOCH, rel.tca) == pytest.approx(6340.0, abs=10.0)
    assert [s.metadata.ref_frame.value for s in cdm.body.segment] == ["EME2000", "EME2000"]


def _radar_rows(run, t_from, t_to):
    return sorted((m for m in run[interfaces.RADAR_TOPIC] if t_from <= time_to_sec(m.header.stamp) <= t_to),
                  key=lambda m: time_to_sec(m.header.stamp))


def _radar_chief(truth: Truth, t, burns):
    """The chief radar_od used at each epoch: under lockstep the truth stream is its clock, so a measurement at t
    was simulated from the first truth sample at or after t (of two at one epoch, the post-burn one) and the sample
    before it, each propagated to t with its secular model and blended in time (chief_from_samples; the
    later sample alone across a burn of ``burns``, the executed epochs)."""
    last = np.searchsorted(truth.t, np.unique(truth.t), side="right") - 1  # the post-burn sample of an epoch
    hist_t, hist_kep = truth.t[last].tolist(), truth.chief[last]
    return np.array([chief_from_samples(hist_t, hist_kep, sorted(burns), float(tk))[0] for tk in np.atleast_1d(t)])


def _batch(t, z, sigma, truth: Truth, burns):
    jd0 = julian_date(EPOCH)
    t = np.asarray(t, dtype=float)
    return RadarBatch(t=t, z=np.asarray(z), sigma=np.asarray(sigma), chief=_radar_chief(truth, t, burns),
                      earth=gcrs_to_itrs(jd0, t), site_ef=np.tile(TIRA.ecef, (t.size, 1)),
                      site_enu=np.tile(TIRA.enu, (t.size, 1, 1)))


def test_tdm_fed_back_gives_the_runs_od_solution(exported, run):
    """The TDM of export, read back, gives radar_od's first solution: the measurements after the drift-stop up to
    the estimate epoch, the batch least squares of core/od/batch.py."""
    fmt, out = exported
    od = min(run[interfaces.OD_TOPIC], key=lambda o: time_to_sec(o.estimate.header.stamp))
    t_est = time_to_sec(od.estimate.header.stamp)
    last_burn = max(time_to_sec(m.epoch) for m in run[interfaces.EXECUTED_TOPIC] if time_to_sec(m.epoch) <= t_est)
    meas = [m for m in ndm.read_tdm(out / f"radar.tdm.{fmt}", EPOCH) if last_burn <= m.t <= t_est]
    assert len(meas) == od.measurements == 117 and len({m.pass_id for m in meas}) == od.passes == 3
    truth = Truth(run[interfaces.TRUTH_ROE_TOPIC])
    batch = _batch([m.t for m in meas], [m.z for m in meas],
                   [(m.sigma_range, m.sigma_angle, m.sigma_angle) for m in meas], truth,
                   [time_to_sec(m.epoch) for m in run[interfaces.EXECUTED_TOPIC]])
    # radar_od's drag model: Vallado's scale height at the carrier's altitude and the configured ballistic ratio
    ratio = table("radar_od")["drag_ballistic_ratio"].default
    model = DragModel(vallado_band(batch.chief[-1, 0] - R_EARTH)[2], ratio)
    result = batch_least_squares(batch, model=model)
    x, _ = result.mean_state()  # the mean ROE radar_od publishes (with drag's short-periodic de)
    a = od.estimate.chief.semi_major_axis
    est = np.array([getattr(od.estimate, k) for k in ("a_da", "a_dl", "a_dex", "a_dey", "a_dix", "a_diy")])
    sigma = np.sqrt(np.diag(np.reshape(od.estimate.covariance, (6, 6))))
    assert result.t_est == t_est
    assert np.max(np.abs(x[:6] * a - est)) < 1e-3  # m, against 1-sigma of meters
    assert np.max(np.abs(x[:6] * a - est) / sigma) < 1e-3
    assert result.x[6] * a == pytest.approx(od.a_da_dot, rel=1e-4, abs=1e-9)
    # and the TDM values are the bag's to rounding
    bag = _radar_rows(run, last_burn, t_est)
    assert np.max(np.abs(np.array([m.z for m in meas]) - [[b.range, b.azimuth, b.elevation] for b in bag])
                  / [1.0, 1e-6, 1e-6]) < 1e-6


@pytest.mark.parametrize("text, match", [
    ("this is not a message", "not a readable CCSDS NDM"),
    ("CCSDS_OPM_VERS = 2.0\n", "not a readable|expected a TDM"),
    ("CCSDS_TDM_VERS = 2.0\nthis is not a TDM\n", "no RANGE/ANGLE_1/ANGLE_2 measurement"),
])
def test_malformed_input_is_a_clear_error(text, match):
    with pytest.raises(ndm.NdmError, match=match):
        ndm.read_tdm(text, EPOCH)


def _tdm_text(fmt="kvn", **kw):
    p = ndm.TrackingPass("TIRA", 4, np.array([10.0, 20.0]), np.array([[1.7e6, 2.4, 0.19], [1.6e6, 2.5, 0.2]]),
                         10.0, 1.7e-4)
    return ndm.to_text(ndm.build_tdm(EPOCH, [p]), fmt)


def test_tdm_checks_units_time_system_and_completeness():
    text = _tdm_text()
    ms = ndm.read_tdm(text, EPOCH)
    assert [(m.t, m.station, m.pass_id) for m in ms] == [(10.0, "TIRA", 4), (20.0, "TIRA", 4)]
    assert ms[0].sigma_angle == pytest.approx(1.7e-4) and ms[0].sigma_range == 10.0
    with pytest.raises(ndm.NdmError, match="TIME_SYSTEM TDB is not supported"):
        ndm.read_tdm(text.replace("= UTC", "= TDB"), EPOCH)
    with pytest.raises(ndm.NdmError, match="REFERENCE_FRAME None is not supported for RADEC"):
        ndm.read_tdm(text.replace("= AZEL", "= RADEC"), EPOCH)
    with pytest.raises(ndm.NdmError, match="ANGLE_TYPE RADEC is not supported for radar measurements"):
        ndm.read_tdm(text.replace("= AZEL", "= RADEC\nREFERENCE_FRAME = EME2000"), EPOCH)
    dropped = "\n".join(line for line in text.splitlines() if not line.startswith("ANGLE_2") or "00:20" not in line)
    with pytest.raises(ndm.NdmError, match="ANGLE_1 and ANGLE_2 come in pairs"):
        ndm.read_tdm(dropped, EPOCH)
    no_sigma = "\n".join(line for line in text.splitlines() if "SIGMA" not in line)
    with pytest.raises(ndm.NdmError, match="no positive measurement sigma"):
        ndm.read_tdm(no_sigma, EPOCH)
    assert ndm.read_tdm(no_sigma, EPOCH, sigma_range=5.0, sigma_angle=1e-4)[0].sigma_range == 5.0
    assert ndm.read_tdm(_tdm_text("xml"), EPOCH) == ms


def test_write_is_atomic(tmp_path, monkeypatch):
    target = tmp_path / "a.opm.xml"
    ndm.write_atomic(target, "first")
    assert target.read_text() == "first" and (target.stat().st_mode & 0o044) == 0o044

    def fail(*_):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", fail)
    with pytest.raises(OSError, match="disk full"):
        ndm.write_atomic(target, "second")
    assert target.read_text() == "first" and sorted(p.name for p in tmp_path.iterdir()) == ["a.opm.xml"]


def test_numbers_go_in_as_plain_floats():
    with pytest.raises(ValueError, match="non-finite"):
        ndm._f(float("nan"))
    assert type(ndm._f(np.float64(1.5))) is float


def test_export_bad_input_exits_2(tmp_path, capsys):
    assert main(["export", str(tmp_path / "none"), "--out", str(tmp_path / "o")]) == 2
    assert "no such bag" in capsys.readouterr().err
    assert main(["export", str(BAG), "--out", str(tmp_path / "o"), "--epoch-utc", "July"]) == 2
    assert "--epoch-utc" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["export", str(BAG), "--out", str(tmp_path / "o"), "--format", "json"])
    assert exc.value.code == 2


# --- an independent reader: Orekit's NDM parsers (scripts/orekit_check.py) ---------------------------------------
ORE_CHECK = Path(__file__).resolve().parents[2] / "scripts" / "orekit_check.py"


def _orekit_read(*paths):
    import json
    import subprocess
    import sys

    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ORE_CHECK.parents[1]),
                                                                      os.environ.get("PYTHONPATH")])))
    proc = subprocess.run([sys.executable, str(ORE_CHECK), "--json", *map(str, paths)], capture_output=True,
                          text=True, timeout=600, env=env)
    assert proc.stdout, f"orekit_check printed nothing (exit {proc.returncode}): {proc.stderr[-2000:]}"
    return proc.returncode, {Path(p).name: e for p, e in json.loads(proc.stdout)["files"].items()}


def _broken_copies(out, fmt, dest):
    """Three files Orekit must refuse: an OPM without its mandatory TIME_SYSTEM, an OPM whose REF_FRAME is no
    CCSDS frame name, a TDM whose ANGLE_TYPE is not one the standard defines."""
    dest.mkdir()
    opm = (out / f"plan01_double_impulse.opm.{fmt}").read_text()
    tdm = (out / f"radar.tdm.{fmt}").read_text()
    if fmt == "xml":
        no_ts = opm.replace("<TIME_SYSTEM>UTC</TIME_SYSTEM>", "")
        frame = opm.replace("<REF_FRAME>EME2000</REF_FRAME>", "<REF_FRAME>J2000_OF_DATE</REF_FRAME>")
        angle = tdm.replace("<ANGLE_TYPE>AZEL</ANGLE_TYPE>", "<ANGLE_TYPE>AZIMUTH_ELEVATION</ANGLE_TYPE>")
    else:
        no_ts = "\n".join(line for line in opm.splitlines() if not line.startswith("TIME_SYSTEM"))
        frame = opm.replace("= EME2000", "= J2000_OF_DATE")
        angle = tdm.replace("= AZEL", "= AZIMUTH_ELEVATION")
    for name, text, original in (("no_time_system.opm", no_ts, opm), ("unknown_frame.opm", frame, opm),
                                 ("bad_angle_type.tdm", angle, tdm)):
        assert text != original
        (dest / f"{name}.{fmt}").write_text(text)
    return dest


@pytest.mark.slow
def test_orekit_reads_the_set_as_written_and_refuses_broken_files(exported, run, tmp_path):
    """Orekit's parsers (ParserBuilder) read all ten files of the reference bag in XML and KVN, with the frame and
    time system names of the standard, and give in SI the values the library reads: the OPM Delta-v equals the
    approved plans' to 1 um/s, the OEM segments and covariances, the TDM measurements and the CDM miss distance are
    ours; three broken copies are refused (so the check can fail)."""
    fmt, out = exported
    rc, files = _orekit_read(out, _broken_copies(out, fmt, tmp_path / "broken"))
    assert rc == 1
    bad = {n: e for n, e in files.items() if not e["ok"]}
    assert sorted(bad) == sorted(f"{n}.{fmt}" for n in ("no_time_system.opm", "unknown_frame.opm",
                                                         "bad_angle_type.tdm")), bad
    assert "TIME_SYSTEM" in bad[f"no_time_system.opm.{fmt}"]["error"]
    assert "J2000_OF_DATE" in bad[f"unknown_frame.opm.{fmt}"]["error"]
    assert "ANGLE_TYPE" in bad[f"bad_angle_type.tdm.{fmt}"]["error"]
    good = {n: e["read"] for n, e in files.items() if e["ok"]}
    assert sorted(good) == sorted(p.name for p in out.iterdir()) and len(good) == len(set_names(run))
    assert {e["format"] for e in files.values()} == {fmt}

    # OPM: frames, time system, the plans' Delta-v (Orekit converts km/s to m/s itself)
    worst = 0.0
    for k, (_, plan) in enumerate(approved(run), start=1):
        burns = [m for m in plan.maneuvers if m.spacecraft == "carrier" and np.any(vec(m.dv_rtn))]
        for suffix, frame in (("", "RTN"), ("_eme2000", "EME2000")):
            opm = good[f"plan{k:02d}_{plan.strategy}{suffix}.opm.{fmt}"]
            assert (opm["ref_frame"], opm["time_system"], opm["center"]) == ("EME2000", "UTC", "EARTH")
            assert len(opm["maneuvers"]) == len(burns) and opm["mass_kg"] == 140.0
            for m, b in zip(opm["maneuvers"], burns):
                assert m["ref_frame"] == frame and m["delta_mass_kg"] < 0 and m["duration_s"] == 0.0
                assert frames.sim_time(EPOCH, m["epoch_ignition"]) == pytest.approx(time_to_sec(b.epoch), abs=1e-6)
                if suffix:
                    assert abs(np.linalg.norm(m["dv_m_s"]) - np.linalg.norm(vec(b.dv_rtn))) < 1e-9
                else:
                    worst = max(worst, float(np.max(np.abs(np.array(m["dv_m_s"]) - vec(b.dv_rtn)))))
    assert worst < 1e-6
    report = json.loads(BAG.with_suffix(".report.json").read_text())
    assert len(good[f"executed_carrier.opm.{fmt}"]["maneuvers"]) == sum(
        m["spacecraft"] == "carrier" for m in report["maneuvers"]) >= 3

    # OEM: the library's segments, states and covariances (km^2... -> m^2...) as Orekit reads them
    ours = ndm.read_message(out / f"ephemeris.oem.{fmt}").body.segment
    theirs = good[f"ephemeris.oem.{fmt}"]["segments"]
    assert [s["object_id"] for s in theirs] == [s.metadata.object_id for s in ours]
    for o, t in zip(ours, theirs):
        assert (t["ref_frame"], t["time_system"], t["interpolation"]) == ("EME2000", "UTC", "HERMITE")
        assert t["n_states"] == len(o.data.state_vector)
        sv = o.data.state_vector[0]
        assert np.allclose(t["first_state"]["position_m"], np.array([sv.x.value, sv.y.value, sv.z.value]) * 1e3,
                           rtol=0, atol=1e-6)
        assert len(t["covariances"]) == len(o.data.covariance_matrix)
        for oc, tc in zip(o.data.covariance_matrix, t["covariances"]):
            c = np.array([[getattr(oc, f"c{ndm.COV_NAMES[max(i, j)]}_{ndm.COV_NAMES[min(i, j)]}").value
                           for j in range(6)] for i in range(6)]) * 1e6
            assert tc["ref_frame"] == "EME2000"
            assert np.allclose(tc["matrix_si"], c, rtol=1e-12, atol=0)
    assert sum(len(s["covariances"]) for s in theirs) == 5

    # TDM: participants, angle type and every measurement in SI (m, rad)
    meas = ndm.read_tdm(out / f"radar.tdm.{fmt}", EPOCH)
    segs = good[f"radar.tdm.{fmt}"]["segments"]
    assert {(s["participants"]["1"], s["participants"]["2"], s["angle_type"], s["time_system"]) for s in segs} == {
        ("TIRA", "PICOSATELLITE", "AZEL", "UTC")}
    got = sorted((frames.sim_time(EPOCH, o["epoch"]), o["value_si"]) for s in segs for o in s["observations"]["RANGE"])
    assert len(got) == len(meas) == sum(s["n_observations"] for s in segs) // 3
    assert np.max(np.abs(np.array(got) - [(m.t, m.z[0]) for m in meas])) < 1e-6
    az = sorted((frames.sim_time(EPOCH, o["epoch"]), o["value_si"] % (2 * math.pi)) for s in segs
                for o in s["observations"]["ANGLE_1"])
    assert np.max(np.abs(np.array(az) - [(m.t, m.z[1]) for m in meas])) < 1e-9

    # CDM: the library's miss distance, TCA and relative state
    rel = ndm.read_message(out / f"closest_approach.cdm.{fmt}").body.relative_metadata_data
    cdm = good[f"closest_approach.cdm.{fmt}"]
    assert cdm["miss_distance_m"] == pytest.approx(rel.miss_distance.value, abs=1e-9)
    assert frames.sim_time(EPOCH, cdm["tca"]) == pytest.approx(frames.sim_time(EPOCH, rel.tca), abs=1e-6)
    assert cdm["relative_position_rtn_m"] == pytest.approx(
        [rel.relative_state_vector.relative_position_r.value, rel.relative_state_vector.relative_position_t.value,
         rel.relative_state_vector.relative_position_n.value], abs=1e-9)
    assert [o["ref_frame"] for o in cdm["objects"]] == ["EME2000", "EME2000"]


# --- XML Schema validation (test/ndm_schema.py) --------------------------------------------------------------------
def _xml_of(path, fmt):
    """The file's XML: itself, or a KVN file read by the library and written as NDM/XML."""
    return path.read_text() if fmt == "xml" else ndm.to_text(ndm.read_message(path), "xml")


def _model_schemas():
    from ccsds_ndm.models import ndmxml2 as nd
    from ndm_schema import model_schema

    return {k: model_schema(c) for k, c in (("opm", nd.Opm), ("oem", nd.Oem), ("tdm", nd.Tdm), ("cdm", nd.Cdm))}


def test_the_set_validates_against_the_schema_of_the_ndm_models(exported, run):
    """All ten files (KVN: as read back and written in XML) are valid against the XML Schema written from ccsds-ndm's
    models of the NDM/XML 2.0.0 schemas: element order, mandatory elements, units, enumerations, the epoch pattern,
    MAN_DELTA_MASS < 0."""
    from ndm_schema import errors

    fmt, out = exported
    schemas = _model_schemas()
    files = sorted(out.iterdir())
    assert len(files) == len(set_names(run)) and {p.name.split(".")[-2] for p in files} == set(schemas)
    for p in files:
        assert errors(schemas[p.name.split(".")[-2]], _xml_of(p, fmt)) == [], p.name


def _small_opm():
    sc = ndm.SpacecraftParameters(140.0, 0.48, 2.3)
    burn = ndm.Burn(10.0, np.array([0.0, 0.01, 0.0]), "RTN", ndm.delta_mass([0.0, 0.01, 0.0], 140.0, 60.0))
    return ndm.build_opm("CARRIER", "CARRIER", EPOCH, 10.0, [A, 0.0, 0.0], v=[0.0, 7600.0, 0.0], burns=[burn],
                         spacecraft=sc)


@pytest.mark.parametrize("what, edit, match", [
    ("positive delta mass", lambda t: t.replace('<MAN_DELTA_MASS units="kg">-', '<MAN_DELTA_MASS units="kg">'),
     "MAN_DELTA_MASS.*maxExclusive"),
    ("epoch with a space", lambda t: t.replace("2016-07-01T00:00:10", "2016-07-01 00:00:10", 1), "EPOCH.*pattern"),
    ("numpy repr", lambda t: t.replace(">140.0<", ">NP.FLOAT64(140.0)<"), "MASS.*NP.FLOAT64"),
    ("missing CENTER_NAME", lambda t: t.replace("<CENTER_NAME>EARTH</CENTER_NAME>", ""), "Expected is .*CENTER_NAME"),
    ("unknown keyword", lambda t: t.replace("<MAN_DURATION", "<MAN_DURATION_X").replace(
        "</MAN_DURATION>", "</MAN_DURATION_X>"), "MAN_DURATION_X.*not expected"),
    ("velocity in m/s", lambda t: t.replace('units="km/s"', 'units="m/s"', 1), "units.*enumeration"),
    ("OPM version 3.0", lambda t: t.replace('version="2.0"', 'version="3.0"'), "fixed value"),
])
def test_schema_validation_refuses_broken_files(what, edit, match):
    """The check can fail: each edit of a valid OPM is refused with the rule it breaks; a numpy scalar handed to the
    library comes out as NP.FLOAT64(...) and is refused too (why messages.py converts every number)."""
    import re

    from ndm_schema import errors

    schema = _model_schemas()["opm"]
    text = ndm.to_text(_small_opm(), "xml")
    assert errors(schema, text) == []
    broken = edit(text)
    assert broken != text, what
    errs = errors(schema, broken)
    assert errs and any(re.search(match, e) for e in errs), (what, errs)
    opm = _small_opm()
    opm.body.segment.data.spacecraft_parameters.mass.value = np.float64(140.0)
    assert any("NP.FLOAT64" in e for e in errors(schema, ndm.to_text(opm, "xml")))


def test_the_set_validates_against_the_official_ndm_xml_schemas(exported, run):
    """Every exported file (KVN: as read back and written in XML) is valid against the official CCSDS NDM/XML 2.0.0
    schema set of the SANA registry (test/data/ndmxml-2.0.0, the unqualified variant), and every XML file names that
    set's master schema in ``xsi:noNamespaceSchemaLocation`` (CCSDS 505.0-B-2); a broken copy is refused."""
    from ndm_schema import errors, official_schema, schema_location

    fmt, out = exported
    schema = official_schema()
    files = sorted(out.iterdir())
    assert len(files) == len(set_names(run))
    for p in files:
        assert errors(schema, _xml_of(p, fmt)) == [], p.name
        if fmt == "xml":
            assert schema_location(p) == ndm.SCHEMA_LOCATION, p.name
    opm = _xml_of(out / f"plan01_double_impulse.opm.{fmt}", fmt)
    assert errors(schema, opm.replace('<MAN_DELTA_MASS units="kg">-', '<MAN_DELTA_MASS units="kg">'))


def test_live_set_final_set_started_early_is_the_export(tmp_path, run):
    """LiveSet.finish starts the final set (once, however often called), close waits for it: the files are the
    export's (apart from CREATION_DATE)."""
    from roe_sep.ndm.dataset import write_set
    from roe_sep.ndm.live import LiveSet

    errors = []
    live = LiveSet(tmp_path / "live", "xml", Options(), lambda: 1.0, errors.append)
    (tmp_path / "live").mkdir()
    for topic, msgs in run.by_topic.items():
        for m in msgs:
            live.add(topic, m)
    live.finish()
    live.finish()
    live.close()
    assert not errors and not live.writer.is_alive() and live.requests.empty()
    write_set(run, tmp_path / "export", "xml")

    def text(p):
        return [line for line in p.read_text().splitlines() if "CREATION_DATE" not in line]

    names = sorted(p.name for p in (tmp_path / "export").iterdir())
    assert sorted(p.name for p in (tmp_path / "live").iterdir()) == names and set(live.written) == {
        n[:-4] for n in names}
    for n in names:
        assert text(tmp_path / "live" / n) == text(tmp_path / "export" / n)


def test_live_set_complete_set_written_before_the_end_is_the_final_set(tmp_path, run):
    """A complete set written from every message (the ground_bridge's, when the scenario reports its end) is the final
    set: finish has nothing left to write. A message of the set that arrives after it is in the final set, written
    once more at finish; a complete set whose write failed is written again too."""
    from roe_sep.ndm.live import LiveSet

    def live_set(name):
        errors, writes = [], []
        live = LiveSet(tmp_path / name, "xml", Options(), lambda: 1.0, errors.append)
        (tmp_path / name).mkdir()
        write = live.write
        live.write = lambda periodic: (writes.append(periodic), write(periodic))
        return live, errors, writes

    msgs = [(t, m) for t, ms in run.by_topic.items() for m in ms]
    last_radar = max(k for k, (t, _) in enumerate(msgs) if t == interfaces.RADAR_TOPIC)
    early, late = msgs[:last_radar] + msgs[last_radar + 1:], [msgs[last_radar]]

    def wait_idle(live):
        deadline = time.monotonic() + 60.0
        while (not live.requests.empty() or live.complete != live.received) and time.monotonic() < deadline:
            time.sleep(0.01)

    # every message, then the complete set, then the end: written once
    live, errors, writes = live_set("once")
    for t, m in msgs:
        live.add(t, m)
    live.request(periodic=True)
    wait_idle(live)
    live.close()
    assert not errors and writes == [True] and live.complete == live.received == len(msgs)

    # the last radar measurement arrives after the complete set: the final set is written again and holds it
    live, errors, writes = live_set("late")
    for t, m in early:
        live.add(t, m)
    live.request(periodic=True)
    wait_idle(live)
    for t, m in late:
        live.add(t, m)
    live.close()
    assert not errors and writes == [True, True]

    def text(p):
        return [line for line in p.read_text().splitlines() if "CREATION_DATE" not in line]

    names = sorted(p.name for p in (tmp_path / "once").iterdir())
    assert sorted(p.name for p in (tmp_path / "late").iterdir()) == names and "radar.tdm.xml" in names
    for n in names:
        assert text(tmp_path / "late" / n) == text(tmp_path / "once" / n), n

    # a complete set that could not be written does not count: the final set is written at finish
    live, errors, writes = live_set("failed")
    for t, m in msgs:
        live.add(t, m)
    (tmp_path / "failed").rmdir()
    (tmp_path / "failed").write_text("not a directory")
    live.request(periodic=True)
    deadline = time.monotonic() + 60.0
    while not errors and time.monotonic() < deadline:
        time.sleep(0.01)
    (tmp_path / "failed").unlink()
    (tmp_path / "failed").mkdir()
    live.close()
    assert len(errors) == 1 and writes == [True, True] and live.complete == live.received
    assert (tmp_path / "failed" / "ephemeris.oem.xml").is_file()
