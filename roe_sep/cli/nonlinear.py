"""``roe-sep propagate`` and ``roe-sep validate``: the nonlinear truth on the command line (issue 5 item 5).

``register(subparsers)`` adds both subcommands to the ``roe-sep`` parser; bad input raises ValueError, which
``roe_sep.cli.main`` reports with exit status 2, as every other subcommand.
"""

import argparse
import dataclasses
import math
import sys

import numpy as np

from .common import check_number, emit, finite_float, integer, number_list, p_list, seed

MODELS = ("keplerian", "j2", "j2drag", "nonlinear")


# a*ROE [m]: the close-formation model needs |a dROE| well below a (checked against 1 % of a once a is known)
_roe_arg = number_list(-1e6, 1e6, unit="m", length=6)
_days_values = number_list(1, 30, integer_values=True)


def _days_list(text):
    """``--days`` of ``validate``: whole days in [1, 30], sorted, each once."""
    return sorted(set(_days_values(text)))


_days_list.__name__ = "days"
MAX_POINTS = 100_000  # output samples of `propagate` (days * 86400 / step)


def _atmospheres(text):
    """``--atmosphere``: a comma-separated list of the truth's density models."""
    from ..core.truth.nonlinear import ATMOSPHERES

    values = [x.strip() for x in text.split(",") if x.strip()]
    if not values or any(v not in ATMOSPHERES for v in values):
        raise argparse.ArgumentTypeError(f"expected a comma-separated list of {', '.join(ATMOSPHERES)}, got {text!r}")
    return list(dict.fromkeys(values))


def propagate_report(roe_m, altitude, inc_deg, u_deg, days, *, step, model, scenario):
    """Propagate a*ROE [m] from a circular chief (mean elements) with one model; SI output."""
    from ..core.constants import SECONDS_PER_DAY
    from ..core.relmotion.dynamics import sun_synchronous_inclination
    from ..core.relmotion.orbit import semi_major_axis
    from ..core.relmotion.roe import roe_to_kepler
    from ..core.truth.validation import Case

    check_number("--alt", altitude, 200e3, 1100e3, hi_open=True, unit="m (the tabulated density)")
    check_number("--days", days, 0.0, 30.0, lo_open=True, unit="days")
    check_number("--step", step, 1.0, 86400.0, unit="s")
    check_number("--u", u_deg, -360.0, 360.0, unit="deg")
    if inc_deg is not None:
        check_number("--inc", inc_deg, 0.0, 180.0, lo_open=True, hi_open=True, unit="deg")
    if days * SECONDS_PER_DAY / step > MAX_POINTS:
        raise ValueError(f"--step: {step:g} s over --days {days:g} gives {days * SECONDS_PER_DAY / step:.0f} output "
                         f"points; at most {MAX_POINTS} allowed (a step >= {days * SECONDS_PER_DAY / MAX_POINTS:g} s)")
    a = float(semi_major_axis(altitude))
    inc = float(sun_synchronous_inclination(a)) if inc_deg is None else math.radians(inc_deg)
    mc = scenario.monte_carlo
    chief = np.array([a, 0.0, inc, 0.0, 0.0, math.radians(u_deg)])
    roe = np.asarray(roe_m, dtype=float) / a
    if np.any(np.abs(roe[[0, 2, 3, 4, 5]]) > 0.01):
        raise ValueError(f"--roe: |a da|, |a dex|, |a dey|, |a dix|, |a diy| must be below 1 % of a ({0.01 * a:.0f} m; "
                         f"near-circular, close formation), got {','.join(f'{x:g}' for x in roe_m)}")
    times = np.arange(0.0, days * SECONDS_PER_DAY + step / 2, step)
    b_c, b_d = (mc.carrier.ballistic, mc.picosat.ballistic) if mc.drag else (0.0, 0.0)
    case = Case("propagate", chief, (), b_c, b_d, mc.density)
    if model == "nonlinear":
        from ..core.truth.nonlinear import mean_roe, pair_state, propagate_pair

        s0 = pair_state(chief, roe_to_kepler(chief, roe))
        out = mean_roe(propagate_pair(s0, 0.0, times, (), b_c, b_deputy=b_d, atmosphere=case.atmosphere)) * a
    else:
        from ..core.relmotion.dynamics import drag_da_dot, propagate

        da_dot = float(drag_da_dot(b_d - b_c, mc.density, a)) if model == "j2drag" else 0.0
        out = propagate(roe[None, :], times, a, inc, model != "keplerian", da_dot=da_dot) * a
    return {"model": model, "a": a, "altitude": altitude, "inclination_deg": math.degrees(inc), "u0_deg": u_deg,
            "delta_b": b_d - b_c, "density": mc.density, "t": times.tolist(), "roe": out.tolist()}


