"""The decisions of the ROS 2 managed-node state machine that a bad request from outside must not break (pure).

A managed node's primary states are ``unconfigured``, ``inactive``, ``active`` and ``finalized``; the transitions
``configure`` (unconfigured -> inactive), ``activate`` (inactive -> active), ``deactivate``, ``cleanup`` and
``shutdown`` are each valid from some states only (ROS 2 design article "Managed nodes",
https://design.ros2.org/articles/node_lifecycle.html). The state machine itself (rcl_lifecycle) says which
transitions leave the current state; these functions decide what to do with a request or a state read, so that the
node and the lifecycle manager only ask and act.
"""

from collections.abc import Iterable, Mapping

#: the state each start-up step of a lifecycle manager leaves a node in
GOAL = {"configure": "inactive", "activate": "active"}
#: the primary states from which each start-up step has already been done (the node is adopted as it is)
DONE = {"configure": ("inactive", "active"), "activate": ("active",)}
#: the primary state each start-up step starts from
START = {"configure": "unconfigured", "activate": "inactive"}


def refusal(state: str, request: tuple[int, str], available: Iterable[tuple[int, str]], *,
            names: Mapping[int, str] | None = None) -> str | None:
    """Why a change-state request is refused (None: it is valid from ``state``).

    Parameters
    ----------
    state : str
        The node's current state label.
    request : tuple of (int, str)
        The (id, label) of the requested transition as the ChangeState service received it: a non-empty label names
        the transition (the id is then ignored, as rclpy does), else the id does.
    available : iterable of (int, str)
        The (id, label) of every transition that leaves ``state``.
    names : mapping of int to str, optional
        The labels of transition ids (all of the state machine's), to name a requested id in the reason.

    Returns
    -------
    str or None
        The reason, naming the state, the transition and the valid ones; None for a valid request.
    """
    transition_id, label = request
    available = list(available)
    if label:
        valid, asked = label in {lb for _, lb in available}, repr(label)
    else:
        name = (names or {}).get(transition_id)
        asked = f"{name!r} [{transition_id}]" if name else f"id {transition_id}"
        valid = transition_id in {i for i, _ in available}
    if valid:
        return None
    choices = ", ".join(f"{lb} [{i}]" for i, lb in available) or "none"
    return f"transition {asked} refused: not valid from state {state!r} (valid: {choices})"


def startup_action(step: str, state: str | None) -> str:
    """What a lifecycle manager does with a node in ``state`` at start-up step ``step`` ('configure', 'activate').

    Returns ``'call'`` (the node is in the step's start state: request the transition), ``'adopt'`` (the step is
    already done: leave the node as it is, e.g. a node that started itself with ``autostart``) or ``'fail'`` (a
    state from which the step cannot be reached: finalized, a transition state, or unknown, None).
    """
    if step not in START:
        raise ValueError(f"unknown start-up step {step!r} (known: {', '.join(START)})")
    if state == START[step]:
        return "call"
    if state in DONE[step]:
        return "adopt"
    return "fail"
