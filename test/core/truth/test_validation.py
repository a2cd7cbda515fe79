"""Model error of the secular ROE model against the nonlinear truth (issue 5 item 3), the nonlinear Monte Carlo
(item 4) and the ``propagate``/``validate`` subcommands (item 5).

Bounds are derived, not tuned. With the truth atmosphere referenced at a - R_E (``Atmosphere.scaled``, the
default before issue 20) the j2drag model's dominant error is the differential-drag magnitude: the truth's
orbit-averaged along-track drag is a factor g = <rho(h)/rho_ref |v_r| v_r.T> / v^2 = 0.952 of the model's (mean
radius 4.2 km above a - R_E: rho x 0.936; co-rotating atmosphere, retrograde orbit: x 1.017; measured in
test_nonlinear). With aDa' = the model's a*da rate (68.45 m/day), the errors are then
    a da:  (1 - g) aDa' t,         a dl:  3/4 n (1 - g) aDa' t^2,
i.e. 3.3 m and 233 m after one day, 9.8 m and 2.1 km after three. The tests allow 25 % above these; the e/i vector
errors (J2 of second order, J3/J4, the O(J2 dv) burn mapping, drag normal to the orbit) stay below 10 m in 3 days.
The default truth atmosphere (``normalised``) has g = 1 by construction: that error must be gone.
"""

import argparse
import dataclasses
import math

import numpy as np
import pytest

from roe_sep.core.constants import R_EARTH
from roe_sep.core.montecarlo.sweep import MonteCarloConfig
from roe_sep.core.relmotion.dynamics import drag_da_dot
from roe_sep.core.separation import multi_impulse
from roe_sep.core.separation.double_impulse import design
from roe_sep.core.truth.nonlinear import Atmosphere
from roe_sep.core.truth.validation import double_impulse_case, model_errors, multi_impulse_case, nonlinear_sweep

G_DRAG = 0.952  # truth / model differential drag (derived above, measured in test_nonlinear)
DAY = 86400.0


def _predicted(case, days):
    rate = abs(drag_da_dot(case.b_deputy - case.b_chief, case.density, case.a)) * case.a  # m/s
    t = np.asarray(days) * DAY
    n = math.sqrt(3.986004418e14 / case.a**3)
    return (1 - G_DRAG) * rate * t, 0.75 * n * (1 - G_DRAG) * rate * t**2


def _cases():
    mc = MonteCarloConfig()
    return [double_impulse_case(design(), mc), multi_impulse_case(multi_impulse.design(), mc)]


@pytest.fixture(scope="module")
def errors():
    """Model errors against the truth in the atmosphere referenced at a - R_E (g = 0.952)."""
    out = {}
    for c in _cases():
        c = dataclasses.replace(c, truth_atmosphere=Atmosphere.scaled(c.density, c.a - R_EARTH))
        out[c.name] = (c, {e.model: e for e in model_errors(c, (1, 2, 3), step=120.0)})
    return out


@pytest.fixture(scope="module")
def errors_normalised():
    return {c.name: (c, {e.model: e for e in model_errors(c, (1, 2, 3), step=120.0, effective=True)})
            for c in _cases()}


@pytest.mark.parametrize("name", ["double_impulse", "multi_impulse"])
def test_normalised_truth_removes_the_drag_magnitude_error(errors, errors_normalised, name):
    """Issue 20: with the orbit-mean drag equal to the model's density the along-track error is no longer the
    drag-magnitude one: after 3 days below a quarter of it, and the model at the truth's effective density
    (``j2drag_eff``) differs from the model by less than the rounding of that mean (< 20 m)."""
    case, errs = errors_normalised[name]
    e, eff = errs["j2drag"], errs["j2drag_eff"]
    _, dl_pred = _predicted(case, e.days)
    assert np.all(np.abs(e.roe_error[:, 1]) < 0.25 * dl_pred)
    assert np.all(np.abs(e.roe_error[:, 1]) < 0.25 * np.abs(errors[name][1]["j2drag"].roe_error[:, 1]))
    assert np.all(np.abs(e.roe_error[:, 0]) < 0.5 * _predicted(case, e.days)[0] + 1.0)
    assert np.all(np.abs(eff.roe_error[:, 1] - e.roe_error[:, 1]) < 20.0)
    assert np.all(np.abs(e.roe_error[:, 2:]) < 10.0)


@pytest.mark.parametrize("name", ["double_impulse", "multi_impulse"])
def test_j2drag_model_error_within_derived_bounds(errors, name):
    case, errs = errors[name]
    e = errs["j2drag"]
    da_pred, dl_pred = _predicted(case, e.days)
    assert np.all(np.abs(e.roe_error[:, 0]) <= 1.25 * da_pred)
    assert np.all(np.abs(e.roe_error[:, 1]) <= 1.25 * dl_pred)
    assert np.all(np.abs(e.roe_error[:, 1]) >= 0.75 * dl_pred)  # the error is the one derived, not another
    assert np.all(np.abs(e.roe_error[:, 2:]) < 10.0)
    assert np.all(e.rtn_error_max <= 1.25 * dl_pred + 30.0)  # RTN: along-track, plus J2 short-period terms


