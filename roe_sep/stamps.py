"""Time stamps (``builtin_interfaces/Time``: whole seconds ``sec`` and ``nanosec`` in [0, 1e9)) <-> seconds.

One function each way, for the nodes (:mod:`roe_sep.nodes.convert`), message validation (:mod:`roe_sep.validate`),
the CCSDS export (:mod:`roe_sep.ndm.dataset`) and the run report (:mod:`roe_sep.report`). A stamp is read by its
fields only (duck typing): a message received by rclpy and one decoded from a bag by mcap_ros2 give the same seconds.

The lowest layer: imports nothing of roe_sep but :mod:`roe_sep.errors`, and neither rclpy nor NumPy.
"""

import math

from .errors import RoeSepError, show

NANOSECONDS_PER_SECOND = 1_000_000_000
INT32_MAX = 2**31 - 1  # builtin_interfaces/Time.sec is an int32


def time_to_sec(t) -> float:
    """Seconds of a stamp: ``t.sec + t.nanosec * 1e-9`` (no check: :func:`roe_sep.validate.time_of` checks)."""
    return t.sec + t.nanosec * 1e-9


def sec_nanosec(seconds: float) -> tuple:
    """``(sec, nanosec)`` of a time [s]: whole seconds rounded down, nanoseconds to the nearest, with the carry
    (``0.9999999999`` s -> ``(1, 0)``). A time that is not finite or outside the int32 seconds of a stamp raises
    :class:`roe_sep.errors.RoeSepError`; a negative time is a valid stamp (``-0.25`` s -> ``(-1, 750000000)``)."""
    try:
        value = float(seconds)
    except (TypeError, ValueError):
        value = math.nan
    if not math.isfinite(value):
        raise RoeSepError(f"time must be a finite number of seconds, got {show(seconds)}")
    sec = math.floor(value)
    nanosec = int(round((value - sec) * NANOSECONDS_PER_SECOND))
    if nanosec >= NANOSECONDS_PER_SECOND:
        sec, nanosec = sec + 1, nanosec - NANOSECONDS_PER_SECOND
    if not -INT32_MAX - 1 <= sec <= INT32_MAX:
        raise RoeSepError(f"time must fit a stamp's int32 seconds, got {show(seconds)} s")
    return int(sec), nanosec


__all__ = ["NANOSECONDS_PER_SECOND", "sec_nanosec", "time_to_sec"]
