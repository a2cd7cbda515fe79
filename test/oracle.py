"""Independent reference: exact two-body positions from Keplerian elements, to check the linear ROE model.

Written from the textbook (Vallado, 'Fundamentals of Astrodynamics', Alg. 10) and used only by tests.
"""

import numpy as np
from scipy.optimize import brentq

from roe_sep.core.constants import MU_EARTH


def kepler_to_cartesian(el):
    a, e, i, raan, w, m = el
    ecc_anom = brentq(lambda x: x - e * np.sin(x) - m, m - 1.0, m + 1.0)
    nu = 2.0 * np.arctan2(np.sqrt(1 + e) * np.sin(ecc_anom / 2), np.sqrt(1 - e) * np.cos(ecc_anom / 2))
    p = a * (1 - e**2)
    r_pf = p / (1 + e * np.cos(nu)) * np.array([np.cos(nu), np.sin(nu), 0.0])
    v_pf = np.sqrt(MU_EARTH / p) * np.array([-np.sin(nu), e + np.cos(nu), 0.0])

    def rot3(t):
        return np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]])

    def rot1(t):
        return np.array([[1, 0, 0], [0, np.cos(t), -np.sin(t)], [0, np.sin(t), np.cos(t)]])

    q = rot3(raan) @ rot1(i) @ rot3(w)
    return q @ r_pf, q @ v_pf


def rtn_relative_position(chief_el, deputy_el):
    """Deputy position minus chief position, in the chief's RTN frame [m]."""
    rc, vc = kepler_to_cartesian(chief_el)
    rd, _ = kepler_to_cartesian(deputy_el)
    r_hat = rc / np.linalg.norm(rc)
    n_hat = np.cross(rc, vc)
    n_hat /= np.linalg.norm(n_hat)
    t_hat = np.cross(n_hat, r_hat)
    return np.array([r_hat, t_hat, n_hat]) @ (rd - rc)
