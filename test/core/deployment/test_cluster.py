"""Cluster separation program (seed 004): the probabilistic model against its statistical simulation."""

import dataclasses
import json

import numpy as np
import pytest
from scipy.integrate import quad

from roe_sep.core.config import ConfigError
from roe_sep.core.deployment.cluster import (
    ClusterConfig,
    Draws,
    cluster_config_from_dict,
    deterministic_bound,
    draw,
    load_cluster_config,
    mean_cos,
    pair_moments,
    pair_tables,
    platform_safe,
    position_moments,
    select_program,
    separation_velocity,
    simulate_program,
    simulated_platform_safety,
    simulated_positions,
    statistical_min_delay_difference,
)
from roe_sep.core.deployment.cluster_dynamics import drag_acceleration, hcw_matrix
from roe_sep.core.deployment.cluster_envelope import omega_bound, psi_extrema
from roe_sep.core.relmotion.dynamics import drag_da_dot
from roe_sep.core.relmotion.orbit import circular_speed, mean_motion

CFG = ClusterConfig()


def test_mean_cos_is_the_seed_quadrature():
    sigma, tau = np.radians(2.0), 17.0
    s = sigma * tau
    num = quad(lambda th: np.cos(th) * th / s**2 * np.exp(-th**2 / (2 * s**2)), 0, 40 * s, limit=200)[0]
    assert mean_cos(sigma, tau) == pytest.approx(num, abs=1e-10)


def test_drag_acceleration_is_the_seed_px_and_reuses_the_core():
    a = CFG.a
    assert drag_acceleration(-0.006, CFG.density, a) == pytest.approx(-CFG.density * circular_speed(a)**2 * 0.006)
    # the repo's convention: dB = B_NS - B_OS = 2 (Q_NS - Q_OS)
    assert drag_acceleration(-0.006, CFG.density, a) == pytest.approx(
        0.5 * mean_motion(a) * a * drag_da_dot(0.012, CFG.density, a))


def test_seed_pairwise_ballistic_differences_are_consistent():
    q = {s.name: s.delta_q for s in CFG.sats}  # Q_NS - Q_OS
    seed_pairs = {("ns2", "ns1"): 0.001, ("ns3", "ns1"): 0.002, ("ns3", "ns2"): 0.001, ("ns4", "ns1"): -0.002,
                  ("ns4", "ns2"): -0.003, ("ns4", "ns3"): -0.004}
    for (i, j), v in seed_pairs.items():
        assert q[i] - q[j] == pytest.approx(v)


def test_hcw_matrix_solves_the_equations():
    n, v = CFG.n, np.array([0.3, -0.7, 0.5])
    t = np.linspace(0, 6000, 601)
    r = hcw_matrix(t, n) @ v
    h = t[1] - t[0]
    acc = (r[2:] - 2 * r[1:-1] + r[:-2]) / h**2
    vel = (r[2:] - r[:-2]) / (2 * h)
    y = r[1:-1, 1]
    assert np.max(np.abs(acc[:, 0] + 2 * n * vel[:, 1])) < 1e-7  # x'' + 2 n y' = 0 (along-track)
    assert np.max(np.abs(acc[:, 1] - 2 * n * vel[:, 0] - 3 * n**2 * y)) < 1e-7
    assert np.max(np.abs(acc[:, 2] + n**2 * r[1:-1, 2])) < 1e-7
    assert np.all(hcw_matrix(np.array([-5.0, 0.0]), n) == 0.0)  # still on the OS before its separation


