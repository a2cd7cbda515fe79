"""The carrier's elements of :mod:`roe_sep.ndm.offline_od` from an ephemeris: the inverse of the model that writes
the carrier's OEM (circular orbits of mean elements carried with the J2 secular rates)."""

import numpy as np
import pytest

from roe_sep.core.od.radar import chief_from_kepler, chief_position_velocity
from roe_sep.core.relmotion.dynamics import propagate_chief
from roe_sep.ndm.offline_od import CarrierSegment, carrier_at, chief_elements


@pytest.mark.parametrize("inc_deg", [97.4, 51.6, 5.0])
def test_chief_elements_invert_the_circular_model_through_the_nodal_turn(inc_deg):
    kep0 = np.array([6.893e6, 0.0, np.radians(inc_deg), 1.1, 0.0, 0.3])
    t = np.arange(0.0, 86400.0, 300.0)
    kep = propagate_chief(kep0, t)
    r, _ = chief_position_velocity(*chief_from_kepler(kep))
    got = chief_elements(t, r)
    assert np.allclose(got[:, 0], kep[:, 0], rtol=0, atol=1e-6)
    assert np.allclose(got[:, 2], kep[:, 2], rtol=0, atol=1e-8)  # 7 cm at the carrier
    d = (got[:, [3, 5]] - np.stack([kep[:, 3], kep[:, 4] + kep[:, 5]], axis=-1) + np.pi) % (2 * np.pi) - np.pi
    assert np.max(np.abs(d)) < 1e-8
    # (without the nodal turn the plane of two positions 300 s apart would lean by up to 1.8e-4 rad at 97.4 deg)
    back, _ = chief_position_velocity(*chief_from_kepler(got))
    assert np.max(np.linalg.norm(back - r, axis=-1)) < 1e-6  # u and the plane through r: r itself


def test_carrier_at_takes_the_first_state_at_or_after_the_epoch_and_no_other_segment():
    kep0 = np.array([6.893e6, 0.0, np.radians(97.4), 1.1, 0.0, 0.3])
    t = np.arange(0.0, 3000.0, 300.0)
    seg = CarrierSegment(t, propagate_chief(kep0, t))
    kep, t_state = carrier_at([seg], 610.0)
    assert t_state == 900.0 and np.allclose(kep, propagate_chief(kep0, np.array([610.0]))[0], atol=1e-9)
    assert carrier_at([seg], 2700.0)[1] == 2700.0
    assert carrier_at([seg], 2701.0) is None and carrier_at([seg], -1.0) is None
