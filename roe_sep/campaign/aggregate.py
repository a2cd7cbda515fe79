"""The campaign's aggregate report from its table rows, and the open-loop Monte Carlo beside it.

Keys of :func:`aggregate`: ``runs`` / ``completed`` / ``failed``; ``p_safe`` and ``criteria`` (each a proportion
over the completed runs with its Wilson 95 % interval, :func:`roe_sep.core.montecarlo.stats.proportion`);
``p_safe_failures_unsafe`` (the conservative reading: a failed run counts as unsafe); ``ic_checks`` (each initial
condition of :func:`roe_sep.report.initial_conditions` over the runs whose IC epoch was evaluated: which one keeps
``ic_reached`` down); ``distributions`` (min distance, min R-N distance at the IC epoch and at the end, |a da| at the
IC epoch, total dv, drift-stop and IC dv, time to IC of the runs that reached the ICs: n, missing, min, p5, p50,
p95, max, mean); ``od_nees`` / ``od_last_nees`` (the first / last OD solution's NEES against its chi-square(6)
bounds), ``od_drift_rate`` / ``od_last_drift_rate`` (their drift rate's squared normalized error against
chi-square(1)); ``ic_reached_lower_95`` (its one-sided Clopper-Pearson bound, :func:`one_sided_lower`);
``ic_trims`` (the runs whose final OD flew a drift trim, of those with a final-OD decision; the trims' dv a
distribution);
``dispersions`` (each applied dispersion against its configured distribution, :mod:`.dispersions`);
``failures`` (count per kind and per reason); the actual approach from the truth beside the passive-safety
verdicts (:func:`truth_outcomes`): ``truth_collision`` and ``truth_keep_out_violated`` (Clopper-Pearson 95 %) and
the distributions ``truth_closest`` / ``truth_keep_out_time``.
"""

import collections
import dataclasses

from ..core.montecarlo.stats import clopper_pearson, distribution, nees_consistency, proportion
from ..core.safety.approach import COLLISION_RADIUS
from .dispersions import dispersion_checks
from .table import CRITERIA, IC_CHECKS

DISTRIBUTIONS = {  # report key -> (row field, unit, of its absolute value)
    "min_distance": ("min_distance_m", "m", False),
    "min_rn_distance_ic": ("min_rn_ic_m", "m", False),
    "min_rn_distance_final": ("min_rn_final_m", "m", False),
    "abs_a_da_ic": ("ic_a_da_m", "m", True),
    "abs_a_da_ic_predicted": ("ic_pred_a_da_m", "m", True),
    "a_da_ic_prediction_error": ("ic_a_da_error_m", "m", True),
    "dv_total": ("dv_total_m_s", "m/s", False),
    "dv_drift_stop": ("dv_drift_stop_m_s", "m/s", False),
    "dv_ic": ("dv_ic_m_s", "m/s", False),
    "time_to_ic": ("time_to_ic_s", "s", False),
    "truth_closest": ("truth_closest_m", "m", False),
    "truth_nearest": ("truth_nearest_m", "m", False),
    "truth_keep_out_time": ("truth_keep_out_s", "s", False),
}


def _column(rows, field, absolute=False):
    if field == "ic_a_da_error_m":  # truth minus the prediction of the plan in force at the IC epoch
        rows = [{field: None if r.get("ic_a_da_m") is None or r.get("ic_pred_a_da_m") is None
                 else r["ic_a_da_m"] - r["ic_pred_a_da_m"]} for r in rows]
    return [None if r.get(field) is None else (abs(r[field]) if absolute else r[field]) for r in rows]


def _squares(values):
    return [None if v is None else v * v for v in values]


def truth_outcomes(done, collision_radius=COLLISION_RADIUS):
    """From the truth (rows with its columns; a row recorded before them is left out and counted in ``missing``):
    ``truth_collision`` (the truth's nearest approach after the ejection, ``truth_nearest_m``, below
    ``collision_radius`` [m]) and ``truth_keep_out_violated``
    (never left the keep-out sphere or came back inside), each with its Clopper-Pearson 95 % interval
    (:func:`~roe_sep.core.montecarlo.stats.clopper_pearson`), and ``collision_radius``."""
    # every local minimum of the distance after the ejection counts, before the departure too (a weak ejection); a
    # run without any (receding all run, or a stuck picosatellite at rest) had no approach: no collision
    known = [r for r in done if r.get("truth_keep_out_violated") is not None]
    closest = [r.get("truth_nearest_m") for r in known]
    return {
        "truth_collision": {**clopper_pearson(sum(1 for d in closest if d is not None and d < collision_radius),
                                              len(known)), "missing": len(done) - len(known)},
        "truth_keep_out_violated": {**clopper_pearson(sum(bool(r["truth_keep_out_violated"]) for r in known),
                                                      len(known)), "missing": len(done) - len(known)},
        "collision_radius": collision_radius,
    }


