"""Parameter declaration and validation from the node's table (:mod:`roe_sep.nodes.parameters`): a bad parameter
stops the node at start-up with its name and its rule in the message.

:func:`declare` gives every parameter its ``ParameterDescriptor`` (type, description with unit and rule, range,
``read_only``), so that ``ros2 param describe`` shows the table's facts and rclpy itself refuses a ``ros2 param set``
of a read-only parameter or of a value outside the range; a settable parameter's other rules (choices, the form of
a string) are checked at run time by an ``on_set_parameters`` callback with the same messages.
"""

import math
import sys

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from rclpy.exceptions import InvalidParameterTypeException
from rclpy.parameter import Parameter

from ..core.config import ConfigError, load_scenario
from ..errors import ParameterError, plain, show
from . import parameters

ROS_TYPES = {"bool": Parameter.Type.BOOL, "int": Parameter.Type.INTEGER, "double": Parameter.Type.DOUBLE,
             "string": Parameter.Type.STRING, "string[]": Parameter.Type.STRING_ARRAY,
             "double[]": Parameter.Type.DOUBLE_ARRAY}


def descriptor(p: parameters.Param) -> ParameterDescriptor:
    """The ``ParameterDescriptor`` of a table entry (``ros2 param describe``)."""
    unit = f" [{p.unit}]" if p.unit else ""
    d = ParameterDescriptor(description=f"{p.description}{unit}", type=ROS_TYPES[p.type].value,
                            additional_constraints=parameters.rule_text(p), read_only=p.read_only)
    if p.range and p.type == "double":
        d.floating_point_range = [FloatingPointRange(from_value=float(p.range[0]), to_value=float(p.range[1]))]
    elif p.range and p.type == "int":
        lo, hi, *step = p.range
        d.integer_range = [IntegerRange(from_value=lo, to_value=hi, step=step[0] if step else 0)]
    return d


def node_table(cls) -> str:
    """The parameter table (:data:`~.parameters.TABLES` key) of a node class or of a subclass of one."""
    for c in cls.__mro__:
        if c.__name__ in parameters.CLASSES:
            return parameters.CLASSES[c.__name__]
    raise KeyError(f"no parameter table for {cls.__name__}")


def _param(node, name) -> parameters.Param:
    """The table entry of ``name`` for ``node``."""
    return parameters.table(node_table(type(node)))[name]


def _given(node, name):
    """The value given for ``name`` (a ``-p`` or params-file override) that rclpy refused for its type."""
    value = node.declare_parameter(name, None, ParameterDescriptor(dynamic_typing=True)).value
    node.undeclare_parameter(name)
    return value


def _check_on_set(node):
    """Refuse a run-time set of a settable parameter that breaks its rule (rclpy checks type, range, read-only)."""
    def check(params):
        for prm in params:
            if prm.value is None or not node.has_parameter(prm.name):  # declared (declare() checks it)
                continue
            try:
                p = _param(node, prm.name)
            except KeyError:
                continue
            why = parameters.problem(p, plain(prm.value))
            if why:
                return SetParametersResult(successful=False,
                                           reason=f"parameter '{prm.name}' {why}, got {show(prm.value)}")
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(check)


def declare(node, name, attr=None):
    """Declare the parameter ``name`` of the node's table with its descriptor and return its value, checked against
    its rule: :class:`ParameterError` ``parameter 'NAME' must be RULE, got VALUE`` otherwise (a value of another
    type included). ``attr``: for a settable parameter, the node attribute that follows a run-time change."""
    p = _param(node, name)
    if not node.has_parameter(name):  # (declared already: a managed node configured again)
        if not getattr(node, "_parameter_check", False):
            node._parameter_check = True
            _check_on_set(node)
        ptype = ROS_TYPES[p.type]
        try:
            value = node.declare_parameter(name, ptype, ParameterDescriptor(type=ptype.value)).value
        except InvalidParameterTypeException:
            raise ParameterError(f"parameter '{name}' must be {parameters.type_text(p)}, got "
                                 f"{show(_given(node, name))}") from None
        if value is None:
            # not given, or given as [] (rcl cannot type an empty list): the default, or an empty list of the type
            value = [] if p.type.endswith("[]") and name in getattr(node, "_parameter_overrides", {}) else p.default
            node.set_parameters([Parameter(name, ptype, value)])
        why = parameters.problem(p, plain(value))
        if why:
            raise ParameterError(f"parameter '{name}' {why}, got {show(value)}")
        node.set_descriptor(name, descriptor(p))
        if attr is not None and not p.read_only:
            node.add_post_set_parameters_callback(
                lambda params: [setattr(node, attr, plain(q.value)) for q in params if q.name == name])
    value = plain(node.get_parameter(name).value)
    why = parameters.problem(p, value)
    if why:
        raise ParameterError(f"parameter '{name}' {why}, got {show(value)}")
    return value


def scenario_of(scenario_file):
    """The scenario of the ``scenario_file`` parameter's value ('' = the embedded default); ParameterError naming the
    parameter for a file that cannot be read or is not a valid scenario."""
    try:
        return load_scenario(scenario_file or None)
    except ConfigError as exc:
        raise ParameterError(f"parameter 'scenario_file': {exc}") from exc


def require(name, ok, value, what):
    """Raise :class:`ParameterError` naming ``name`` unless ``ok`` (a rule between parameters: the table checks
    each on its own)."""
    if not ok:
        raise ParameterError(f"parameter '{name}' must be {what}, got {show(value)}")


def finite(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def help_requested(argv) -> bool:
    """``-h`` or ``--help`` among the arguments before ``--ros-args``."""
    args = list(sys.argv if argv is None else argv)[1:]
    if "--ros-args" in args:
        args = args[:args.index("--ros-args")]
    return "-h" in args or "--help" in args


def print_usage(node_module: str, summary: str = "") -> int:
    """A node executable's ``--help``: its usage and parameter table on stdout; exit code 0."""
    sys.stdout.write(parameters.usage(node_module, summary))
    return 0
