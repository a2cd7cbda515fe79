"""Figures of the multi-impulse acceptance analysis: AC1-AC3 in the layout of seed 001 Figs. 4-6 (PNG)."""

from pathlib import Path

import numpy as np

from . import pyplot, save, subset


def fig_ac1(res, path):
    """AC1 (seed 001 Fig. 4): a da vs a dl after the ejection (gray) and the drift reduction (black); 24 h later."""
    plt = pyplot()
    a, cfg = res.design.a, res.design.config
    idx = subset(res.roe_after_reduction.shape[0])
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    axes[0].scatter(res.roe_after_ejection[idx, 1] * a, res.roe_after_ejection[idx, 0] * a, s=3, c="0.65",
                    label="after separation")
    axes[0].scatter(res.roe_after_reduction[idx, 1] * a, res.roe_after_reduction[idx, 0] * a, s=3, c="k",
                    label="after drift reduction")
    axes[1].scatter(res.roe_horizon[idx, 1] * a, res.roe_horizon[idx, 0] * a, s=3, c="k")
    axes[0].set_title("after separation / drift reduction")
    axes[1].set_title(f"{res.mc.horizon / 3600:.0f} h after drift reduction")
    for ax in axes:
        for x in (cfg.a_dl_min, cfg.a_dl_max):
            ax.axvline(x, color="tab:red", lw=1.2)
        ax.axhline(0.0, color="gray", lw=0.8)
        ax.set_xlabel("a dl [m]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("a da [m]")
    axes[0].legend(fontsize=8)
    fig.suptitle(f"AC1: a da < 0 after the drift reduction in {np.mean(res.ac1):.3%} of {res.mc.samples} samples")
    save(fig, path)


def fig_ac2(res, path):
    """AC2 (seed 001 Fig. 5): along-track distance at the nearest R = 0 transit vs SPL factor f1."""
    plt = pyplot()
    idx = subset(res.crossing.shape[0])
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    ax.scatter(res.draws.f1[idx], res.crossing[idx], s=3, c="k")
    ax.axhline(2000.0, color="tab:red", label="AC2: 2 km")
    ax.axvline(1.0 - 3.0 * res.design.config.spl_sigma, color="tab:red", ls="--", label="3-sigma under-performance")
    ax.set_xlabel("SPL performance factor f1")
    ax.set_ylabel("|T| at nearest R = 0 transit [m]")
    ax.set_title(f"AC2 satisfied in {np.mean(res.ac2):.3%}")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    save(fig, path)


def fig_ac3(res, path):
    """AC3 (seed 001 Fig. 6): minimum R-N distance (Eq. 25) vs a da after the drift reduction."""
    plt = pyplot()
    a, cfg = res.design.a, res.design.config
    idx = subset(res.min_rn.shape[0])
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    ax.scatter(res.roe_after_reduction[idx, 0] * a, res.min_rn[idx], s=3, c="k")
    free = np.flatnonzero(res.drift_free)
    ax.scatter(res.roe_after_reduction[free, 0] * a, res.min_rn[free], s=12, c="tab:orange",
               label=f"drift-free (|a da| < {res.drift_free_a_da:.0f} m), all {free.size}")
    ax.axhline(cfg.min_rn_distance, color="tab:red", label=f"{cfg.min_rn_distance:g} m")
    ax.axvspan(-res.drift_free_a_da, res.drift_free_a_da, color="tab:orange", alpha=0.1)
    ax.set_xlabel("a da after drift reduction [m]")
    ax.set_ylabel("minimum R-N distance [m]")
    ax.set_title("AC3: minimum cross-track distance")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    save(fig, path)


def write_acceptance_figures(res, directory: Path):
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, fn in (("multi_ac1", fig_ac1), ("multi_ac2", fig_ac2), ("multi_ac3", fig_ac3)):
        path = directory / f"{name}.png"
        fn(res, path)
        paths.append(path)
    return paths
