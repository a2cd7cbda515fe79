"""Figures of the deployment analyses: the seed-003 deployment sweep (Figs. 4-6) and the seed-004 cluster program
(Fig. 4 layout), PNG."""

import dataclasses

import numpy as np

from . import pyplot, save


def deployment_figures(res, out_dir):
    """deploy_distance_<i>.png (seed 003 Fig. 5: distance vs time per angle, both dv) for each inclination and
    deploy_first_orbits.png (Figs. 4, 6b: the first three orbits after a radial and a V-bar deployment)."""
    from ..core.deployment.sweep import distance_curves
    from ..core.relmotion.orbit import mean_motion

    plt = pyplot()
    out_dir.mkdir(parents=True, exist_ok=True)
    cfg, paths = res.config, []
    days = res.times / 86400.0
    for ii, inc in enumerate(cfg.inclinations_deg):
        angles = list(cfg.angles_deg)
        shown = [k for k, a in enumerate(angles) if abs(a / 45.0 - round(a / 45.0)) < 1e-9] or list(range(len(angles)))
        cols = 4
        rows = int(np.ceil(len(shown) / cols))
        fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.5 * rows), sharex=True, squeeze=False)
        for ax, k in zip(axes.flat, shown):
            for jd, dv in enumerate(cfg.dv):
                ax.plot(days, res.distance[ii, jd, k] / 1e3, label=f"{dv:g} m/s")
            ax.set_title(f"deploy {angles[k]:g} deg", fontsize=9)
            ax.grid(alpha=0.3)
        for ax in axes.flat[len(shown):]:
            ax.axis("off")
        axes.flat[0].legend(fontsize=8)
        for ax in axes[-1]:
            ax.set_xlabel("time [day]")
        for ax in axes[:, 0]:
            ax.set_ylabel("distance [km]")
        fig.suptitle(f"CubeSat-mother craft distance, i = {inc:g} deg, {cfg.altitude / 1e3:.0f} km")
        path = out_dir / ("deploy_distance_i" + f"{inc:g}".replace(".", "p") + ".png")
        save(fig, path, dpi=100)
        paths.append(path)
    # first three orbits (baseline inclination): radial vs V-bar deployments, both dv
    n = mean_motion(cfg.a)
    t = np.linspace(0.0, 3 * 2 * np.pi / n, 1501)[1:]  # the departure (distance 0) is off the log scale
    fig, ax = plt.subplots(figsize=(7, 4))
    shown = [(k, jd) for k, ang in enumerate(cfg.angles_deg) if ang % 90 == 0 for jd in range(len(cfg.dv))]
    if shown:
        dv_rtn = np.stack([res.dv_rtn[0, jd, k] for k, jd in shown])
        curves = distance_curves(cfg, dv_rtn, np.radians(cfg.inclinations_deg[0]), t)
        for (k, jd), d in zip(shown, curves):
            ax.plot(t * n / (2 * np.pi), d / 1e3,
                    label=f"{cfg.angles_deg[k]:g} deg, {cfg.dv[jd]:g} m/s")
    ax.set_xlabel("orbits after deployment")
    ax.set_ylabel("distance [km]")
    ax.set_yscale("log")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2)
    ax.set_title("first three orbits: radial deployments return to the mother craft")
    path = out_dir / "deploy_first_orbits.png"
    save(fig, path, dpi=100)
    paths.append(path)
    return paths


def cluster_figures(prog, out_dir, samples=2000, seed=0):
    """cluster_regions.png (seed 004 Figs. 3-4: P(safe from the OS) vs delay, analytical condition vs statistical
    estimate) and cluster_program.png (Fig. 5: pair distances of the selected program, simulated, with the P* bound)."""
    from ..core.deployment.cluster import (
        METHODS,
        draw,
        pair_distance_bound,
        platform_safe,
        simulated_platform_safety,
        simulated_positions,
    )

    plt = pyplot()
    out_dir.mkdir(parents=True, exist_ok=True)
    cfg, paths = prog.config, []
    dr = draw(cfg, samples, seed)
    # the regions over a delay range wide enough to show where the analytical one ends
    wide = dataclasses.replace(cfg, max_delay=max(cfg.max_delay, 150.0), delay_step=5.0)
    d = wide.delays
    fig, ax = plt.subplots(figsize=(7, 4))
    for k, s in enumerate(cfg.sats):
        p = simulated_platform_safety(wide, dr, s, d)
        line, = ax.plot(d, p, label=f"{s.name} statistical (V = {s.velocity:g} m/s)")
        for m, (method, marker) in enumerate(zip(METHODS, "s^")):
            ok = platform_safe(dataclasses.replace(wide, method=method), s, d)
            ax.plot(d[ok], np.full(ok.sum(), 1.0 + 0.002 * (2 * k + m + 1)), marker, ms=3, color=line.get_color(),
                    label=f"{s.name} {method}: safe with P*")
    ax.axhline(cfg.p_required, color="k", ls="--", lw=0.8)
    ax.set_xlabel("separation delay [s]")
    ax.set_ylabel("P(safe from the OS)")
    ax.set_title("safe from the OS: analytical regions (envelope squares, gaussian triangles) and the "
                 "statistical P", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    path = out_dir / "cluster_regions.png"
    save(fig, path, dpi=100)
    paths.append(path)
    if prog.feasible:
        members = [i for i, s in enumerate(cfg.sats) if s.cluster]
        t = np.arange(np.nanmin(prog.delays), np.nanmax(prog.delays) + cfg.horizon, cfg.time_step)
        pos = {i: simulated_positions(cfg, dr, cfg.sats[i], prog.delays[i], t) for i in members}
        fig, ax = plt.subplots(figsize=(7, 4))
        for a_, i in enumerate(members):
            for j in members[a_ + 1:]:
                dist = np.linalg.norm(pos[i] - pos[j], axis=-1)
                q = np.quantile(dist, [1.0 - cfg.p_required, 0.5, cfg.p_required], axis=0)
                line, = ax.plot(t, q[1] / 1e3, label=f"{cfg.sats[i].name}-{cfg.sats[j].name} median")
                ax.fill_between(t, q[0] / 1e3, q[2] / 1e3, color=line.get_color(), alpha=0.2)
                bound = pair_distance_bound(cfg, cfg.sats[i], prog.delays[i], cfg.sats[j], prog.delays[j], t=t)
                ax.plot(t, bound / 1e3, ls="--", color=line.get_color(), lw=0.8)
        ax.axhline(cfg.r_max / 1e3, color="k", ls=":", lw=0.8)
        ax.set_xlabel("time from the start of the program [s]")
        ax.set_ylabel("pair distance [km]")
        ax.set_title(f"selected program: simulated median and (1-P*, P*) quantiles, {cfg.method} P* bound (dashed)",
                     fontsize=9)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
        path = out_dir / "cluster_program.png"
        save(fig, path, dpi=100)
        paths.append(path)
    return paths


# ------------------------------------------------------------------------------------------------ deploy-sweep
