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