def test_analytical_moments_match_the_simulation():
    """Seed 004 Eqs. (1)-(2) against 200,000 sampled tumbling states (exact moments: agreement to sampling noise)."""
    dr = draw(CFG, 200_000, seed=3)
    s1, s2 = CFG.sats[0], CFG.sats[1]
    t = np.array([400.0, 3000.0, 6000.0])
    pos1 = simulated_positions(CFG, dr, s1, 20.0, t)
    p1 = drag_acceleration(-s1.delta_q, CFG.density, CFG.a)
    mean, var = position_moments(t, s1.velocity, np.array(20.0), p1, CFG.sigma, n=CFG.n)
    assert np.mean(pos1, axis=0) == pytest.approx(mean, abs=4 * np.sqrt(var.max() / 2e5) + 1e-6)
    assert np.var(pos1, axis=0) == pytest.approx(var, rel=0.03, abs=1e-6)
    pos2 = simulated_positions(CFG, dr, s2, 31.0, t)
    p2 = drag_acceleration(-s2.delta_q, CFG.density, CFG.a)
    pm, pv = pair_moments(t, s1.velocity, np.array(20.0), p1, s2.velocity, dtj=np.array(31.0), pj=p2, sigma=CFG.sigma,
                          n=CFG.n)
    rel = pos1 - pos2
    assert np.mean(rel, axis=0) == pytest.approx(pm, abs=4 * np.sqrt(pv.max() / 2e5) + 1e-6)
    assert np.var(rel, axis=0) == pytest.approx(pv, rel=0.03, abs=1e-6)
    # the covariance of the shared tumbling matters: independence would overstate the spread
    v = separation_velocity(dr, 1.0, 20.0)
    assert np.all(np.linalg.norm(v, axis=-1) == pytest.approx(1.0))


def test_deterministic_bound_holds_for_every_sample():
    dr = draw(CFG, 20_000, seed=5)
    s = CFG.sats[3]
    tau = np.arange(20.0, 3000.0, 20.0)
    r = simulated_positions(CFG, dr, s, 30.0, 30.0 + tau)
    bound = deterministic_bound(tau, s.velocity, drag_acceleration(-s.delta_q, CFG.density, CFG.a), CFG.n)
    assert np.all(np.linalg.norm(r, axis=-1) >= bound - 1e-9)


def test_omega_bound_is_the_rayleigh_p_star_quantile():
    sigma = np.radians(0.3)
    w = omega_bound(sigma, 0.997)
    assert 1.0 - np.exp(-w**2 / (2 * sigma**2)) == pytest.approx(0.997, abs=1e-12)
    dr = draw(CFG, 400_000, seed=4)
    assert np.mean(dr.omega <= CFG.omega_star) == pytest.approx(0.997, abs=4e-4)


def test_psi_extrema_against_a_dense_sweep():
    rng = np.random.default_rng(7)
    ux, uy, wx, wy, h = rng.normal(size=(5, 400)) * rng.uniform(0.1, 100, size=(5, 1))
    psi = np.linspace(0, 2 * np.pi, 20001)[:, None]
    s, c = np.sin(psi), np.cos(psi)
    f = (ux + s * wx) ** 2 + (uy + s * wy) ** 2 + (c * h) ** 2
    lo, hi = psi_extrema(ux, uy, wx, wy, h)
    # the closed form is the exact extremum: never beyond the sweep, and within its resolution of it
    assert np.all(lo <= f.min(axis=0) + 1e-9) and lo == pytest.approx(f.min(axis=0), rel=1e-4, abs=1e-9)
    assert np.all(hi >= f.max(axis=0) - 1e-9) and hi == pytest.approx(f.max(axis=0), rel=1e-4)


def _dense_states(cfg, n_omega=241, n_psi=121):
    o, p = np.meshgrid(np.linspace(0.0, cfg.omega_star, n_omega), np.linspace(0.0, 2 * np.pi, n_psi))
    return Draws(o.ravel(), p.ravel())


@pytest.mark.slow
def test_envelope_decides_like_the_states_it_covers():
    """Sound both ways on the stage condition: where the envelope says clear, no state of S* comes within r* (dense
    sweep); where it says not clear, a state of S* does (ns1 from 75 s: a tilt of ~76 deg towards -R brings it
    back within 7 m of the stage 2 h later; the found state is checked directly)."""
    s = CFG.sats[0]
    tau = np.arange(CFG.departure_time, CFG.horizon + 1.0, CFG.time_step)
    ok = platform_safe(CFG, s, np.array([60.0, 70.0, 80.0]))
    assert list(ok) == [True, True, False]
    dense = _dense_states(CFG)
    for dt in (60.0, 70.0):
        d = np.linalg.norm(simulated_positions(CFG, dense, s, dt, dt + tau), axis=-1)
        assert d.min() >= CFG.r_safe
    state = Draws(np.array([0.92625 * CFG.omega_star]), np.array([1.5 * np.pi]))
    d = np.linalg.norm(simulated_positions(CFG, state, s, 80.0, 80.0 + tau), axis=-1)
    assert d.min() < CFG.r_safe