def cmd_propagate(args):
    from ..core.config import load_scenario

    rep = propagate_report(args.roe, args.alt, args.inc, args.u, args.days, step=args.step, model=args.model,
                           scenario=load_scenario(args.config))
    emit(rep, args.json, lambda r: print_propagate(r, args.step))
    return 0


def print_propagate(rep, step, out=None):
    """The ROE table of ``roe-sep propagate``, one row every 3 h (``step`` [s] the sampling) and the last."""
    w = (out or sys.stdout).write
    w(f"ROE propagation, model {rep['model']}: a = {rep['a']:.1f} m, i = {rep['inclination_deg']:.3f} deg, "
      f"u0 = {rep['u0_deg']:g} deg, dB = {rep['delta_b']:.5f} m^2/kg, rho = {rep['density']:.3g} kg/m^3\n")
    w(f"  {'t [h]':>8s}" + "".join(f"{'a ' + n + ' [m]':>14s}" for n in ("da", "dl", "dex", "dey", "dix", "diy"))
      + "\n")
    t = np.asarray(rep["t"])
    stride = max(1, int(round(3 * 3600.0 / step)))
    for k in list(range(0, len(t), stride)) + ([len(t) - 1] if (len(t) - 1) % stride else []):
        w(f"  {t[k] / 3600:8.2f}" + "".join(f"{x:14.2f}" for x in rep["roe"][k]) + "\n")


def validate_report(scenario, days, mc_samples=0, p_values=None, seed=None, *, atmospheres=("normalised", "msis"),
                    f107=140.0, f107a=140.0, ap=15.0):
    """The model-error table (item 3) for the double- and multi-impulse cases under each truth atmosphere
    (``normalised``: the seeds' density as the orbit mean; ``msis``: NRLMSIS 2.0 at F10.7 ``f107``, its 81-day
    mean ``f107a`` and Ap ``ap``, orbit at LTAN 09:30 on the default epoch), optionally the nonlinear MC."""
    from ..core.constants import SECONDS_PER_DAY
    from ..core.separation import multi_impulse
    from ..core.separation.double_impulse import design
    from ..core.truth.nonlinear import ATMOSPHERES, truth_atmosphere
    from ..core.truth.validation import (
        double_impulse_case,
        model_errors,
        multi_impulse_case,
        nonlinear_sweep,
        sso_raan,
        truth_effective_density,
        zonal_effect,
    )

    for name, value in (("--f107", f107), ("--f107a", f107a), ("--ap", ap)):
        if not math.isfinite(value) or value < 0 or value > 1000:
            raise ValueError(f"{name} must be a number in [0, 1000], got {value:g}")
    if not atmospheres or any(a not in ATMOSPHERES for a in atmospheres):
        raise ValueError(f"--atmosphere must be a comma-separated list of {', '.join(ATMOSPHERES)}, "
                         f"got {','.join(atmospheres)!r}")
    mc = scenario.monte_carlo
    d = design(scenario.separation)
    raan = sso_raan()
    cases = [double_impulse_case(d, mc, raan),
             multi_impulse_case(multi_impulse.design(scenario.separation, mc=mc), mc, raan)]
    span = max(days) * SECONDS_PER_DAY
    rep = {"days": days, "rows": [], "zonal_effect": {}, "atmospheres": {}}
    for atm_name in dict.fromkeys(atmospheres):
        for case in cases:
            atm = truth_atmosphere(atm_name, case.density, case.chief_mean, span, f107=f107, f107a=f107a, ap=ap)
            case = dataclasses.replace(case, truth_atmosphere=atm)
            info = rep["atmospheres"].setdefault(atm_name, atm.describe())
            info.setdefault("effective_density", {})[case.name] = truth_effective_density(case, span)
            info["model_density"] = case.density
            for e in model_errors(case, days, effective=True):
                rep["rows"].append({"atmosphere": atm_name, **e.to_dict()})
            if atm_name == "normalised":
                rep["zonal_effect"][case.name] = zonal_effect(case, days).tolist()
    if mc_samples:
        over = {"samples": mc_samples}
        if seed is not None:
            over["seed"] = seed
        res = nonlinear_sweep(d, dataclasses.replace(mc, **over), p_values or scenario.p_values)
        rep["monte_carlo"] = res.to_dict()
    return rep