@pytest.mark.parametrize("name", ["double_impulse", "multi_impulse"])
def test_drag_free_models_miss_the_drift(errors, name):
    _, errs = errors[name]
    assert abs(errs["j2"].roe_error[0, 1]) > 4000.0  # differential drag is not optional (> 4 km after a day)
    assert np.all(np.abs(errs["keplerian"].roe_error[:, 2]) > np.abs(errs["j2"].roe_error[:, 2]))  # J2 e-rotation


def test_nonlinear_monte_carlo_agrees_with_linear():
    d = design()
    mc = MonteCarloConfig(samples=400, seed=3, horizon=DAY, j2=True)  # the truth always has J2
    res = nonlinear_sweep(d, mc, [0.0, 0.06])
    for lin, nl, ag in zip(res.linear_rows, res.rows, res.agreement):
        assert abs(lin["p_approach"] - nl["p_approach"]) <= 0.02
        assert ag["approach"] >= 0.98 and ag["evaporation"] >= 0.99
    assert res.rows[0]["p_approach"] > 0.3  # p = 0 approaches often, in both (seed 002 Fig. 4)
    for rms in res.roe_diff_after_stop.values():
        assert max(rms) < 10.0  # m: linear (J2 + drag) vs nonlinear ROE right after the drift-stop, RMS


def _parser():
    from roe_sep.cli import nonlinear as cli_nonlinear

    ap = argparse.ArgumentParser(prog="roe-sep")
    cli_nonlinear.register(ap.add_subparsers(dest="command", required=True))
    return ap


def _run(argv, capsys):
    import json

    args = _parser().parse_args(argv + ["--json"])
    assert args.func(args) == 0
    return json.loads(capsys.readouterr().out)


def test_propagate_nonlinear_agrees_with_j2drag(capsys):
    base = ["propagate", "--roe", "0,9000,-20,-590,14,400", "--days", "1", "--step", "3600"]
    nl = _run(base + ["--model", "nonlinear"], capsys)
    j2d = _run(base + ["--model", "j2drag"], capsys)
    assert nl["t"] == j2d["t"] and len(nl["roe"]) == 25 and len(nl["roe"][0]) == 6
    diff = np.abs(np.array(nl["roe"]) - np.array(j2d["roe"]))[-1]
    case = double_impulse_case(design())
    da_pred, dl_pred = _predicted(case, [1])
    assert diff[0] <= 1.25 * da_pred[0] and diff[1] <= 1.25 * dl_pred[0] and np.all(diff[2:] < 5.0)


def test_cli_rejects_bad_input(capsys):
    from roe_sep.cli import nonlinear as cli_nonlinear
    from roe_sep.core.config import load_scenario

    with pytest.raises(SystemExit) as exc:
        _parser().parse_args(["propagate", "--roe", "1,2,3"])
    assert exc.value.code == 2
    with pytest.raises(ValueError, match="--alt"):
        cli_nonlinear.propagate_report([0] * 6, -1.0, None, 0.0, 1.0, step=600.0, model="j2", scenario=load_scenario())
    with pytest.raises(SystemExit) as exc:
        _parser().parse_args(["validate", "--atmosphere", "normalised,jacchia"])
    assert exc.value.code == 2
    with pytest.raises(ValueError, match="--f107"):
        cli_nonlinear.validate_report(load_scenario(), [1], f107=float("nan"))


def test_validate_reports_each_truth_atmosphere(capsys):
    """``roe-sep validate``: the model error under the normalised atmosphere and under NRLMSIS 2.0. NRLMSIS at
    moderate activity (F10.7 = 140, Ap = 15) has a third of the seeds' 1 g/km^3 as its orbit mean, so the model
    with 1 g/km^3 over-predicts the drift by the derived amount 3/4 n (1 - rho_eff/rho) aDa' t^2; at the truth's
    orbit-mean density the model error is a few tens of meters."""
    rep = _run(["validate", "--days", "1"], capsys)
    assert list(rep["atmospheres"]) == ["normalised", "msis"]
    rows = {(r["atmosphere"], r["case"], r["model"]): r for r in rep["rows"]}
    assert len(rows) == 2 * 2 * 4
    for case in ("double_impulse", "multi_impulse"):
        assert rep["atmospheres"]["normalised"]["effective_density"][case] == pytest.approx(1e-12, rel=0.01)
        rho_eff = rep["atmospheres"]["msis"]["effective_density"][case]
        assert 1e-13 < rho_eff < 0.6e-12
        c = next(c for c in _cases() if c.name == case)
        rate = abs(drag_da_dot(c.b_deputy - c.b_chief, c.density, c.a)) * c.a
        n = math.sqrt(3.986004418e14 / c.a**3)
        pred = 0.75 * n * (1 - rho_eff / c.density) * rate * DAY**2
        assert rows[("msis", case, "j2drag")]["roe_error"]["dl"][0] == pytest.approx(pred, rel=0.1)
        assert abs(rows[("msis", case, "j2drag_eff")]["roe_error"]["dl"][0]) < 100.0
        assert abs(rows[("normalised", case, "j2drag")]["roe_error"]["dl"][0]) < 50.0
    assert rep["atmospheres"]["msis"]["f107"] == 140.0 and rep["atmospheres"]["msis"]["fit_rms_ln_rho"] < 0.1