@pytest.mark.parametrize("method", ["envelope", "gaussian"])
def test_analytical_platform_region_is_more_conservative_than_the_statistical_one(method):
    """Seed 004 Fig. 4: every delay the analytical model calls safe from the OS is safe in the simulation, and the
    analytical region is strictly smaller (measured at 0.3 deg/s: envelope up to 70 s, gaussian 80-95 s, statistical
    the whole grid to 120 s; the drag offset keeps almost every simulated NS km away from the stage)."""
    cfg = dataclasses.replace(ClusterConfig(), max_delay=120.0, delay_step=10.0, method=method)
    dr = draw(cfg, 2000, seed=1)
    d = cfg.delays
    for s in (cfg.sats[0], cfg.sats[3]):
        ana = platform_safe(cfg, s, d)
        stat = simulated_platform_safety(cfg, dr, s, d) >= cfg.p_required
        assert np.all(stat[ana])
        assert ana[0] and not np.all(ana) and np.all(stat)


@pytest.mark.slow
@pytest.mark.parametrize("method", ["envelope", "gaussian"])
def test_analytical_pair_region_is_more_conservative_when_the_lighter_drag_goes_first(method):
    """Pair safety (4), NS with the smaller ballistic coefficient separated first (ns1 then ns2, ns1 then ns3):
    the analytical minimum delay difference is at least the statistical one (measured: statistical 6 s, envelope
    6 s, gaussian 15-17 s; the pair is safe as soon as the head start V dt clears r*)."""
    cfg = dataclasses.replace(ClusterConfig(), max_delay=35.0, method=method)
    dr = draw(cfg, 2000, seed=2)
    for j in (1, 2):
        si, sj = cfg.sats[0], cfg.sats[j]
        safe, _, _ = pair_tables(cfg, si, sj)
        ana_min = cfg.delays[safe[0]][0] - cfg.min_delay
        stat_min = statistical_min_delay_difference(cfg, dr, si, sj, cfg.min_delay, differences=np.arange(1.0, 30.0))
        assert stat_min is not None and stat_min <= ana_min


@pytest.mark.slow
def test_envelope_pair_regions_lie_inside_the_statistical_ones():
    """The regions the seed's Gaussian model gets wrong (docs/seeds.md): with the heavier-drag NS first the envelope
    never calls the pair safe (a drag-driven crossing exists in S*), where the statistical P stays below or near P*; the
    largest delay difference within r** is at most the statistical one (measured 22/15/10 s vs 23/15/10 s from
    5/20/40 s)."""
    cfg = dataclasses.replace(ClusterConfig(), max_delay=70.0)
    dr = draw(cfg, 4000, seed=6)
    s1, s2 = cfg.sats[0], cfg.sats[1]
    d = cfg.delays
    safe, within, _ = pair_tables(cfg, s1, s2)
    for anchor in (5.0, 20.0, 40.0):
        i0 = int(np.flatnonzero(d == anchor)[0])
        dd = d - anchor
        assert not np.any(safe[:, i0] & (dd > 0))  # ns2 first, ns1 later: never safe with P* on S*
        ana_max = dd[within[i0] & (dd > 0)][-1]
        t = anchor + ana_max + np.arange(0.0, cfg.horizon + 1.0, cfg.time_step)
        rel = simulated_positions(cfg, dr, s1, anchor, t) - simulated_positions(cfg, dr, s2, anchor + ana_max, t)
        assert np.mean(np.max(np.linalg.norm(rel, axis=-1), axis=-1) <= cfg.r_max) >= cfg.p_required
    # heavier first from 22 s: the statistical pair is below P* at 6 and 10 s too (0.978 / 0.992 measured)
    assert statistical_min_delay_difference(cfg, dr, s2, s1, 22.0, differences=[6.0, 10.0]) is None


@pytest.fixture(scope="module")
def program():
    return select_program(ClusterConfig())


