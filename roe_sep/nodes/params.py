"""Parameter declaration and validation: a bad parameter stops the node at start-up with its name in the message."""

import math

from rcl_interfaces.msg import ParameterDescriptor
from rclpy.exceptions import ParameterException

from ..errors import ParameterError


def declare(node, name, default, description):
    """Declare a parameter with a description (shown by ``ros2 param describe``) and return its value.

    A value of the wrong type (e.g. an integer for a double) raises :class:`ParameterError` naming the parameter.
    """
    if node.has_parameter(name):  # a managed node configured again (configure -> cleanup -> configure)
        value = node.get_parameter(name).value
        return list(value) if isinstance(default, list) else value
    try:
        value = node.declare_parameter(name, default, ParameterDescriptor(description=description)).value
    except ParameterException as exc:
        raise ParameterError(f"parameter '{name}' must have the type of its default {default!r}: {exc}") from exc
    return list(value) if isinstance(default, list) else value


def require(name, ok, value, what):
    """Raise :class:`ParameterError` naming ``name`` unless ``ok``."""
    if not ok:
        raise ParameterError(f"parameter '{name}' must be {what}, got {value!r}")


def finite(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
