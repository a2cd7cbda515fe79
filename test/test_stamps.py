"""roe_sep.stamps: a stamp <-> seconds, once; and the validation of a message's stamp (roe_sep.validate)."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from roe_sep.errors import BadMessage, RoeSepError
from roe_sep.stamps import sec_nanosec, time_to_sec
from roe_sep.validate import time_of


def stamp(sec, nanosec):
    return SimpleNamespace(sec=sec, nanosec=nanosec)


@pytest.mark.parametrize("seconds", [0.0, 1.5, 1000.000000001, 87247.267903516, 864000.25, 2**31 - 1.0, -0.25])
def test_round_trip_to_the_nanosecond(seconds):
    sec, nanosec = sec_nanosec(seconds)
    assert isinstance(sec, int) and isinstance(nanosec, int) and 0 <= nanosec < 1_000_000_000
    assert time_to_sec(stamp(sec, nanosec)) == pytest.approx(seconds, abs=1e-9)


def test_nanosecond_carry_and_rounding():
    assert sec_nanosec(0.9999999999) == (1, 0)  # rounds up to a whole second: carried, never nanosec = 1e9
    assert sec_nanosec(41.9999999996) == (42, 0)
    assert sec_nanosec(2.0000000004) == (2, 0) and sec_nanosec(2.0000000006) == (2, 1)
    assert sec_nanosec(-0.25) == (-1, 750_000_000)  # a negative time is a valid stamp (validation refuses it)
    assert sec_nanosec(np.float64(3.5)) == (3, 500_000_000) and sec_nanosec(7) == (7, 0)
    assert time_to_sec(stamp(3, 500_000_000)) == 3.5 and time_to_sec(stamp(0, 1)) == 1e-9


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, np.float64(np.nan), 2.0**31, -(2.0**31) - 1, "x",
                                 None])
def test_no_stamp_for_a_time_that_is_not_one(bad):
    with pytest.raises(RoeSepError, match="time must") as info:
        sec_nanosec(bad)
    assert "np." not in str(info.value)


def test_validation_refuses_a_negative_or_malformed_stamp():
    assert time_of("header.stamp", stamp(12, 250_000_000)) == 12.25
    for bad in (stamp(-1, 0), stamp(0, -1), stamp(0, 1_000_000_000)):
        with pytest.raises(BadMessage, match="header.stamp") as info:
            time_of("header.stamp", bad)
        assert info.value.field == "header.stamp" and "non-negative time" in str(info.value)
