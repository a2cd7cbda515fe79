"""What the radar sensor (:mod:`.radar`) and the OD (:mod:`.radar_od`) share: the ground stations, the epoch and the
measurement sigmas of their parameters, and the truth message's chief as both read it."""

import math
import operator
from typing import NamedTuple

import numpy as np

from ..core.constants import R_EARTH
from ..core.od.radar import Station, julian_date
from ..validate import ROE_FIELDS
from .convert import elements_to_array, msg_to_roe, time_to_sec
from .params import ParameterError, declare, require

_ROE_VALUES = operator.attrgetter(*ROE_FIELDS)  # a message's a*ROE [m], in ROE order


def stations_of(node):
    """The node's parameters ``stations``, ``station_*`` and ``epoch_utc``: ([Station], Julian date of sim time 0);
    ParameterError unless every station has its coordinates (the table checks each parameter alone) or for an
    epoch that is not an ISO-8601 date-time."""
    names = declare(node, "stations")
    lats = declare(node, "station_latitudes_deg")
    lons = declare(node, "station_longitudes_deg")
    alts = declare(node, "station_altitudes_m")
    epoch = declare(node, "epoch_utc")
    for name, values in (("station_latitudes_deg", lats), ("station_longitudes_deg", lons),
                         ("station_altitudes_m", alts)):
        require(name, len(values) == len(names), values, f"{len(names)} value(s), one per station of 'stations'")
    try:
        jd0 = julian_date(epoch)
    except (ValueError, TypeError) as exc:
        raise ParameterError(f"parameter 'epoch_utc' must be an ISO-8601 UTC date-time, got {epoch!r}: {exc}") \
            from exc
    return [Station(s, math.radians(la), math.radians(lo), float(h))
            for s, la, lo, h in zip(names, lats, lons, alts)], jd0


class Tracking(NamedTuple):
    """The parameters the sensor and the OD read alike (:func:`tracking_of`)."""

    stations: list
    """The ground stations (:class:`~roe_sep.core.od.radar.Station`)."""
    jd0: float
    """Julian date of sim time 0."""
    site_ef: list
    """Each station's ECEF position [m]."""
    site_enu: list
    """Each station's local east-north-up frame (rows in ECEF)."""
    sigma: np.ndarray
    """The measurement 1-sigma ``[range [m], azimuth [rad], elevation [rad]]``."""


def tracking_of(node) -> Tracking:
    """The node's stations and epoch (:func:`stations_of`) and its ``sigma_range_m`` and ``sigma_angle_deg``;
    ParameterError as :func:`stations_of` and :func:`~.params.declare` say."""
    stations, jd0 = stations_of(node)
    sigma_range = declare(node, "sigma_range_m")
    sigma_angle = math.radians(declare(node, "sigma_angle_deg"))
    return Tracking(stations, jd0, [s.ecef for s in stations], [s.enu for s in stations],
                    np.array([sigma_range, sigma_angle, sigma_angle]))


def parse_truth(msg):
    """(t, dimensionless ROE, chief elements) of a truth message; ValueError on NaN or an impossible orbit.

    The tests on the message's floats: the chief's a, e and i in their bounds (so finite), its other elements
    finite; the ROE finite exactly when the a*ROE are (divided by an a of the bounds). The arrays are those of
    :func:`elements_to_array` and :func:`msg_to_roe`."""
    c = msg.chief
    kep = elements_to_array(c)
    t = time_to_sec(msg.header.stamp)
    a, e, inc, raan, argp, u = (c.semi_major_axis, c.eccentricity, c.inclination, c.raan, c.arg_perigee,
                                c.mean_arg_latitude)
    if not (R_EARTH + 1e5 < a < R_EARTH + 5e6 and 0.0 <= e < 0.1 and 0.0 <= inc <= math.pi
            and math.isfinite(raan) and math.isfinite(argp) and math.isfinite(u - argp)):
        raise ValueError(f"chief elements are not a near-circular low Earth orbit: {kep.tolist()}")
    roe = msg_to_roe(msg)
    if not all(map(math.isfinite, _ROE_VALUES(msg))):
        raise ValueError(f"ROE are not finite: {(roe * kep[0]).tolist()} m")
    return t, roe, kep