def print_validate(rep, out=None):
    w = (out or sys.stdout).write
    w("Model error: core secular ROE model minus nonlinear truth (J2-J4 + drag, mean ROE via Brouwer-Lyddane)\n")
    names = ("da", "dl", "dex", "dey", "dix", "diy")
    for atm_name, info in rep["atmospheres"].items():
        w(f"\ntruth atmosphere: {atm_name}" + (
            f" (NRLMSIS 2.0, F10.7 = {info['f107']:g}, F10.7a = {info['f107a']:g}, Ap = {info['ap']:g}, "
            f"fit RMS {info['fit_rms_ln_rho']:.1%} in ln rho)" if atm_name == "msis" else
            " (exponential, orbit-mean drag = the model's density)")
          + "; orbit-mean density " + ", ".join(f"{k} {v * 1e12:.3f}" for k, v in info["effective_density"].items())
          + f" g/km^3, model {info['model_density'] * 1e12:g} g/km^3\n")
        w(f"  {'case':15s}{'model':11s}{'day':>4s}" + "".join(f"{'a ' + n:>10s}" for n in names)
          + f"{'max|dr|':>10s}{'max|d|r||':>11s}   [m]\n")
        for row in (r for r in rep["rows"] if r["atmosphere"] == atm_name):
            for k, day in enumerate(row["days"]):
                w(f"  {row['case']:15s}{row['model']:11s}{day:4d}"
                  + "".join(f"{row['roe_error'][n][k]:10.1f}" for n in names)
                  + f"{row['rtn_error_max'][k]:10.1f}{row['distance_error_max'][k]:11.1f}\n")
    for name, z in rep["zonal_effect"].items():
        w(f"  J3+J4 effect on the truth ({name}, last day): a*dROE = [" + " ".join(f"{x:.1f}" for x in z[-1])
          + "] m\n")
    if "monte_carlo" in rep:
        m = rep["monte_carlo"]
        w(f"\nNonlinear vs linear Monte Carlo ({m['samples']} samples, same draws, {m['seconds']:.1f} s)\n")
        w(f"  {'p [m/s]':>8s}{'P(appr) lin':>13s}{'P(appr) nl':>12s}{'P(evap) lin':>13s}{'P(evap) nl':>12s}"
          f"{'same appr':>11s}{'same evap':>11s}\n")
        for lr, nr, ag in zip(m["linear_rows"], m["rows"], m["agreement"]):
            w(f"  {nr['p']:8.4f}{lr['p_approach']:13.3%}{nr['p_approach']:12.3%}{lr['p_evaporation']:13.3%}"
              f"{nr['p_evaporation']:12.3%}{ag['approach']:11.3%}{ag['evaporation']:11.3%}\n")