@pytest.mark.slow
def test_default_program(program):
    """The Soyuz-stage example: a feasible program, the cluster within r** and separated by the minimum delays."""
    assert program.feasible
    d = program.delays
    assert np.all(np.isfinite(d)) and len(set(d)) == 4
    assert np.nanmin(d[:3]) == CFG.min_delay  # the minimax picks the earliest separation
    assert d[3] > np.max(d[:3])  # the fourth NS after the cluster
    assert program.max_pair_distance <= CFG.r_max
    for (i, j), r in program.pair_regions.items():
        assert abs(d[i] - d[j]) >= r["min_delay_difference_s"]


@pytest.mark.slow
def test_program_statistics(program):
    """The envelope program holds jointly with P >= P*: every sampled state of S* meets every condition, and the
    simulated P* quantile of the largest cluster distance is below the analytical bound (measured 5587 vs 5623 m)."""
    dr = draw(CFG, 5000, seed=0)
    stat = simulate_program(CFG, program.delays, dr)
    assert stat["p_safe"] >= CFG.p_required
    assert stat["max_pair_distance_quantile"] <= program.max_pair_distance
    inside = dr.omega <= CFG.omega_star
    assert simulate_program(CFG, program.delays, Draws(dr.omega[inside], dr.psi[inside]))["p_safe"] == 1.0


@pytest.mark.slow
def test_gaussian_program():
    """The seed's model gives a program too (heavier-drag NS first, measured 5/22/37/43 s), which the statistical
    check finds below P* jointly (measured 0.983): the reason the envelope is the default."""
    cfg = dataclasses.replace(ClusterConfig(), method="gaussian")
    prog = select_program(cfg)
    assert prog.feasible and len(set(prog.delays)) == 4
    stat = simulate_program(cfg, prog.delays, draw(cfg, 3000, seed=0))
    assert all(p >= cfg.p_required for p in stat["p_platform"])
    assert 0.9 < stat["p_safe"] < cfg.p_required


def test_config_file_is_the_default():
    from pathlib import Path

    cfg = load_cluster_config(Path(__file__).resolve().parents[3] / "config" / "cluster.yaml")
    assert cfg == ClusterConfig()


@pytest.mark.parametrize("data,word", [({"sigma_deg_s": -1.0}, "sigma_deg_s"), ({"bogus": 1}, "bogus"),
                                       ({"sats": [{"velocity": 0.0, "delta_q": 0.0}]}, "velocity"),
                                       ({"r_max": 5.0}, "r_max"), ({"method": "normal"}, "method")])
def test_bad_config(data, word):
    with pytest.raises(ConfigError, match=word):
        cluster_config_from_dict(data)


@pytest.fixture()
def small_config(tmp_path):
    path = tmp_path / "cluster.yaml"
    path.write_text("max_delay: 50.0\n")
    return path


@pytest.mark.slow
def test_cli_json(capsys, small_config):
    import argparse

    from roe_sep.cli import analysis as cli_analysis

    parser = argparse.ArgumentParser()
    cli_analysis.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["cluster", "--json", "--samples", "0", "--config", str(small_config)])
    assert args.func(args) == 0
    rep = json.loads(capsys.readouterr().out)
    for key in ("delays_s", "velocities_mps", "p_safe", "max_pair_distance_m"):
        assert key in rep
    assert rep["velocities_mps"] == [2.0, 2.0, 2.0, 1.0]
    with pytest.raises(SystemExit):  # refused by the option's range, before any computation
        parser.parse_args(["cluster", "--p", "1.5"])
    assert "--p" in capsys.readouterr().err


@pytest.mark.slow
def test_cli_plots(capsys, small_config, tmp_path):
    """--plots writes the regions figure (seed 004 Figs. 3-4) and the program figure (Fig. 5)."""
    import argparse

    from roe_sep.cli import analysis as cli_analysis

    parser = argparse.ArgumentParser()
    cli_analysis.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["cluster", "--json", "--samples", "200", "--config", str(small_config),
                              "--plots", str(tmp_path)])
    assert args.func(args) == 0
    figures = json.loads(capsys.readouterr().out)["figures"]
    assert sorted(p.split("/")[-1] for p in figures) == ["cluster_program.png", "cluster_regions.png"]
    for f in figures:
        with open(f, "rb") as fh:
            assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
