import dataclasses
import math

import numpy as np
import pytest

from roe_sep.core.relmotion.dynamics import propagate
from roe_sep.core.relmotion.maneuvers import delta_roe
from roe_sep.core.relmotion.roe import e_vector_polar, i_vector_polar
from roe_sep.core.separation.double_impulse import InfeasibleDesignError, SeparationConfig, admissible_k, design

D = design()


def test_published_dv1_and_dv2():
    """Seed 002 Eq. (16)."""
    np.testing.assert_allclose(D.dv1_rtn, [-1.329250, -0.162718, 0.441269], atol=5e-7)
    np.testing.assert_allclose(D.dv2_rtn, [-1.329250, +0.162718, 0.0], atol=5e-7)
    assert np.linalg.norm(D.dv1_rtn) == pytest.approx(1.41, rel=1e-12)  # the SPL magnitude, Eq. (5)


def test_published_bounds_table2():
    """Seed 002 Eq. (10) and Table 2: a de_min = 511.25 m, margin 127.81 m at 515 km."""
    b = D.bounds
    assert b.a_de_min == pytest.approx(511.25, abs=0.005)
    assert b.a_di_margin == pytest.approx(127.81, abs=0.005)
    assert (math.ceil(b.a_de_min), math.floor(b.a_de_max)) == (512, 596)
    assert (math.ceil(b.a_di_min), math.floor(b.a_di_max)) == (278, 805)
    assert (b.a_dl_min, b.a_dl_max) == (5000.0, 10000.0)


def test_published_p_3sigma():
    """Seed 002: 3-sigma under-performance of both maneuvers gives p = 0.0732231 m/s."""
    assert D.p_min == pytest.approx(0.0732231, abs=5e-8)
    assert D.p_max == pytest.approx(D.n * 590.0 / 4 - 3 * 0.05 * D.n * 590.0 / 4)


def test_k_range_eq14():
    assert D.k_admissible == (1, 3)  # seed 002: 'the admissible values of k ... are [1, 3]'
    assert D.a_dl_f == pytest.approx(-1.5 * 3 * math.pi * D.a_da1 + D.a_dl_star)
    assert admissible_k(4819.7, -295.0, 5000.0, 10000.0) == (1, 3)
    assert admissible_k(12000.0, -295.0, 5000.0, 10000.0) == ()


@pytest.mark.parametrize("leading", [True, False])
def test_plan_reaches_the_aimed_orbit_through_eq2(leading):
    """Apply both impulses with Eq. (2): da_F = 0, |de| = de_F anti-/parallel to di (phase u1), dl_F of Eq. (13)."""
    d = design(SeparationConfig(leading=leading))
    roe = d.final_roe() * d.a
    assert roe[0] == pytest.approx(0.0, abs=1e-9)
    assert roe[1] == pytest.approx(d.a_dl_f)
    assert math.copysign(1, roe[1]) == (1 if leading else -1)
    de, phi = e_vector_polar(roe)
    di, theta = i_vector_polar(roe)
    assert de == pytest.approx(590.0)
    assert di == pytest.approx(400.0)
    assert theta == pytest.approx(math.radians(88.0))
    assert math.cos(phi - theta) == pytest.approx(-1.0 if leading else 1.0)


def test_eq21_lower_bound_is_the_zero_drift_boundary():
    """At |p| = e1 + e2 the worst case of Eq. (20) ends exactly drift-free.

    Design assumption of seed 002: errors only on the tangential components, e1 = 3 sigma under-performance of
    dvT1 and e2 = 3 sigma over-performance of dvT2 (which strengthens the reduction's opposite, Eq. 18).
    """
    dv1 = D.dv1_rtn * np.array([1.0, 1.0 - 3 * 0.10, 1.0])
    dv2 = D.drift_stop_dv(D.p_min) + np.array([0.0, 3 * 0.05 * D.dv2_rtn[1], 0.0])
    assert D.drift_stop_dv(D.p_min)[1] == pytest.approx(D.dv2_rtn[1] - D.p_min)
    roe1 = delta_roe(dv1, D.u1, D.a, D.n)
    final = propagate(roe1, (D.u2 - D.u1) / D.n, D.a, D.inc, j2=False) + delta_roe(dv2, D.u2, D.a, D.n)
    assert final[0] * D.a == pytest.approx(0.0, abs=1e-6)


def test_following_is_the_mirror_case():
    d = design(SeparationConfig(leading=False))
    np.testing.assert_allclose(d.dv1_rtn, [1.329250, 0.162718, 0.441269], atol=5e-7)
    assert d.eta == 0.0
    assert d.drift_stop_dv(0.05)[1] == pytest.approx(-0.162718 + 0.05, abs=5e-7)


@pytest.mark.parametrize(
    "change,match",
    [
        ({"spl_dv": float("nan")}, "spl_dv must be finite"),
        ({"spl_dv": -1.0}, "spl_dv must be positive"),
        ({"spl_dv": "fast"}, "spl_dv must be a number"),
        ({"spl_dv": 0.4}, "too small for the aimed orbit"),
        ({"a_de_f": 400.0}, "safety #6"),
        ({"a_di_f": 250.0}, "safety #7"),
        ({"a_de_f": 600.0}, "visibility #2"),
        ({"a_di_f": 900.0}, "visibility #3"),
        ({"k": 2}, "odd natural number"),
        ({"k": 5}, r"safety #1 / visibility #1 \(Eq. 14\).*admissible k: \[1, 3\]"),
        ({"eta_deg": 0.0}, "safety #2"),
        ({"leading": "yes"}, "leading must be true or false"),
        ({"a_dl_min": 20000.0}, "a_dl_min"),
    ],
)
def test_infeasible_input_names_the_constraint(change, match):
    with pytest.raises(ValueError, match=match):
        design(dataclasses.replace(SeparationConfig(), **change))


def test_infeasible_is_a_distinct_error_type():
    with pytest.raises(InfeasibleDesignError):
        design(SeparationConfig(a_de_f=400.0))
    design(SeparationConfig(eta_deg=180.0))  # consistent eta is accepted
