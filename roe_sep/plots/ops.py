"""The operational timeline of the separation day in the layout of seed 001 Fig. 7 (PNG)."""

import datetime as _dt
from pathlib import Path

import numpy as np

from . import pyplot, save


def _t(iso):
    return _dt.datetime.strptime(iso, "%Y-%m-%dT%H:%M:%SZ")


def fig_timeline(rep: dict, path: Path):
    """Seed 001 Fig. 7: ground-station contacts (empty bars), TIRA passes (red), Earth shadow (solid), the chosen
    separation window (green line) and its radar passes."""
    plt = pyplot()
    stations = list(dict.fromkeys(c["station"] for c in rep["contacts"]))
    rows = stations + ["TIRA", "shadow"]
    fig, ax = plt.subplots(figsize=(14, 3.6))
    t0 = _dt.datetime.fromisoformat(rep["date"])

    def h(iso):
        return (_t(iso) - t0).total_seconds() / 3600.0

    for c in rep["contacts"]:
        y = rows.index(c["station"])
        ax.barh(y, h(c["end"]) - h(c["start"]), left=h(c["start"]), height=0.6, fill=False, edgecolor="k")
    for p in rep["radar_passes"]:
        ax.barh(rows.index("TIRA"), h(p["end"]) - h(p["start"]), left=h(p["start"]), height=0.6, color="tab:red")
    for e in rep["eclipses"]:
        ax.barh(rows.index("shadow"), h(e["end"]) - h(e["start"]), left=h(e["start"]), height=0.6, color="k")
    best = next((w for w in rep["windows"] if w["eligible"]), None)
    if best:
        ax.axvline(h(best["start"]), color="tab:green", lw=2,
                   label=f"separation {best['start'][5:16]} ({best['station']})")
        for key, ls in (("first_radar", "--"), ("backup_radar", ":"), ("confirm_radar", "-.")):
            if best[key]:
                ax.axvline(h(best[key]), color="tab:red", ls=ls, lw=1,
                           label=f"{key.replace('_', ' ')} {best[key][5:16]}")
        ax.legend(fontsize=7, loc="upper right", ncol=2)
    ax.set_yticks(range(len(rows)), rows)
    ax.set_ylim(-0.6, len(rows) - 0.4 + 0.8)
    ax.set_xlim(0, 24 * rep["days"])
    ax.set_xticks(np.arange(0, 24 * rep["days"] + 1, 3))
    ax.set_xlabel(f"hours from {rep['date']} 00:00 UTC")
    ax.set_title(f"Visibility of the carrier by the ground stations and TIRA, {rep['date']} (+{rep['days']:g} d)")
    ax.grid(axis="x", alpha=0.3)
    save(fig, path)
    return path
