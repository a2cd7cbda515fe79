"""The managed-node decisions without DDS: which change-state requests are refused, and what a lifecycle manager
does with each state it reads at start-up (roe_sep.core.lifecycle)."""

import pytest

from roe_sep.core.lifecycle import GOAL, refusal, startup_action

# what rcl_lifecycle lists as leaving each primary state (id, label): ros2 lifecycle list NODE
FROM_ACTIVE = [(4, "deactivate"), (7, "shutdown")]
FROM_UNCONFIGURED = [(1, "configure"), (5, "shutdown")]
NAMES = {1: "configure", 2: "cleanup", 3: "activate", 4: "deactivate", 5: "shutdown", 6: "shutdown", 7: "shutdown"}


@pytest.mark.parametrize("request_", [(4, ""), (7, ""), (0, "deactivate"), (0, "shutdown"), (1, "deactivate")])
def test_a_transition_valid_from_the_state_is_not_refused(request_):
    # a label names the transition (the id is then ignored, as rclpy does)
    assert refusal("active", request_, FROM_ACTIVE, names=NAMES) is None


def test_configure_of_an_active_node_is_refused_naming_state_and_transition():
    why = refusal("active", (1, ""), FROM_ACTIVE, names=NAMES)
    assert why == "transition 'configure' [1] refused: not valid from state 'active' (valid: deactivate [4], " \
                  "shutdown [7])"
    assert "'configure' refused: not valid from state 'active'" in refusal("active", (0, "configure"), FROM_ACTIVE)


@pytest.mark.parametrize("request_", [(5, ""), (6, ""), (3, ""), (2, ""), (10, ""), (99, ""), (0, ""),
                                      (0, "activate"), (0, "no_such"), (4, "configure")])
def test_every_other_request_from_active_is_refused(request_):
    # shutdown by the id of another state's shutdown (5, 6) too: rcl would not find it registered from 'active'
    assert refusal("active", request_, FROM_ACTIVE, names=NAMES) is not None


def test_an_unknown_id_is_named_by_its_number():
    assert refusal("unconfigured", (42, ""), FROM_UNCONFIGURED).startswith("transition id 42 refused: not valid "
                                                                            "from state 'unconfigured'")
    assert refusal("unconfigured", (1, ""), FROM_UNCONFIGURED) is None
    assert refusal("finalized", (1, ""), []).endswith("(valid: none)")


@pytest.mark.parametrize(("step", "state", "action"), [
    ("configure", "unconfigured", "call"), ("configure", "inactive", "adopt"), ("configure", "active", "adopt"),
    ("configure", "finalized", "fail"), ("configure", "configuring", "fail"), ("configure", None, "fail"),
    ("activate", "inactive", "call"), ("activate", "active", "adopt"), ("activate", "unconfigured", "fail"),
    ("activate", "finalized", "fail"), ("activate", None, "fail")])
def test_the_manager_calls_adopts_or_fails_by_the_state_it_reads(step, state, action):
    assert startup_action(step, state) == action


def test_each_step_adopts_the_state_it_leads_to():
    assert all(startup_action(step, goal) == "adopt" for step, goal in GOAL.items())
    with pytest.raises(ValueError, match="unknown start-up step 'cleanup'"):
        startup_action("cleanup", "active")