def aggregate(rows, collision_radius=COLLISION_RADIUS):
    """The statistics of a list of rows (one per seed); ``collision_radius`` [m] of :func:`truth_outcomes`."""
    done = [r for r in rows if r["status"] == "ok"]
    failed = [r for r in rows if r["status"] != "ok"]
    n = len(done)
    ic_columns = {c: _column(done, f"ic_{c}") for c in IC_CHECKS}  # None: no IC epoch evaluated in that run
    out = {
        "runs": len(rows), "completed": n, "failed": len(failed),
        "p_safe": proportion(sum(r["safe"] for r in done), n),
        "p_safe_failures_unsafe": proportion(sum(r["safe"] for r in done), len(rows)),
        "criteria": {c: proportion(sum(r[f"crit_{c}"] for r in done), n) for c in CRITERIA},
        # each initial condition over the completed runs in which the IC epoch was evaluated (an IC plan flown)
        "ic_checks": {c: proportion(sum(v is True for v in col), sum(v is not None for v in col))
                      for c, col in ic_columns.items()},
        "distributions": {k: {"unit": unit, **distribution(_column(done, f, absolute))}
                          for k, (f, unit, absolute) in DISTRIBUTIONS.items()},
        # the OD covariance against the truth: NEES of the ROE (6 dof) and the drift rate's squared z (1 dof), of the
        # first solution (before any acquisition burn) and of the last one (after them)
        "od_nees": nees_consistency([r.get("od_nees") for r in done], dof=6),
        "od_drift_rate": nees_consistency(_squares(r.get("od_z_a_da_dot") for r in done), dof=1),
        "od_last_nees": nees_consistency([r.get("od_last_nees") for r in done], dof=6),
        "od_last_drift_rate": nees_consistency(_squares(r.get("od_last_z_a_da_dot") for r in done), dof=1),
        # ROE and drift rate together (7 dof, with their cross-covariance)
        "od_nees7": nees_consistency([r.get("od_nees7") for r in done], dof=7),
        "od_last_nees7": nees_consistency([r.get("od_last_nees7") for r in done], dof=7),
        "dispersions": dispersion_checks(done),
        **truth_outcomes(done, collision_radius),
        "failures": {"by_kind": dict(collections.Counter(r["failure"] for r in failed)),
                     "by_reason": dict(collections.Counter(r["reason"] for r in failed).most_common())},
    }
    out["distributions"]["min_distance"]["note"] = "missing: no approach after the departure (or no value)"
    out["distributions"]["abs_a_da_ic"]["note"] = "truth |a da| at the IC epoch (the drift initial condition)"
    reached = sum(r["crit_ic_reached"] for r in done)
    out["ic_reached_lower_95"] = one_sided_lower(reached, n)
    trims = [r.get("ic_trim") for r in done if r.get("ic_trim") is not None]  # runs with a final-OD decision
    out["ic_trims"] = proportion(sum(trims), len(trims))
    out["distributions"]["ic_trim_dv"] = {"unit": "m/s", **distribution(
        [r.get("ic_trim_dv_m_s") for r in done if r.get("ic_trim")])}
    out["distributions"]["abs_a_da_ic_predicted"]["note"] = "|a da| the last information predicted at the IC epoch"
    out["distributions"]["a_da_ic_prediction_error"]["note"] = "|truth - predicted a da| at the IC epoch"
    out["distributions"]["time_to_ic"]["note"] = "ejection to the IC epoch, runs that reached the ICs there"
    out["distributions"]["truth_closest"]["note"] = "the truth's closest approach after the departure (HCW-refined)"
    out["distributions"]["truth_nearest"]["note"] = "the truth's nearest approach after the ejection (HCW-refined)"
    out["distributions"]["truth_keep_out_time"]["note"] = "truth: time inside the keep-out after the departure"
    return out


def one_sided_lower(k, n, confidence=0.95):
    """Clopper-Pearson one-sided lower confidence bound of a proportion k/n (None without runs): the p below which
    k or more successes in n would have probability < 1 - confidence (0 misses in 299 runs: 0.990)."""
    from scipy.stats import beta

    if not n:
        return None
    return 0.0 if k == 0 else float(beta.ppf(1.0 - confidence, k, n - k + 1))


def planner_p(scenario, overrides):
    """The drift-stop reduction |p| [m/s] the planner node flies with these overrides, and how it was chosen; None
    for the multi-impulse strategy (its carrier burns are sized otherwise) and for ``three_sigma`` (per ejection)."""
    from ..core.montecarlo.sweep import sweep
    from ..core.separation.double_impulse import design

    pl = (overrides or {}).get("planner", {})
    if pl.get("strategy", "double_impulse") != "double_impulse":
        return None, "multi_impulse strategy: no open-loop p sweep"
    mode = pl.get("p_mode", "monte_carlo")
    if mode == "fixed":
        return float(pl.get("p_reduction", 0.0)), "fixed"
    if mode != "monte_carlo":
        return None, f"p_mode {mode}: |p| is chosen per ejection"
    mc = dataclasses.replace(scenario.monte_carlo, samples=int(pl.get("mc_samples", 100000)),
                             seed=int(pl.get("mc_seed", 0)))
    return float(sweep(design(scenario.separation), mc, scenario.p_values).p_best), \
        f"p_best of the planner's {mc.samples}-sample sweep (mc_seed {mc.seed})"


def open_loop(config, overrides, samples=20000, seed=0):
    """The open-loop ``roe-sep mc`` result for the scenario's dispersions (seed 002 Monte Carlo: dispersed ejection and
    drift-stop propagated analytically, no OD, no IC acquisition) at the |p| the planner uses: its summary row."""
    from ..core.config import load_scenario
    from ..core.montecarlo.sweep import sweep
    from ..core.separation.double_impulse import design

    scenario = load_scenario(config)
    p, how = planner_p(scenario, overrides)
    if p is None:
        return {"p": None, "p_source": how}
    mc = dataclasses.replace(scenario.monte_carlo, samples=int(samples), seed=int(seed))
    row = sweep(design(scenario.separation), mc, [p]).rows[0]
    return {"p": p, "p_source": how, "samples": mc.samples, "seed": mc.seed, "horizon_s": mc.horizon,
            "drag": mc.drag, "j2": mc.j2, **{k: v for k, v in row.items() if k != "p"}}
