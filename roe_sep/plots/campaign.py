"""Figures of a closed-loop campaign (``roe-sep campaign``): the review set of a separation campaign.

* ``dv_hist.png``: carrier total dv per run (drift-stop + IC acquisition), with the 5/50/95 % percentiles;
* ``time_to_ic_hist.png``: ejection to the IC epoch [h], runs that reached the ICs there;
* ``ei_vs_along_track.png``: at the end of each run, the e/i separation (minimum R-N distance, seed 002 Eq. 25)
  against the mean along-track separation |a dl|, safe runs and unsafe runs in their own colours, with the IC
  limits (minimum R-N distance, along-track band).
"""

import math
from pathlib import Path

import numpy as np

from . import pyplot, save


def _values(rows, field, scale=1.0):
    return np.array([r[field] * scale for r in rows if r["status"] == "ok" and r.get(field) is not None])


def _hist(values, xlabel, title, path):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    if values.size:
        ax.hist(values, bins=max(5, min(40, int(np.sqrt(values.size)) * 2)), color="tab:blue", alpha=0.8)
        for q, style in ((5, ":"), (50, "--"), (95, ":")):
            v = np.percentile(values, q)
            ax.axvline(v, color="k", ls=style, lw=1, label=f"p{q} = {v:.4g}")
        ax.legend(fontsize=8)
    else:
        ax.text(0.5, 0.5, "no completed run with a value", ha="center", transform=ax.transAxes)
    ax.ticklabel_format(axis="x", useOffset=False)  # a narrow spread reads in the quantity's own values
    ax.set_xlabel(xlabel)
    ax.set_ylabel("runs")
    ax.set_title(f"{title} ({values.size} runs)")
    ax.grid(alpha=0.3)
    save(fig, path)


def fig_ei_vs_along_track(rows, path, min_rn=None, dl_range=None):
    """The scatter, with the IC limits when given: minimum R-N distance [m] and the [a_dl_min, a_dl_max] band [m]."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ok = [r for r in rows if r["status"] == "ok" and r.get("final_a_dl_m") is not None
          and r.get("min_rn_final_m") is not None]
    for safe, colour, label in ((True, "tab:green", "safe"), (False, "tab:red", "unsafe")):
        sel = [r for r in ok if r["safe"] == safe]
        ax.scatter([abs(r["final_a_dl_m"]) / 1e3 for r in sel], [r["min_rn_final_m"] for r in sel], s=14,
                   c=colour, label=f"{label} ({len(sel)})", edgecolors="none")
    if dl_range is not None:
        ax.axvspan(dl_range[0] / 1e3, dl_range[1] / 1e3, color="tab:blue", alpha=0.08, label="IC along-track band")
    if min_rn is not None:
        ax.axhline(min_rn, color="tab:red", ls="--", lw=1, label=f"min R-N limit {min_rn:g} m")
    ax.set_xlabel("|a dl| at the end [km]")
    ax.set_ylabel("e/i separation: min R-N distance at the end [m]")
    ax.set_title("Final e/i separation vs along-track separation")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    save(fig, path)


def write_campaign_figures(rows, out_dir, min_rn=None, dl_range=None):
    """Write the campaign figures into ``out_dir`` (limits as in :func:`fig_ei_vs_along_track`); returns their
    paths."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = [out_dir / "dv_hist.png", out_dir / "time_to_ic_hist.png", out_dir / "ei_vs_along_track.png"]
    _hist(_values(rows, "dv_total_m_s"), "carrier total dv [m/s]", "Carrier dv per run", paths[0])
    _hist(_values(rows, "time_to_ic_s", 1 / 3600), "ejection to IC epoch [h]",
          "Time to the ICs, runs that reached them", paths[1])
    fig_ei_vs_along_track(rows, paths[2], min_rn, dl_range)
    return paths



def _draw_distance(ax, series, title, keep_out, split_label):
    counts = [0, 0]
    closest = []
    for t_h, d, flag, (t_min, d_min) in series:
        counts[bool(flag)] += 1
        ax.plot(t_h, np.maximum(d, 1e-1), lw=0.6, alpha=0.55 if flag else 0.35,
                color="tab:red" if flag else "0.45")
        if d_min is not None and math.isfinite(d_min):
            closest.append((t_min, d_min, flag))
    for flag, colour in ((False, "0.45"), (True, "tab:red")):
        if counts[flag] and split_label[flag]:
            ax.plot([], [], color=colour, label=f"{split_label[flag]} ({counts[flag]})")
    if keep_out is not None:
        ax.axhline(keep_out, color="tab:blue", ls="--", lw=1, label=f"keep-out {keep_out:g} m")
    if closest:
        c = np.array(closest, dtype=float)
        ax.scatter(c[:, 0], np.maximum(c[:, 1], 1e-1), s=9, c=np.where(c[:, 2] > 0, "tab:red", "k"), marker="v",
                   zorder=3, label="each run's closest approach after departure")
        k = int(np.argmin(c[:, 1]))
        ax.annotate(f"{c[k, 1]:.0f} m", (c[k, 0], max(c[k, 1], 1e-1)), textcoords="offset points", xytext=(4, -10),
                    fontsize=8)
    ax.set_yscale("log")
    ax.set_ylim(10.0, 2e5)
    ax.set_xlabel("time since the ejection [h]")
    ax.set_ylabel("distance [m]")
    ax.set_title(f"{title} ({len(series)} runs)", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="lower right")


def fig_distance_vs_time(series, path, title, keep_out=None, split_label=("", "")):
    """Distance [m] between the spacecraft against time since the ejection [h], one line per run, log scale
    (10 m to 200 km): ``series`` a list of ``(t_h, distance_m, flag, (t_closest_h, closest_m))`` (``flag`` True:
    drawn in red and counted under ``split_label[1]``, else grey under ``split_label[0]``; the run's closest approach
    after its departure as the simulator tracks it, a triangle, the smallest labelled), the keep-out radius [m]
    dashed when given."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    _draw_distance(ax, series, title, keep_out, split_label)
    save(fig, path)


def fig_distance_grid(panels, path, keep_out=None, columns=2):
    """:func:`fig_distance_vs_time` of several campaigns in one figure, a panel each: ``panels`` a list of
    ``(title, series, split_label)``."""
    plt = pyplot()
    rows = -(-len(panels) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(6.5 * columns, 3.8 * rows), squeeze=False)
    for ax, (title, series, split) in zip(axes.flat, panels):
        _draw_distance(ax, series, title, keep_out, split)
    for ax in axes.flat[len(panels):]:
        ax.set_visible(False)
    save(fig, path)
