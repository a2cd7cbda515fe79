import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from roe_sep.core.relmotion.maneuvers import control_matrix, delta_roe, dispersed_dv, dv_for_delta_roe
from roe_sep.core.relmotion.roe import roe_to_rtn

A, N = 6893137.0, 1.1031727426577115e-3
dv_st = st.tuples(*[st.floats(-2, 2, allow_nan=False)] * 3).map(np.array)
angle = st.floats(0, 2 * np.pi)


def test_eq2_hand_values_at_u_90deg():
    # seed 002 Eq. (2) at u = 90 deg: a Delta dex = dvR/n, a Delta dey = 2 dvT/n, a Delta diy = dvN/n
    d = delta_roe([1.0, 0.5, 0.2], np.pi / 2, A, N) * A
    np.testing.assert_allclose(d, [1.0 / N, -2.0 / N, 1.0 / N, 1.0 / N, 0.0, 0.2 / N], atol=1e-9)


@given(dv=dv_st, u=angle)
@settings(max_examples=200, deadline=None)
def test_impulse_changes_velocity_not_position(dv, u):
    """Eq. (2) and the RTN map agree: an impulse leaves the position and adds dv to the velocity."""
    droe = delta_roe(dv, u, A, N)
    pos, vel = roe_to_rtn(droe, u)
    np.testing.assert_allclose(pos * A, 0.0, atol=1e-9)
    np.testing.assert_allclose(vel * A * N, dv, atol=1e-12)


@given(dv=dv_st, u=angle)
@settings(max_examples=200, deadline=None)
def test_inverse_of_eq2(dv, u):
    np.testing.assert_allclose(dv_for_delta_roe(delta_roe(dv, u, A, N), u, A, N), dv, atol=1e-12)


def test_control_matrix_broadcasts():
    u = np.linspace(0, 6, 7)
    g = control_matrix(u)
    assert g.shape == (7, 6, 3)
    np.testing.assert_allclose(g[3], control_matrix(u[3]))


def test_eq22_identity_and_hand_rotation():
    dv = np.array([-1.32925, -0.162718, 0.441269])
    np.testing.assert_allclose(dispersed_dv(dv, 1.0, np.zeros(3)), dv)
    # eps_z rotates R into T: (1, 0, 0) -> (1, -ez, 0); eps_x couples T and N; scaled by f
    np.testing.assert_allclose(dispersed_dv(np.array([1.0, 0, 0]), 2.0, np.array([0, 0, 1e-3])), [2.0, -2e-3, 0])
    np.testing.assert_allclose(dispersed_dv(np.array([0, 1.0, 0]), 1.0, np.array([1e-3, 0, 0])), [0, 1.0, -1e-3])
    np.testing.assert_allclose(dispersed_dv(np.array([0, 0, 1.0]), 1.0, np.array([0, 1e-3, 0])), [-1e-3, 0, 1.0])


def test_eq22_vectorized():
    rng = np.random.default_rng(0)
    dv = rng.normal(size=3)
    f = rng.normal(1, 0.1, 20)
    eps = rng.normal(0, 1e-4, (20, 3))
    out = dispersed_dv(dv, f, eps)
    assert out.shape == (20, 3)
    np.testing.assert_allclose(out[5], dispersed_dv(dv, f[5], eps[5]))
    # a small rotation keeps the magnitude to first order
    assert np.linalg.norm(out[5]) == pytest.approx(abs(f[5]) * np.linalg.norm(dv), rel=1e-6)


def test_eq18_thruster_error_on_the_unreduced_drift_stop():
    """Seed 002 Eq. (18): dv_T2* = dv_T2 + e2 - |p| with e2 = (f2 - 1) dv_T2 of the unreduced burn (Eq. 16)."""
    from roe_sep.core.relmotion.maneuvers import unreduced_burns

    dv_t2, p = 0.162718, 0.05
    unreduced = np.array([-1.32925, dv_t2, 0.0])
    commanded = unreduced - [0.0, p, 0.0]
    np.testing.assert_allclose(unreduced_burns(commanded, p)[0], unreduced)
    for f2 in (0.85, 1.0, 1.15):
        out = dispersed_dv(commanded, f2, np.zeros(3), unreduced)
        assert out[1] == pytest.approx(dv_t2 + (f2 - 1.0) * dv_t2 - p, abs=1e-15)  # Eq. (18)
        assert out[1] != pytest.approx(f2 * (dv_t2 - p), abs=1e-6) or f2 == 1.0  # not the error on the reduced burn
        assert out[0] == pytest.approx(f2 * unreduced[0])
    # Eq. (20), second line, at the lower bound of Eq. (21), |p| = e1 + e2 (e_i at 3 sigma of the unreduced
    # burns): a 3-sigma over-performing drift-stop leaves dv_T2* = |dv_T1| - e1, exactly the drift of a 3-sigma
    # under-performing ejection (da_F* = 0); 0.0732231 m/s is the design value the seeds quote
    e1, e2 = 3 * 0.10 * dv_t2, 3 * 0.05 * dv_t2
    assert e1 + e2 == pytest.approx(0.0732231, abs=1e-7)
    out = dispersed_dv(unreduced - [0.0, e1 + e2, 0.0], 1.15, np.zeros(3), unreduced)
    assert out[1] == pytest.approx(dv_t2 - e1, abs=1e-15)
    # reference None is Eq. (22) exactly; attitude errors rotate the whole commanded burn
    eps = np.array([1e-4, -2e-4, 3e-4])
    np.testing.assert_allclose(dispersed_dv(commanded, 1.1, eps, commanded), dispersed_dv(commanded, 1.1, eps))
    np.testing.assert_allclose(dispersed_dv(commanded, 1.0, eps, unreduced), dispersed_dv(commanded, 1.0, eps))


def test_unreduced_burns_split_and_vectorized():
    from roe_sep.core.relmotion.maneuvers import unreduced_burns

    parts = np.array([[0.0, 0.3, 0.0], [0.0, 0.1, 0.0]])  # a drift reduction split over two orbits
    ref = unreduced_burns(parts, 0.08)
    assert ref[:, 1].sum() == pytest.approx(0.48) and ref[0, 1] / ref[1, 1] == pytest.approx(3.0)
    np.testing.assert_allclose(unreduced_burns(-parts, 0.08), -ref)  # the carrier's own burns: same rule
    np.testing.assert_allclose(unreduced_burns(parts, 0.0), parts)
    f = np.array([0.9, 1.0, 1.1])
    out = dispersed_dv(parts[0], f, np.zeros((3, 3)), ref[0])
    np.testing.assert_allclose(out[:, 1], 0.3 + (f - 1) * ref[0, 1])
