"""The OEM as an independent reader takes it: the KVN text parsed here (not by our reader), the velocities against
the time derivative of the positions, and the declared interpolation (Hermite, positions and velocities of the
nearest states, written here) reproducing the trajectory between the states."""

import math
from datetime import datetime
from pathlib import Path

import numpy as np
import pytest

from roe_sep.cli import main
from roe_sep.core.relmotion.dynamics import propagate, propagate_chief, sun_synchronous_inclination
from roe_sep.core.relmotion.orbit import semi_major_axis
from roe_sep.ndm import frames
from roe_sep.ndm import messages as ndm

BAG = Path(__file__).resolve().parents[2] / "bags" / "default_run"
EPOCH = "2016-07-01T00:00:00"
A = float(semi_major_axis(515e3))
INC = float(sun_synchronous_inclination(A))


def parse_oem_kvn(text):
    """Segments of a KVN OEM: (metadata dict, t [s since the first epoch of the file], r [m], v [m/s])."""
    segs, meta, rows, in_meta, in_cov = [], {}, [], False, False
    for line in text.splitlines():
        line = line.strip()
        if line in ("COVARIANCE_START", "COVARIANCE_STOP"):
            in_cov = line == "COVARIANCE_START"
        elif in_cov:
            continue
        elif line == "META_START":
            if rows:
                segs.append((meta, rows))
            meta, rows, in_meta = {}, [], True
        elif line == "META_STOP":
            in_meta = False
        elif in_meta and "=" in line:
            k, v = (s.strip() for s in line.split("=", 1))
            meta[k] = v
        elif not in_meta and meta and line and line[0].isdigit() and "=" not in line:
            rows.append(line.split())
    if rows:
        segs.append((meta, rows))
    t0 = datetime.fromisoformat(segs[0][1][0][0])
    out = []
    for meta, rows in segs:
        t = np.array([(datetime.fromisoformat(r[0]) - t0).total_seconds() for r in rows])
        x = np.array([[float(v) for v in r[1:7]] for r in rows]) * 1e3  # km, km/s -> m, m/s
        out.append((meta, t, x[:, :3], x[:, 3:]))
    return out


def hermite(t, r, v, tq, states):
    """Hermite interpolation (positions and velocities) of ``states`` nearest states at the times ``tq``: the
    divided differences of the doubled nodes, written out here."""
    out = []
    for q in np.atleast_1d(tq):
        k0 = int(np.clip(np.searchsorted(t, q) - states // 2, 0, t.size - states))
        idx = np.arange(k0, k0 + states)
        z = np.repeat(t[idx], 2)
        f = np.repeat(r[idx], 2, axis=0).astype(float)
        table = [f.copy()]
        first = np.empty((2 * states - 1, 3))
        for i in range(2 * states - 1):
            first[i] = v[idx[i // 2]] if i % 2 == 0 else (f[i + 1] - f[i]) / (z[i + 1] - z[i])
        table.append(first)
        for order in range(2, 2 * states):
            prev = table[-1]
            table.append(np.array([(prev[i + 1] - prev[i]) / (z[i + order] - z[i]) for i in range(len(prev) - 1)]))
        p, w = np.zeros(3), 1.0
        for order in range(2 * states):
            p = p + table[order][0] * w
            w = w * (q - z[order])
        out.append(p)
    return np.array(out)


def lagrange_derivative(t, r, k, states=10):
    """d r / dt at node ``k`` of the degree-(states - 1) Lagrange polynomial through the nearest ``states`` nodes."""
    k0 = int(np.clip(k - states // 2, 0, t.size - states))
    x = t[k0:k0 + states] - t[k]
    c = np.polyfit(x, r[k0:k0 + states], states - 1)
    return c[-2]


def states_of_a_drifting_pair(t):
    kep0 = np.array([A, 0.0012, INC, 1.1, 0.4, 0.3])
    roe0 = np.array([-60.0, 6000.0, 300.0, -400.0, 100.0, 350.0]) / A
    chief = propagate_chief(kep0, t)
    roe = propagate(roe0, t, A, INC, True, da_dot=-8e-4 / A)  # drag: a da drifting by -69 m/day
    return frames.chief_state(chief, EPOCH, t), frames.deputy_state(roe, chief, EPOCH, t)


def test_oem_velocities_are_the_derivative_of_its_positions_and_hermite_reproduces_it():
    t = np.arange(0.0, 6 * 3600.0 + 1.0, 300.0)
    (rc, vc), (rd, vd) = states_of_a_drifting_pair(t)
    segs = [ndm.EphemerisSegment("CARRIER", "CARRIER", t, rc, vc), ndm.EphemerisSegment("PICO", "PICO", t, rd, vd)]
    parsed = parse_oem_kvn(ndm.to_text(ndm.build_oem(EPOCH, segs), "kvn"))
    mid = t[:-1] + 150.0
    (rc_mid, _), (rd_mid, _) = states_of_a_drifting_pair(mid)
    for (meta, tt, r, v), truth in zip(parsed, (rc_mid, rd_mid)):
        assert meta["INTERPOLATION"] == "HERMITE" and meta["INTERPOLATION_DEGREE"] == "7"
        np.testing.assert_allclose(tt, t, atol=1e-6)
        # the velocity is the time derivative of the positions (was 10 m/s off along-track: sqrt(mu/a) without J2)
        dv = max(np.max(np.abs(lagrange_derivative(tt, r, k) - v[k])) for k in range(tt.size))
        assert dv < 0.05  # 3 cm/s at a segment's ends (the 10-point derivative's own error), 0.2 mm/s inside
        # a Hermite reader (degree 7: 4 states) is within a metre mid-step, edges of the segment included
        err = np.linalg.norm(hermite(tt, r, v, mid, 4) - truth, axis=-1)
        assert np.max(err) < 1.0


@pytest.mark.slow
def test_the_exported_runs_oem_velocities_are_the_derivative_of_its_positions(tmp_path):
    """The reference run's export: every segment's velocities against the derivative of its positions (10-point
    Lagrange, 300 s spacing, the states at least 3 from a segment's ends; a segment of fewer states is left out).
    The OD segments (the estimate propagated by the model) to 2 mm/s. The truth segments to 0.2 m/s: their positions
    are the truth's mean elements sample by sample, which scatter by tens of metres about the secular motion from
    one 300 s sample to the next (what the truth's mean-element fit leaves of J3, J4, drag), so no velocity can be
    the derivative of the positions closer than that; the model's own velocity is. Each carrier burn starts a new
    carrier segment (the velocity jumps there)."""
    assert main(["export", str(BAG), "--out", str(tmp_path), "--format", "kvn"]) == 0
    worst = {"CARRIER": 0.0, "PICOSATELLITE": 0.0, "PICOSATELLITE-OD": 0.0}
    for meta, t, r, v in parse_oem_kvn((tmp_path / "ephemeris.oem.kvn").read_text()):
        assert meta["INTERPOLATION"] == "HERMITE"
        for k in range(3, t.size - 4) if t.size >= 10 else ():
            err = float(np.max(np.abs(lagrange_derivative(t, r, k) - v[k])))
            worst[meta["OBJECT_ID"]] = max(worst[meta["OBJECT_ID"]], err)
    assert 0.0 < worst["PICOSATELLITE-OD"] < 0.002, worst
    assert 0.0 < worst["CARRIER"] < 0.2 and 0.0 < worst["PICOSATELLITE"] < 0.2, worst
    assert all(math.isfinite(w) for w in worst.values())
