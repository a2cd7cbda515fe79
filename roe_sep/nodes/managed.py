"""Managed (lifecycle) nodes: the planning nodes (planner, radar_od, ic_planner, safety_monitor) go through
unconfigured -> configure -> inactive -> activate -> active, the ROS 2 managed-node state machine.

* ``configure()`` (a subclass's): declares and checks the parameters and does the start-up work (the planner's
  Monte Carlo). A bad parameter fails the ``configure`` transition with the parameter's name in the message (logged,
  and the node stays unconfigured); nothing is published or subscribed yet.
* ``activate()`` (a subclass's): creates the node's publishers, subscriptions, services and timers (its lockstep
  participant), and publishes its first status. ``deactivate`` destroys exactly what ``activate`` created (the
  node's state is kept: a re-activated node goes on); ``cleanup`` forgets the configured state.

Parameter ``autostart`` (in each managed node's table, :mod:`.parameters`): the node configures and activates itself
in its constructor, so that ``PlannerNode()`` is fully active right after construction, as before these were managed
nodes (``roe-sep run``, ``ros2 run roe_sep planner``, a test or a composed process adding the node to an executor);
a parameter error then raises :class:`~.params.ParameterError` from the constructor (``main`` exits with status 2).
``autostart:=false`` leaves the node unconfigured for a lifecycle manager (:mod:`.lifecycle_manager`, ``ros2
lifecycle set``).

A change-state request whose transition is not valid from the node's current state (``configure`` of an active
node, a raw ChangeState call with any transition id) is refused: a failed response (``success=false``) and a WARN
naming the state and the transition (:func:`roe_sep.core.lifecycle.refusal`); the node goes on as it was. rclpy alone
raises ``RCLError`` inside the service callback, which ends the node's process.
"""

from rclpy.lifecycle import Node as LifecycleNode
from rclpy.lifecycle import TransitionCallbackReturn

from ..core.lifecycle import refusal
from .params import ParameterError, declare


class ManagedNode(LifecycleNode):
    """Base of the managed nodes; subclasses implement ``configure()`` and ``activate()``."""

    def __init__(self, node_name, **kwargs):
        super().__init__(node_name, **kwargs)
        self._change_state = self._service_change_state.callback  # rclpy's, called for a valid request only
        self._service_change_state.callback = self._on_change_state_request
        self.transition_error = None  # why the last transition failed (an exception), None if it did not
        self._quiet = False  # no log of a failed transition (autostart: the constructor raises it)
        self._activated = []  # (destroy function, entity) created by activate()
        self.autostart = declare(self, "autostart")
        if self.autostart:
            self._quiet = True  # a failure raises from the constructor: its one report is the caller's (spin.serve)
            try:
                for trigger in (self.trigger_configure, self.trigger_activate):
                    if trigger() != TransitionCallbackReturn.SUCCESS:
                        raise self.transition_error or RuntimeError(f"{node_name}: {trigger.__name__} failed")
            finally:
                self._quiet = False

    # ---------------------------------------------------------------- subclass hooks
    def configure(self):
        """Declare and check the parameters, do the start-up work."""

    def activate(self):
        """Create the publishers, subscriptions, services and timers; start working."""

    # ---------------------------------------------------------------- transitions
    def _on_change_state_request(self, request, response):
        """The ChangeState service: rclpy's for a transition valid from the current state, else a refusal."""
        _, state = self._state_machine.current_state
        available = [(t[0], t[1]) for t in self._state_machine.available_transitions]
        names = {t[0]: t[1] for t in self._state_machine.transition_graph}
        why = refusal(state, (request.transition.id, request.transition.label), available, names=names)
        if why is None:
            return self._change_state(request, response)
        self.get_logger().warning(why)
        response.success = False
        return response

    def _entities(self):
        return [(self.destroy_publisher, e) for e in self.publishers] + \
            [(self.destroy_subscription, e) for e in self.subscriptions] + \
            [(self.destroy_service, e) for e in self.services] + \
            [(self.destroy_client, e) for e in self.clients] + \
            [(self.destroy_timer, e) for e in self.timers]

    def _transition(self, what, hook):
        self.transition_error = None
        try:
            hook()
        except Exception as exc:  # noqa: BLE001 -- the lifecycle reports it; autostart re-raises it
            self.transition_error = exc
            if not self._quiet:
                why = exc if isinstance(exc, ParameterError) else f"{type(exc).__name__}: {exc}"
                self.get_logger().error(f"{what} failed: {why}")
            return TransitionCallbackReturn.FAILURE
        return TransitionCallbackReturn.SUCCESS

    def on_configure(self, state):
        return self._transition("configure", self.configure)

    def on_activate(self, state):
        before = {id(e) for _, e in self._entities()}

        def hook():
            try:
                self.activate()
            finally:
                self._activated = [(d, e) for d, e in self._entities() if id(e) not in before]
        result = self._transition("activate", hook)
        if result != TransitionCallbackReturn.SUCCESS:
            self._destroy_activated()
            return result
        return super().on_activate(state)

    def on_deactivate(self, state):
        self._destroy_activated()
        return super().on_deactivate(state)

    def on_cleanup(self, state):
        self._destroy_activated()
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state):
        self._destroy_activated()
        return TransitionCallbackReturn.SUCCESS

    def activated_later(self, create):
        """Run ``create`` after ``activate`` (e.g. once a read-back is over) and count what it creates as activated:
        ``deactivate`` destroys it too."""
        before = {id(e) for _, e in self._entities()}
        create()
        self._activated += [(d, e) for d, e in self._entities() if id(e) not in before]

    def _destroy_activated(self):
        for destroy, entity in reversed(self._activated):
            destroy(entity)
        self._activated = []
