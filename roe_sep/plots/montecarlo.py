"""Figures of the double-impulse Monte Carlo analysis in the layout of seed 002 Figs. 3-8 (seed 000 Figs. 4-9), as PNG
files."""

from pathlib import Path

import numpy as np

from ..core.montecarlo.sweep import SweepResult
from . import pyplot, save, subset


def _tag(p):
    return f"p{p:.4f}".replace(".", "_")


def fig_drift(res: SweepResult, p, path):
    """Residual a da vs mean along-track separation a dl after the drift-stop and ``horizon`` later (Figs. 4-6)."""
    plt = pyplot()
    out, a, cfg = res.outcomes[p], res.design.a, res.design.config
    idx = subset(out.roe_after_stop.shape[0])
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, roe, title in ((axes[0], out.roe_after_stop, "after drift-stop"),
                           (axes[1], out.roe_horizon, f"{res.mc.horizon / 3600:.0f} h after drift-stop")):
        ax.scatter(roe[idx, 1] * a, roe[idx, 0] * a, s=3, c="k")
        for x in (cfg.a_dl_min, cfg.a_dl_max):
            ax.axvline(x, color="tab:red", lw=1.5)
        ax.axhline(0.0, color="gray", lw=0.8)
        ax.set_xlabel("a dl [m]")
        ax.set_title(title)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("a da [m]")
    fig.suptitle(f"Residual a da vs mean tangential separation (p = {p:g} m/s, "
                 f"drag {'on' if res.mc.drag else 'off'})")
    save(fig, path)


def fig_ei(res: SweepResult, p, path):
    """Relative eccentricity and inclination magnitudes after the drift-stop with safety/visibility limits (Fig. 7)."""
    plt = pyplot()
    out, a, cfg, b = res.outcomes[p], res.design.a, res.design.config, res.design.bounds
    idx = subset(out.roe_after_stop.shape[0])
    r = out.roe_after_stop[idx]
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    ax.scatter(np.hypot(r[:, 2], r[:, 3]) * a, np.hypot(r[:, 4], r[:, 5]) * a, s=3, c="k")
    ax.axvline(cfg.min_rn_distance, color="tab:red", label="safety (min R-N)")
    ax.axhline(cfg.min_rn_distance, color="tab:red")
    ax.axvline(b.a_de_max, color="tab:blue", ls="--", label="visibility (FOV)")
    ax.axhline(b.a_di_max, color="tab:blue", ls="--")
    ax.set_xlabel("a de [m]")
    ax.set_ylabel("a di [m]")
    ax.set_title(f"Relative e/i after drift-stop (p = {p:g} m/s)")
    ax.legend(loc="lower right", fontsize=8)
    ax.grid(alpha=0.3)
    save(fig, path)


def fig_min_rn(res: SweepResult, p, path):
    """Minimum R-N distance (Eq. 25) vs residual a da (Fig. 8)."""
    plt = pyplot()
    out, a, cfg = res.outcomes[p], res.design.a, res.design.config
    idx = subset(out.roe_after_stop.shape[0])
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    ax.scatter(out.roe_after_stop[idx, 0] * a, out.min_rn[idx], s=3, c="k")
    ax.axhline(cfg.min_rn_distance, color="tab:red")
    ax.set_xlabel("a da after drift-stop [m]")
    ax.set_ylabel("minimum R-N distance [m]")
    ax.set_title(f"Minimum cross-track distance (p = {p:g} m/s)")
    ax.grid(alpha=0.3)
    save(fig, path)


def fig_crossing(res: SweepResult, path):
    """Along-track distance at the nearest R = 0 transit before the drift-stop vs the SPL factor f1 (Fig. 9)."""
    plt = pyplot()
    idx = subset(res.draws.f1.shape[0])
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    ax.scatter(res.draws.f1[idx], res.pre.crossing[idx], s=3, c="k")
    ax.axvline(1.0 - 3.0 * res.design.config.spl_sigma, color="tab:red", ls="--", label="3-sigma under-performance")
    ax.set_xlabel("SPL performance factor f1")
    ax.set_ylabel("|T| at nearest R = 0 transit [m]")
    ax.set_title("Nearest crossing of the R = 0 plane")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    save(fig, path)


def fig_p_sweep(res: SweepResult, path):
    """P(approaching drift) and P(evaporation) vs p (seed 002 Table 3 as a figure), p_best marked."""
    plt = pyplot()
    ps = [r["p"] for r in res.rows]
    floor = 0.5 / res.mc.samples  # show zero counts below the resolution of the run
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for key, label in (("p_approach", "approaching drift (a da > 0)"),
                       ("p_evaporation", f"evaporation (a dl > {res.mc.evaporation_distance / 1e3:g} km)")):
        ax.semilogy(ps, [max(r[key], floor) for r in res.rows], "o-", label=label)
    ax.semilogy(ps, [max(r["p_approach"] + r["p_evaporation"], floor) for r in res.rows], "k--", label="sum")
    ax.axvline(res.p_best, color="gray", ls=":", label=f"p_best = {res.p_best:g} m/s")
    ax.axhline(1.0 / res.mc.samples, color="lightgray", lw=0.8)
    ax.set_xlabel("drift-stop reduction p [m/s]")
    ax.set_ylabel("probability")
    ax.set_title(f"p sweep ({res.mc.samples} samples)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    save(fig, path)


def write_figures(res: SweepResult, directory: Path):
    """Write every figure for p = first of the sweep (usually 0) and p_best; returns the paths."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for p in dict.fromkeys([res.rows[0]["p"], res.p_best]):
        for name, fn in (("drift", fig_drift), ("ei", fig_ei), ("min_rn", fig_min_rn)):
            path = directory / f"{name}_{_tag(p)}.png"
            fn(res, p, path)
            paths.append(path)
    for name, fn in (("crossing", fig_crossing), ("p_sweep", fig_p_sweep)):
        path = directory / f"{name}.png"
        fn(res, path)
        paths.append(path)
    return paths
