"""The nodes' decisions as pure functions (docs/run.md, "Decisions"): ``on_<event>(state, event, config) ->
(new_state, actions)`` over an explicit, immutable state that serializes to strict JSON (``to_dict`` /
``from_dict``), so that a node only converts its messages to events and carries out the actions. :mod:`.common`
holds the shared action types and the serialization, :mod:`.ic_planner` the acquisition's re-plan, trim and
deferral rules, :mod:`.planner` the drift-stop's hold, replacement and completion, :mod:`.cam` the first-orbit
collision-avoidance rule on the measured ejection (not wired to a node yet).
"""
