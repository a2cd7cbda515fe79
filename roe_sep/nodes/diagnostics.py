"""Helpers for the standard ``/diagnostics`` topic (diagnostic_msgs/DiagnosticArray)."""

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from .convert import sec_to_time

OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR


def publish_status(node, publisher, level, message, values=None, hardware_id="roe_sep", part="", stamp=None):
    """Publish one DiagnosticStatus named ``roe_sep/<node name>[/<part>]`` with ``values`` as key/value strings.

    Stamped with ``stamp`` [s] if given, else the sim time of the node's current lockstep step, else its clock."""
    name = f"roe_sep/{node.get_name()}" + (f"/{part}" if part else "")
    if isinstance(level, int):  # the message field is a byte
        level = bytes([level])
    status = DiagnosticStatus(level=level, name=name, message=message,
                              hardware_id=hardware_id,
                              values=[KeyValue(key=str(k), value=str(v)) for k, v in (values or {}).items()])
    array = DiagnosticArray(status=[status])
    lockstep = getattr(node, "lockstep", None)
    if stamp is None and lockstep is not None and lockstep.active and lockstep.time is not None:
        stamp = lockstep.time
    if stamp is not None:
        array.header.stamp = sec_to_time(stamp)
    else:
        array.header.stamp = node.get_clock().now().to_msg()
    publisher.publish(array)
