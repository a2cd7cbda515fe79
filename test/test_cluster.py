"""Cluster separation program (seed 004): the probabilistic model against its statistical simulation."""

import dataclasses
import json

import numpy as np
import pytest
from scipy.integrate import quad

from roe_sep.core.cluster import (
    ClusterConfig,
    cluster_config_from_dict,
    deterministic_bound,
    drag_acceleration,
    draw,
    hcw_matrix,
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
from roe_sep.core.config import ConfigError
from roe_sep.core.dynamics import drag_da_dot
from roe_sep.core.orbit import circular_speed, mean_motion

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
    mean, var = position_moments(t, s1.velocity, np.array(20.0), p1, CFG.sigma, CFG.n)
    assert np.mean(pos1, axis=0) == pytest.approx(mean, abs=4 * np.sqrt(var.max() / 2e5) + 1e-6)
    assert np.var(pos1, axis=0) == pytest.approx(var, rel=0.03, abs=1e-6)
    pos2 = simulated_positions(CFG, dr, s2, 31.0, t)
    p2 = drag_acceleration(-s2.delta_q, CFG.density, CFG.a)
    pm, pv = pair_moments(t, s1.velocity, np.array(20.0), p1, s2.velocity, np.array(31.0), p2, CFG.sigma, CFG.n)
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


def test_analytical_platform_region_is_more_conservative_than_the_statistical_one():
    """Seed 004 Fig. 4: every delay the analytical model calls safe from the OS is safe in the simulation, and the
    analytical region is strictly smaller (measured at 0.3 deg/s: analytical up to 80-95 s, statistical the whole
    grid to 120 s; the P* box of the position spreads as the tumbling randomizes the direction, while the drag offset
    keeps every simulated NS km away from the stage)."""
    cfg = dataclasses.replace(ClusterConfig(), max_delay=120.0, delay_step=10.0)
    dr = draw(cfg, 2000, seed=1)
    d = cfg.delays
    for s in (cfg.sats[0], cfg.sats[3]):
        ana = platform_safe(cfg, s, d)
        stat = simulated_platform_safety(cfg, dr, s, d) >= cfg.p_required
        assert np.all(stat[ana])
        assert ana[0] and not np.all(ana) and np.all(stat)


def test_analytical_pair_region_is_more_conservative_when_the_lighter_drag_goes_first():
    """Pair safety (4), NS with the smaller ballistic coefficient separated first (ns1 then ns2, ns1 then ns3):
    the analytical minimum delay difference exceeds the statistical one (measured 15-17 s vs 6 s: the statistical
    pair is safe as soon as the head start V dt clears r*)."""
    cfg = dataclasses.replace(ClusterConfig(), max_delay=35.0)
    dr = draw(cfg, 2000, seed=2)
    for j in (1, 2):
        si, sj = cfg.sats[0], cfg.sats[j]
        safe, _, _ = pair_tables(cfg, si, sj)
        ana_min = cfg.delays[safe[0]][0] - cfg.min_delay
        stat_min = statistical_min_delay_difference(cfg, dr, si, sj, cfg.min_delay, np.arange(1.0, 30.0))
        assert stat_min is not None and stat_min < ana_min


@pytest.fixture(scope="module")
def program():
    return select_program(ClusterConfig())


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


def test_program_statistics(program):
    stat = simulate_program(CFG, program.delays, draw(CFG, 3000, seed=0))
    assert all(p >= CFG.p_required for p in stat["p_platform"])
    assert 0.9 < stat["p_safe"] <= 1.0


def test_config_file_is_the_default():
    from pathlib import Path

    cfg = load_cluster_config(Path(__file__).resolve().parents[1] / "config" / "cluster.yaml")
    assert cfg == ClusterConfig()


@pytest.mark.parametrize("data,word", [({"sigma_deg_s": -1.0}, "sigma_deg_s"), ({"bogus": 1}, "bogus"),
                                       ({"sats": [{"velocity": 0.0, "delta_q": 0.0}]}, "velocity"),
                                       ({"r_max": 5.0}, "r_max")])
def test_bad_config(data, word):
    with pytest.raises(ConfigError, match=word):
        cluster_config_from_dict(data)


@pytest.fixture()
def small_config(tmp_path):
    path = tmp_path / "cluster.yaml"
    path.write_text("max_delay: 50.0\n")
    return path


def test_cli_json(capsys, small_config):
    import argparse

    from roe_sep import cli_analysis

    parser = argparse.ArgumentParser()
    cli_analysis.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["cluster", "--json", "--samples", "0", "--config", str(small_config)])
    assert args.func(args) == 0
    rep = json.loads(capsys.readouterr().out)
    for key in ("delays_s", "velocities_mps", "p_safe", "max_pair_distance_m"):
        assert key in rep
    assert rep["velocities_mps"] == [2.0, 2.0, 2.0, 1.0]
    args = parser.parse_args(["cluster", "--p", "1.5"])
    with pytest.raises(ValueError, match="p_required"):
        args.func(args)


def test_cli_plots(capsys, small_config, tmp_path):
    """--plots writes the regions figure (seed 004 Figs. 3-4) and the program figure (Fig. 5)."""
    import argparse

    from roe_sep import cli_analysis

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
