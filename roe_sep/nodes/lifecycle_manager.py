"""lifecycle_manager: ordered start-up of managed nodes, the way nav2's lifecycle manager does it.

For every node of ``node_names``: ``configure`` for each, in order, then ``activate`` for each, in order. Before
each step it reads the node's state (``/<node>/get_state``) and decides (:func:`roe_sep.core.lifecycle.
startup_action`): a node still in the step's start state gets the transition (``/<node>/change_state``,
lifecycle_msgs/srv/ChangeState); a node past it (already configured, or active: one that started itself with
``autostart``) is adopted as it is; a node in any other state (finalized, unknown) fails the start-up. A transition
that fails stops the start-up: the manager logs which node and transition failed (the node's own log says why, e.g.
the parameter error of its ``configure``), publishes an ERROR on ``/diagnostics`` and exits with status 1. When
every node is active it publishes OK "managed nodes active" and keeps running (so that a launch does not see it
exit); on SIGINT/SIGTERM it exits 0, whatever state it found, and leaves the nodes as they are.

The start-up never blocks the executor: it is a generator (:meth:`LifecycleManager.startup`) resumed by a timer on
the steady clock every :data:`TICK` s, which yields while it waits for a service, a response or the request
writer's match, so that the manager answers its own services meanwhile (``ros2 param list /lifecycle_manager``
while it waits for its nodes) and a signal ends it at once. Steady time, not the node's clock: under
``use_sim_time`` the clock only starts once the managed nodes are up.

Parameters: :data:`roe_sep.nodes.parameters.LIFECYCLE_MANAGER` (``lifecycle_manager --help``, docs/parameters.md):
``node_names`` (the managed nodes of :data:`roe_sep.graph.MANAGED`) and ``timeout``, how long to wait for each
node's service, and for each transition (a call without an answer is made again, up to 3 times, unless the node's
state shows it was done).
"""


import time

from diagnostic_msgs.msg import DiagnosticArray
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from rclpy.clock import Clock, ClockType
from rclpy.node import Node

from .. import interfaces
from ..core.lifecycle import GOAL, startup_action
from .diagnostics import ERROR, OK, publish_status
from .params import declare

ATTEMPTS = 3  # calls of a transition that got no answer
MATCH_DELAY = 0.5  # s
TICK = 0.05  # s (steady time) between two steps of the start-up
STEPS = (("configure", Transition.TRANSITION_CONFIGURE), ("activate", Transition.TRANSITION_ACTIVATE))


class LifecycleManager(Node):
    def __init__(self):
        super().__init__("lifecycle_manager")
        self.node_names = declare(self, "node_names")
        self.timeout = declare(self, "timeout")
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        self.outcome = None  # (ok, message) once the start-up has ended
        self._startup = self.startup()
        self._timer = self.create_timer(TICK, self._tick, clock=Clock(clock_type=ClockType.STEADY_TIME))

    @property
    def failed(self) -> bool:
        return self.outcome is not None and not self.outcome[0]

    def _tick(self):
        """Resume the start-up until its next wait; at its end, say how it went (log and ``/diagnostics``)."""
        try:
            next(self._startup)
        except StopIteration as end:
            self._timer.cancel()
            self.outcome = ok, message = end.value
            (self.get_logger().info if ok else self.get_logger().error)(message)
            publish_status(self, self.diag_pub, OK if ok else ERROR, message, {"nodes": len(self.node_names)})

    def _call(self, srv_type, service, request):
        """Generator: the service's response, or None and why (no service, no answer within ``timeout``); yields
        while it waits."""
        client = self.create_client(srv_type, service)
        try:
            deadline = time.monotonic() + self.timeout
            while not client.service_is_ready():
                if time.monotonic() > deadline:
                    return None, f"service {service} not available within {self.timeout:g} s"
                yield
            # the server is discovered; give it a moment to match this client's request writer too (a request sent
            # before that is lost)
            ready = time.monotonic()
            while time.monotonic() - ready < MATCH_DELAY:
                yield
            future = client.call_async(request)
            deadline = time.monotonic() + self.timeout
            while not future.done():
                if time.monotonic() > deadline:
                    client.remove_pending_request(future)
                    return None, f"{service} did not answer within {self.timeout:g} s"
                yield
            return future.result(), None
        finally:
            self.destroy_client(client)

    def state(self, name):
        """Generator: the node's lifecycle state label ('unconfigured', 'inactive', 'active', ...), None if
        unknown."""
        result, _ = yield from self._call(GetState, f"/{name}/get_state", GetState.Request())
        return None if result is None else result.current_state.label

    def startup(self):
        """Generator: configure, then activate, every node in order, adopting those already past a step; returns
        (ok, message)."""
        for label, transition in STEPS:
            for name in self.node_names:
                state = None
                for _ in range(ATTEMPTS):  # a lost request or response: ask again
                    state = yield from self.state(name)
                    if state is not None:
                        break
                action = startup_action(label, state)
                if action == "adopt":
                    self.get_logger().info(f"/{name}: {label} already done (state {state!r}), adopted")
                    continue
                if action == "fail":
                    why = "no answer from its get_state" if state is None else f"state {state!r}"
                    return False, f"{label} of /{name} impossible: {why}"
                problem = yield from self._transition(name, label, transition)
                if problem is not None:
                    return False, problem
                self.get_logger().info(f"/{name}: {label} ok")
        return True, f"managed nodes active: {', '.join(self.node_names)}"

    def _transition(self, name, label, transition):
        """Generator: None once the transition is done, else why it failed."""
        for _ in range(ATTEMPTS):
            request = ChangeState.Request()
            request.transition.id = transition
            result, problem = yield from self._call(ChangeState, f"/{name}/change_state", request)
            if problem is None:
                break
            # no answer: a lost request or a lost response; the node's state tells which
            if (yield from self.state(name)) == GOAL[label]:
                return None
            self.get_logger().warning(f"{problem}; asking again")
        if problem is None and not result.success:
            problem = (f"{label} of /{name} failed (state now {(yield from self.state(name))!r}; the node's "
                       f"log says why, e.g. a parameter error)")
        return problem

    def destroy_node(self):
        self._startup.close()  # a start-up still waiting destroys its client now, while the node exists
        return super().destroy_node()


def main(args=None):
    """Exit 1 when a transition failed; 0 on SIGINT/SIGTERM (whether the start-up had ended or not); ``-h``/``--help``
    prints the usage and the parameter table."""
    from .params import help_requested, print_usage
    from .spin import leave, serve

    if help_requested(args):
        return print_usage("lifecycle_manager", __doc__)
    managers = []

    def manager():
        managers.append(LifecycleManager())
        return managers[-1]

    code = serve([("lifecycle_manager", manager)], args, until=lambda: managers[0].failed, leaving=True)
    return leave(code or (1 if managers and managers[0].failed else 0))


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
