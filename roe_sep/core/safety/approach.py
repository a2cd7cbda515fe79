"""The actual approach of a run, from the truth: what happened, as opposed to the passive-safety verdicts (a
prediction with no further burns, :mod:`.monitor`). Pure numpy.

Input: the truth's relative states (position, velocity in the carrier's rotating RTN frame), sampled by the
simulator every ``truth_period`` (60 s by default, 300 s in the golden run) and right after every burn, so no burn
falls strictly inside a sampling interval. Between two samples the motion is the Clohessy-Wiltshire (HCW) solution
from the interval's first sample (seed 000's linearized relative motion, the near-circular limit of the ROE model):
:func:`hcw_propagate`. Each interval is scanned on a grid of ``step`` seconds (at most) for the sign changes of r.v
(= |r| d|r|/dt) and of |r| - keep_out, and each bracket is solved by bisection on the HCW solution to 1e-6 s.

Bound of the refinement: the HCW solution from a sample, propagated to the next sample, is compared with that sample
(positions are continuous across an impulsive burn); the largest mismatch over the run is reported as
``refine_error_m``. The propagation error grows from zero over an interval (an unmodelled acceleration: J2, drag,
eccentricity, the nonlinearity), so inside each interval it stays at most that mismatch, and so does the error of
every refined distance. A local minimum and maximum of |r| closer together than ``step`` are not resolved.
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

BISECTIONS = 48  # a 60-s bracket to 2e-13 s; 300 s to 1e-12 s


def hcw_propagate(pos: ArrayLike, vel: ArrayLike, tau: ArrayLike, n: float) -> tuple[np.ndarray, np.ndarray]:
    """Clohessy-Wiltshire solution (circular chief, rotating RTN frame: x radial, y along-track, z normal).

    x = (4 - 3c) x0 + s/n vx0 + 2 (1 - c)/n vy0,  y = 6 (s - n t) x0 + y0 - 2 (1 - c)/n vx0 + (4 s - 3 n t)/n vy0,
    z = c z0 + s/n vz0 with c = cos(n t), s = sin(n t) (seed 000's HCW equations; the velocities their derivatives).

    Parameters
    ----------
    pos, vel : array_like, shape (..., 3)
        Relative position [m] and velocity [m/s] at t = 0.
    tau : array_like, shape (...)
        Propagation times [s] (broadcast against ``pos[..., 0]``).
    n : float
        Mean motion of the chief [rad/s].

    Returns
    -------
    (numpy.ndarray, numpy.ndarray), each shape (..., 3)
        Position [m] and velocity [m/s] at ``tau``.
    """
    r, v = np.asarray(pos, dtype=float), np.asarray(vel, dtype=float)
    t = np.asarray(tau, dtype=float)
    c, s, nt = np.cos(n * t), np.sin(n * t), n * t
    x0, y0, z0, vx0, vy0, vz0 = r[..., 0], r[..., 1], r[..., 2], v[..., 0], v[..., 1], v[..., 2]
    x = (4.0 - 3.0 * c) * x0 + s / n * vx0 + 2.0 * (1.0 - c) / n * vy0
    y = 6.0 * (s - nt) * x0 + y0 - 2.0 * (1.0 - c) / n * vx0 + (4.0 * s - 3.0 * nt) / n * vy0
    z = c * z0 + s / n * vz0
    vx = 3.0 * n * s * x0 + c * vx0 + 2.0 * s * vy0
    vy = -6.0 * n * (1.0 - c) * x0 - 2.0 * s * vx0 + (4.0 * c - 3.0) * vy0
    vz = -n * s * z0 + c * vz0
    return np.stack([x, y, z], axis=-1), np.stack([vx, vy, vz], axis=-1)


@dataclass(frozen=True)
class Approach:
    """The actual approach of :func:`actual_approach` (epochs in s, distances in m, ``None``: no such event)."""

    departure_epoch: float | None  # first exit from the keep-out sphere at or after the start
    closest_distance: float | None  # smallest local minimum of |r| after the departure (see actual_approach)
    closest_epoch: float | None
    closest_at_end: bool  # the closest approach is the end of the truth, still approaching there
    closest_error_m: float | None  # the refinement's bound there (its interval's mismatch; 0 at a sample)
    nearest: tuple  # (distance, epoch, bound) of the smallest local minimum after the start, departed or not
    # (the end counts while still approaching), the collision's comparand; (None, None, None) without one
    minima: np.ndarray  # (M, 3): every local minimum of |r| after the start (epoch, distance, bound), in time order
    keep_out_s: float  # time inside the keep-out after the departure (never departed: from the start to the end)
    keep_out_entries: int  # re-entries after the departure
    span: tuple  # (start, end) epochs of the truth scanned
    refine_error_m: float  # largest HCW mismatch at an interval's end (the refinement's bound)
    truth_step_s: float  # largest sampling interval of the truth
    step: float  # the scan grid [s]

    @property
    def keep_out_violated(self) -> bool:
        """The pair never left the keep-out sphere, or came back inside it."""
        return self.departure_epoch is None or self.keep_out_entries > 0


def _bisect(pred, lo, hi, at_lo):
    """Where the boolean ``pred(tau)`` (vectorized, shape of ``lo``) changes in [lo, hi], ``pred(lo) == at_lo``."""
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        same = pred(mid) == at_lo
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    return 0.5 * (lo + hi)


def actual_approach(times: ArrayLike, pos: ArrayLike, vel: ArrayLike, n: float, keep_out: float, *,
                    start: float, step: float = 10.0, chunk: int = 1 << 20) -> Approach | None:
    """The truth's closest approach and time inside the keep-out sphere over ``[start, last sample]``.

    The departure is the first exit from the keep-out sphere; the closest approach is the smallest local minimum of
    |r| at or after it (a pair that never left: after ``start``; the end counts while |r| still decreases there),
    ``nearest`` the same over every minimum after ``start`` (an approach before the departure too: a weak ejection);
    the keep-out time and entries are those after the departure. Sampling, refinement and its bound: the module.

    Parameters
    ----------
    times : array_like, shape (K,)
        Truth epochs [s]; a repeated epoch keeps its last sample (the state after a burn).
    pos, vel : array_like, shape (K, 3)
        Relative position [m] and velocity [m/s] in the carrier's rotating RTN frame.
    n : float
        Chief mean motion [rad/s].
    keep_out : float
        Keep-out radius [m].
    start : float
        First epoch [s] scanned (the ejection: its sample is the state right after it).
    step : float
        Scan grid [s] inside each sampling interval.
    chunk : int
        Grid points per vectorized pass (at least one interval's), the memory bound.

    Returns
    -------
    Approach or None
        None with fewer than two samples at or after ``start``.
    """
    t = np.asarray(times, dtype=float)
    r, v = np.asarray(pos, dtype=float).reshape(-1, 3), np.asarray(vel, dtype=float).reshape(-1, 3)
    order = np.argsort(t, kind="stable")
    t, r, v = t[order], r[order], v[order]
    keep = (t >= start) & np.append(t[1:] != t[:-1], True)  # a repeated epoch: its last sample
    t, r, v = t[keep], r[keep], v[keep]
    if t.size < 2:
        return None
    dt = np.diff(t)
    mins_t, mins_d, mins_e, cross_t, cross_in = [], [], [], [], []
    err = np.zeros(dt.size)  # the HCW mismatch at each interval's end [m]
    per = max(1, chunk // (int(np.ceil(dt.max() / step)) + 1))  # intervals per pass
    for lo in range(0, dt.size, per):
        k = np.arange(lo, min(lo + per, dt.size))
        m = np.maximum(np.ceil(dt[k] / step).astype(int), 1)
        grid = np.arange(m.max() + 1)[None, :] / m[:, None]  # fractions of each interval, 0..1 (clipped)
        tau = np.minimum(grid, 1.0) * dt[k][:, None]
        rk, vk = hcw_propagate(r[k][:, None, :], v[k][:, None, :], tau, n)
        err[k] = np.linalg.norm(rk[:, -1] - r[k + 1], axis=-1)
        g = np.einsum("kjc,kjc->kj", rk, vk)  # r.v: |r| d|r|/dt
        out = np.linalg.norm(rk, axis=-1) >= keep_out
        same = tau[:, 1:] > tau[:, :-1]  # the clipped tail repeats the end: no bracket there
        # interior minima: r.v from < 0 to >= 0 between grid points
        ki, ji = np.nonzero(same & (g[:, :-1] < 0.0) & (g[:, 1:] >= 0.0))
        if ki.size:
            r0, v0 = r[k[ki]], v[k[ki]]

            def closing(x, r0=r0, v0=v0):
                p, q = hcw_propagate(r0, v0, x, n)
                return np.einsum("ic,ic->i", p, q) < 0.0

            root = _bisect(closing, tau[ki, ji], tau[ki, ji + 1], True)
            mins_t.append(t[k[ki]] + root)
            mins_d.append(np.linalg.norm(hcw_propagate(r0, v0, root, n)[0], axis=-1))
            mins_e.append(err[k[ki]])
        # keep-out crossings: |r| >= keep_out changes (an entry where it was outside)
        kc, jc = np.nonzero(same & (out[:, :-1] != out[:, 1:]))
        if kc.size:
            r0, v0 = r[k[kc]], v[k[kc]]

            def outside(x, r0=r0, v0=v0):
                return np.linalg.norm(hcw_propagate(r0, v0, x, n)[0], axis=-1) >= keep_out

            was_out = out[kc, jc]
            cross_t.append(t[k[kc]] + _bisect(outside, tau[kc, jc], tau[kc, jc + 1], was_out))
            cross_in.append(was_out)
        # a minimum at a sample (a burn turned an approach into a departure): r.v < 0 arriving, >= 0 leaving
        kink = k[(g[:, -1] < 0.0) & (np.einsum("kc,kc->k", r[k + 1], v[k + 1]) >= 0.0)]
        mins_t.append(t[kink + 1])
        mins_d.append(np.linalg.norm(r[kink + 1], axis=-1))
        mins_e.append(np.zeros(kink.size))  # a sample: no refinement
    minima = np.stack([np.concatenate(x) for x in (mins_t, mins_d, mins_e)], axis=-1)
    minima = minima[np.argsort(minima[:, 0], kind="stable")]
    ct = np.concatenate(cross_t) if cross_t else np.empty(0)
    ci = np.concatenate(cross_in) if cross_in else np.empty(0, dtype=bool)
    order = np.argsort(ct, kind="stable")
    ct, ci = ct[order], ci[order]
    d0, end = float(np.linalg.norm(r[0])), float(t[-1])
    if d0 >= keep_out:  # outside from the start
        departure = float(t[0])
    else:
        exits = ct[~ci]
        departure = float(exits[0]) if exits.size else None
    approaching = float(r[-1] @ v[-1]) < 0.0  # still approaching at the end of the truth

    def smallest(rows):
        found = [(float(d), float(e), False, float(b)) for e, d, b in rows]
        if approaching:
            found.append((float(np.linalg.norm(r[-1])), end, True, 0.0))
        return min(found, default=(None, None, False, None))

    closest = smallest(minima[minima[:, 0] >= (t[0] if departure is None else departure)])
    nearest = smallest(minima)
    if departure is None:
        inside, entries = end - float(t[0]), 0
    else:  # after the departure the crossings alternate: entry, exit, entry, ...
        later = ct > departure
        ent, ext = ct[later & ci], ct[later & ~ci]
        entries = int(ent.size)
        pairs = min(entries, ext.size)
        inside = float(np.sum(ext[:pairs] - ent[:pairs]))
        if entries > ext.size:  # inside at the end
            inside += end - float(ent[-1])
    return Approach(departure, closest[0], closest[1], bool(closest[2]), closest[3],
                    (nearest[0], nearest[1], nearest[3]), minima, inside, entries,
                    (float(t[0]), end), float(err.max()), float(dt.max()), float(step))


CARRIER_BOX = (0.6, 0.8, 0.8)
"""m, the carrier's edges: BIROS "measures 60x80x80 cm" (seed 001 Sec. 1; config/default.yaml's 0.48 m^2 is one
0.6 x 0.8 face)."""
PICOSAT_BOX = (0.1, 0.1, 0.1)
"""m, the picosatellite's edges: BEESAT-4, "10x10x10 cm" (seed 001 Sec. 1; the config's 0.01 m^2 is one face)."""


def hard_body_radius(box_a: ArrayLike, box_b: ArrayLike) -> float:
    """Collision radius [m] of two boxes: the sum of the radii of their circumscribed spheres, half their space
    diagonals (a collision is possible only when the centres come closer than this).

    Parameters
    ----------
    box_a, box_b : array_like, shape (3,)
        Edge lengths [m] of each body.

    Returns
    -------
    float
        |box_a| / 2 + |box_b| / 2 [m].
    """
    return 0.5 * (math.sqrt(float(np.sum(np.square(box_a)))) + math.sqrt(float(np.sum(np.square(box_b)))))


COLLISION_RADIUS = hard_body_radius(CARRIER_BOX, PICOSAT_BOX)
"""m, the collision radius of the two bodies: 0.640 m + 0.087 m = 0.727 m (:func:`hard_body_radius` of
:data:`CARRIER_BOX` and :data:`PICOSAT_BOX`); a closest approach of the centres below it can be a contact."""
