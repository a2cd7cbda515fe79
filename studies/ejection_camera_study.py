"""Study: the carrier camera's weak-ejection test on the nonlinear truth (no DDS), as the closed loop makes it.

For each run seed the simulator's world is drawn as ``roe-sep run`` draws it (:func:`roe_sep.core.truth.simulated.
dispersed_truth`: the SPL's magnitude and pointing, the differential ballistic coefficient, the release delay; the
nonlinear truth, J2-J4 and drag), the design's ejection is commanded at u1 as the ejector does, the truth's relative
position is sampled every ``camera_period`` from the release to ``hold_lead`` before the blind drift-stop, turned into
bearings with the simulator's camera noise (:func:`~roe_sep.core.truth.simulated.camera_rng`,
:func:`~roe_sep.core.safety.ejection_check.camera_bearing`) and tested as the planner tests them
(:func:`~roe_sep.core.safety.ejection_check.check_ejection`, the planner's defaults). Nominal seeds must never hold;
``--f1`` fixes a weak ejection (``spl_weak``) to find the detection boundary. One line per seed and a summary.

    python studies/ejection_camera_study.py --seeds 1000 1200
    python studies/ejection_camera_study.py --seeds 1000 1100 --f1 0.3
"""

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from roe_sep.core.config import load_scenario  # noqa: E402
from roe_sep.core.od.radar import julian_date, raan_from_ltan  # noqa: E402
from roe_sep.core.relmotion.dynamics import drag_da_dot, propagate_chief  # noqa: E402
from roe_sep.core.safety.ejection_check import camera_bearing, check_ejection, nominal_fraction  # noqa: E402
from roe_sep.core.separation.double_impulse import design, plan_drift_stop, reduction_bounds  # noqa: E402
from roe_sep.core.truth.contingency import contingency_from_dict  # noqa: E402
from roe_sep.core.truth.execution import BurnExecution  # noqa: E402
from roe_sep.core.truth.secular import time_to_arg_latitude  # noqa: E402
from roe_sep.core.truth.simulated import SimulatedTruth, camera_rng, dispersed_truth  # noqa: E402
from roe_sep.nodes.parameters import table  # noqa: E402


def run(seed, f1=None):
    """One seed: (executed f1, drag factor g, the check)."""
    sim, planner = table("sim"), table("planner")
    scenario = load_scenario(None)
    d = design(scenario.separation)
    raan = float(raan_from_ltan(sim["ltan_hours"].default, julian_date(sim["epoch_utc"].default)))
    cont = None if f1 is None else contingency_from_dict({"name": "spl_weak", "spl_fraction": f1})
    world = dispersed_truth(scenario, d, raan, math.radians(sim["u0_deg"].default), seed, disperse=True,
                            dynamics="nonlinear", j2=True,
                            ejection_delay_max=sim["ejection_delay_max"].default, contingency=cont)
    period = sim["camera_period"].default
    samples = {}
    truth = SimulatedTruth(world.model, period, 10.0, 1000.0,
                           lambda e, s: samples.update({round(t, 3): (s[0][j], s[2][0][j]) for j, t in enumerate(e)}),
                           on_hour=lambda: None)
    truth.advance(period)
    kep = samples[round(period, 3)][0]
    t_ej = period + time_to_arg_latitude(kep[4] + kep[5], d.u1, kep[0], kep[2])
    chief = propagate_chief(kep, t_ej - period)
    ex = BurnExecution(truth, world.errors, world.ejection_delay, False, lambda level, text: None,
                       contingency=world.contingency)
    ex.eject(t_ej, d.dv1_rtn, "picosatellite", "ejection")
    burn = ex.take(ex.due(math.inf)[0])
    truth.advance(burn.epoch)
    done = ex.execute(burn)
    stop = plan_drift_stop(d.dv1_rtn, chief[4] + chief[5], t_ej, chief[0], chief[2], k=d.k,
                           p=reduction_bounds(d.dv1_rtn[1], scenario.separation)[0], j2=True)
    t_end = stop.epoch - planner["hold_lead"].default
    truth.advance(t_end)
    times = np.array(sorted(t for t in samples if done.epoch < t <= t_end))
    pos = np.array([samples[round(t, 3)][1] for t in times])
    los = camera_bearing(pos, math.radians(sim["camera_sigma_deg"].default), camera_rng(seed))
    mc = scenario.monte_carlo
    check = check_ejection(times, los, d.dv1_rtn, done.epoch, propagate_chief(chief, done.epoch - t_ej),
                           da_dot=float(drag_da_dot(mc.delta_b, mc.density, chief[0])),
                           sigma=math.radians(sim["camera_sigma_deg"].default),
                           floor=planner["camera_model_floor"].default,
                           bound=nominal_fraction(scenario.separation.spl_sigma, mc.ballistic_sigma,
                                            planner["hold_sigmas"].default),
                           alpha=planner["hold_alpha"].default)
    return float(np.linalg.norm(done.dv_rtn) / np.linalg.norm(d.dv1_rtn)), world.drag_factor, check


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", nargs=2, type=int, default=(1000, 1200), metavar=("FIRST", "STOP"))
    ap.add_argument("--f1", type=float, default=None, help="a fixed weak ejection (spl_weak); none: nominal")
    args = ap.parse_args(argv)
    rows = []
    for seed in range(*args.seeds):
        f1, g, c = run(seed, args.f1)
        rows.append((f1, g, c))
        print(f"seed {seed}: f1 {f1:.3f}, g {g:.3f}, f1/g {f1 / g:.3f}; fitted {c.f1:.2f}, gain {c.gain:8.1f}, "
              f"{c.samples} bearings: {'HOLD' if c.weak else 'flies'}", flush=True)
    held = [r for r in rows if r[2].weak]
    print(f"{len(held)} of {len(rows)} held (bound {rows[0][2].bound:.4f})")
    if held and len(held) < len(rows):
        print(f"largest f1/g held {max(f / g for f, g, _ in held):.3f}, smallest not held "
              f"{min(f / g for f, g, c in rows if not c.weak):.3f}; smallest g held {min(g for _, g, _ in held):.3f}, "
              f"largest g not held {max(g for _, g, c in rows if not c.weak):.3f}")
    if not held:
        print(f"smallest fitted {min(c.f1 for _, _, c in rows):.2f}, "
              f"largest gain {max(c.gain for _, _, c in rows):.1f}")


if __name__ == "__main__":
    main()
