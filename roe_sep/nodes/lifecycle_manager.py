"""lifecycle_manager: ordered start-up of managed nodes, the way nav2's lifecycle manager does it.

Calls ``/<node>/change_state`` (lifecycle_msgs/srv/ChangeState) for every node of ``node_names``: ``configure``
for each, in order, then ``activate`` for each, in order. A transition that fails stops the start-up: the manager
logs which node and transition failed (the node's own log says why, e.g. the parameter error of its
``configure``), publishes an ERROR on ``/diagnostics`` and exits with status 1. When every node is active it
publishes OK "managed nodes active" and keeps running (so that a launch does not see it exit); on SIGINT it leaves
the nodes as they are.

Parameters: :data:`roe_sep.nodes.parameters.LIFECYCLE_MANAGER` (``lifecycle_manager --help``, docs/parameters.md):
``node_names`` (the managed nodes of :data:`roe_sep.graph.MANAGED`) and ``timeout``, how long to wait for each
node's service, and for each transition (a call without an answer is made again, up to 3 times, unless the node's
state shows it was done).
"""


import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from rclpy.node import Node

from .. import interfaces
from .diagnostics import ERROR, OK, publish_status
from .params import declare

GOAL = {"configure": "inactive", "activate": "active"}
ATTEMPTS = 3  # calls of a transition that got no answer
MATCH_DELAY = 0.5  # s
STEPS = (("configure", Transition.TRANSITION_CONFIGURE), ("activate", Transition.TRANSITION_ACTIVATE))


class LifecycleManager(Node):
    def __init__(self):
        super().__init__("lifecycle_manager")
        self.node_names = declare(self, "node_names")
        self.timeout = declare(self, "timeout")
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)

    def _call(self, client, request):
        if not client.wait_for_service(timeout_sec=self.timeout):
            return None, f"service {client.srv_name} not available within {self.timeout:g} s"
        # the server is discovered; give it a moment to match this client's request writer too (a request sent
        # before that is lost)
        rclpy.spin_once(self, timeout_sec=MATCH_DELAY)
        future = client.call_async(request)
        rclpy.spin_until_future_complete(self, future, timeout_sec=self.timeout)
        if not future.done():
            return None, f"{client.srv_name} did not answer within {self.timeout:g} s"
        return future.result(), None

    def state(self, name):
        """The node's lifecycle state label ('unconfigured', 'inactive', 'active', ...), None if unknown."""
        result, _ = self._call(self.create_client(GetState, f"/{name}/get_state"), GetState.Request())
        return None if result is None else result.current_state.label

    def startup(self):
        """Configure, then activate, every node in order; returns (ok, message)."""
        for label, transition in STEPS:
            for name in self.node_names:
                for _ in range(ATTEMPTS):
                    client = self.create_client(ChangeState, f"/{name}/change_state")
                    request = ChangeState.Request()
                    request.transition.id = transition
                    result, problem = self._call(client, request)
                    self.destroy_client(client)
                    if problem is None:
                        break
                    # no answer: a lost request or a lost response; the node's state tells which
                    if self.state(name) == GOAL[label]:
                        problem, result = None, ChangeState.Response(success=True)
                        break
                    self.get_logger().warning(f"{problem}; asking again")
                if problem is None and not result.success:
                    problem = (f"{label} of /{name} failed (state now {self.state(name)!r}; the node's log says "
                               f"why, e.g. a parameter error)")
                if problem is not None:
                    return False, problem
                self.get_logger().info(f"/{name}: {label} ok")
        return True, f"managed nodes active: {', '.join(self.node_names)}"


def start(nodes) -> int:
    """Bring the managed nodes up (:meth:`LifecycleManager.startup`), say how it went on the log and
    ``/diagnostics``; exit code 1 if a transition failed, else 0 (the manager keeps running)."""
    node = nodes[0]
    ok, message = node.startup()
    (node.get_logger().info if ok else node.get_logger().error)(message)
    publish_status(node, node.diag_pub, OK if ok else ERROR, message, {"nodes": len(node.node_names)})
    return 0 if ok else 1


def main(args=None):
    from .params import help_requested, print_usage
    from .spin import serve

    if help_requested(args):
        return print_usage("lifecycle_manager", __doc__)
    return serve([("lifecycle_manager", LifecycleManager)], args, start=start)


if __name__ == "__main__":
    raise SystemExit(main())
