"""The end of a scenario as the simulator reports it on ``/diagnostics``: its final status, "scenario complete" or
"scenario aborted: ...", repeated every wall second until the simulator stops. Watchers (the runner's observer, the
ground_bridge) read it from a raw subscription's bytes. Importing this module loads nothing else (the runner's
start-up stays light); the message package loads when a status that may be final is decoded."""

FINAL_MARK = b"scenario "  # in the serialized bytes of every final status (CDR strings are their UTF-8 bytes)


def final_status(array):
    """The simulator's final status in a ``DiagnosticArray`` ("scenario complete" or "scenario aborted: ..."), or
    None."""
    return next((s.message for s in array.status if s.name == "roe_sep/sim" and (
        s.message == "scenario complete" or s.message.startswith("scenario aborted"))), None)


def final_status_of(data: bytes):
    """:func:`final_status` of a serialized ``DiagnosticArray`` (a raw subscription's message), decoded only when its
    bytes contain :data:`FINAL_MARK`: a watcher reads every status of a run (about 950) and decodes the few that
    may be the final one."""
    if FINAL_MARK not in data:
        return None
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.serialization import deserialize_message

    return final_status(deserialize_message(data, DiagnosticArray))