def cmd_validate(args):
    from ..core.config import load_scenario

    for name, value in (("--p", args.p), ("--seed", args.seed)):
        if value is not None and not args.mc:
            raise ValueError(f"{name} applies to the Monte Carlo only: give --mc N (N >= 1) with it")

    rep = validate_report(load_scenario(args.config), args.days, args.mc or 0, args.p, args.seed,
                          atmospheres=args.atmosphere,
                          f107=args.f107, f107a=args.f107a, ap=args.ap)
    emit(rep, args.json, print_validate)
    return 0


def register(subparsers):
    """Add ``propagate`` and ``validate`` to the ``roe-sep`` subparsers."""
    p = subparsers.add_parser("propagate", help="propagate ROE with a secular model or the nonlinear truth")
    p.add_argument("--roe", type=_roe_arg, required=True, metavar="DA,DL,DEX,DEY,DIX,DIY",
                   help="initial mean ROE a*[da dl dex dey dix diy] [m]")
    p.add_argument("--alt", type=finite_float(200e3, 1100e3, hi_open=True, unit="m"), default=515e3,
                   help="chief mean altitude a - R_E [m] in [200000, 1100000) (default 515000)")
    p.add_argument("--inc", type=finite_float(0.0, 180.0, lo_open=True, hi_open=True, unit="deg"),
                   help="chief inclination [deg] in (0, 180) (default: sun-synchronous)")
    p.add_argument("--u", type=finite_float(-360.0, 360.0, unit="deg"), default=0.0,
                   help="chief mean argument of latitude at t = 0 [deg] in [-360, 360]")
    p.add_argument("--days", type=finite_float(0.0, 30.0, lo_open=True, unit="days"), default=1.0,
                   help="propagation span [days] in (0, 30] (default 1)")
    p.add_argument("--step", type=finite_float(1.0, 86400.0, unit="s"), default=600.0,
                   help=f"output step [s] in [1, 86400], at most {MAX_POINTS} points (default 600)")
    p.add_argument("--model", choices=MODELS, default="j2drag", help="dynamics (default j2drag)")
    p.add_argument("--config", help="scenario YAML (drag properties and density)")
    p.add_argument("--json", action="store_true", help="machine-readable output (t [s], roe [m])")
    p.set_defaults(func=cmd_propagate)

    p = subparsers.add_parser("validate", help="model error of the secular ROE model against the nonlinear truth")
    p.add_argument("--config", help="scenario YAML")
    p.add_argument("--days", type=_days_list, default=(1, 2, 3),
                   help="comma-separated whole days, each in [1, 30] (default 1,2,3)")
    p.add_argument("--mc", type=integer(0, 100_000), metavar="N",
                   help="also run the nonlinear Monte Carlo with N samples (N in [0, 100000]) next to the linear one")
    p.add_argument("--p", type=p_list, help="comma-separated p values [m/s], each in [0, 1], for --mc (needs --mc)")
    p.add_argument("--seed", type=seed(), help="Monte Carlo seed in [0, 2**32 - 1] (needs --mc)")
    p.add_argument("--atmosphere", type=_atmospheres, default=["normalised", "msis"], metavar="LIST",
                   help="truth atmospheres, comma-separated: normalised (exponential, orbit-mean drag = the "
                        "scenario density), msis (NRLMSIS 2.0) (default both)")
    p.add_argument("--f107", type=finite_float(50.0, 400.0, unit="sfu"), default=140.0,
                   help="NRLMSIS: F10.7 of the previous day [sfu] in [50, 400] (default 140)")
    p.add_argument("--f107a", type=finite_float(50.0, 400.0, unit="sfu"), default=140.0,
                   help="NRLMSIS: 81-day mean F10.7 [sfu] in [50, 400] (default 140)")
    p.add_argument("--ap", type=finite_float(0.0, 400.0), default=15.0,
                   help="NRLMSIS: daily Ap in [0, 400] (default 15)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_validate)
