"""Parameter declaration and validation: a bad parameter stops the node at start-up with its name in the message."""

import math

from rcl_interfaces.msg import ParameterDescriptor


class ParameterError(ValueError):
    """A node parameter is invalid; the message names it."""


def declare(node, name, default, description):
    """Declare a parameter with a description (shown by ``ros2 param describe``) and return its value."""
    return node.declare_parameter(name, default, ParameterDescriptor(description=description)).value


def require(name, ok, value, what):
    """Raise :class:`ParameterError` naming ``name`` unless ``ok``."""
    if not ok:
        raise ParameterError(f"parameter '{name}' must be {what}, got {value!r}")


def finite(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
