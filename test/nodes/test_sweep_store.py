"""The planner's start-up sweep stored on disk (p_best_stored): the same float as p_best, keyed by its inputs."""

import dataclasses
import json

from roe_sep.core.config import load_scenario
from roe_sep.core.montecarlo.sweep import p_best
from roe_sep.nodes.sweep_store import p_best_stored


def inputs(samples=2000, seed=3):
    scenario = load_scenario(None)
    mc = dataclasses.replace(scenario.monte_carlo, samples=samples, seed=seed)
    return scenario.separation, mc, tuple(scenario.p_values)


def test_stored_value_is_p_best_and_read_back(tmp_path):
    p_best_stored.cache_clear()
    sep, mc, ps = inputs()
    first = p_best_stored(sep, mc, ps, str(tmp_path))
    assert first == p_best(sep, mc, ps)
    files = list(tmp_path.glob("p_best_*.json"))
    assert len(files) == 1
    stored = json.loads(files[0].read_text())
    assert stored["p_best"] == first
    # a fresh process reads it: poison the file's value under its own key, and the read returns the stored value
    stored["p_best"] = 123.0
    files[0].write_text(json.dumps(stored))
    p_best_stored.cache_clear()
    assert p_best_stored(sep, mc, ps, str(tmp_path)) == 123.0


def test_other_inputs_other_key_and_damaged_file_recomputed(tmp_path):
    p_best_stored.cache_clear()
    sep, mc, ps = inputs()
    p_best_stored(sep, mc, ps, str(tmp_path))
    (first,) = tmp_path.glob("p_best_*.json")  # the file of (sep, mc, ps): its name is a digest, in no set order
    sep2, mc2, _ = inputs(seed=4)
    p_best_stored(sep2, mc2, ps, str(tmp_path))
    files = sorted(tmp_path.glob("p_best_*.json"))
    assert len(files) == 2
    for f in files:
        f.write_text("{not json")
    p_best_stored.cache_clear()
    assert p_best_stored(sep, mc, ps, str(tmp_path)) == p_best(sep, mc, ps)
    assert json.loads(first.read_text())["p_best"] is not None


def test_unwritable_directory_still_computes(tmp_path):
    p_best_stored.cache_clear()
    blocker = tmp_path / "file"
    blocker.write_text("")
    sep, mc, ps = inputs()
    assert p_best_stored(sep, mc, ps, str(blocker / "sub")) == p_best(sep, mc, ps)
