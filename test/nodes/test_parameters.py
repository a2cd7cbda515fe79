"""Node parameters: one table per executable (:mod:`roe_sep.nodes.parameters`) is the only source of the declared
parameters, their descriptors, the start-up checks, ``--help`` and docs/parameters.md; rclpy refuses a run-time set
outside the table; a bad parameter ends a node in one line on stderr with exit status 2."""

import ast
import math
import subprocess
import sys
import time

import pytest
from rcl_interfaces.msg import ParameterType  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.parameter_client import AsyncParameterClient  # noqa: E402
from rosutil import ROOT, init, rclpy, ros_env, start_node, stop_node  # noqa: I001  (skips without rclpy)

from roe_sep.nodes import parameters  # noqa: E402
from roe_sep.nodes.params import ParameterError, declare, descriptor  # noqa: E402
from roe_sep.nodes.suite import NODE_CLASSES  # noqa: E402

CLASSES = dict(NODE_CLASSES, lifecycle_manager="lifecycle_manager:LifecycleManager")
ONE_LINE_TIMEOUT = 120  # s: a refusal takes a few seconds (imports); generous for a loaded machine


def node_class(name):
    import importlib

    module, cls = CLASSES[name].split(":")
    return getattr(importlib.import_module(f"roe_sep.nodes.{module}"), cls)


def entry_points():
    """{console script: 'module:function'} of setup.py."""
    tree = ast.parse((ROOT / "setup.py").read_text())
    scripts = next(ast.literal_eval(n.value) for n in ast.walk(tree)
                   if isinstance(n, ast.keyword) and n.arg == "entry_points")["console_scripts"]
    return dict(s.replace(" ", "").split("=") for s in scripts)


# ------------------------------------------------------------------------------------------------ the table itself
def test_docs_are_generated_from_the_tables():
    """docs/parameters.md is the generator's output (regenerate: python -m roe_sep.nodes.parameters --markdown)."""
    assert (ROOT / "docs" / "parameters.md").read_text() == parameters.markdown()


def test_every_default_keeps_its_own_rule():
    assert set(parameters.TABLES) == set(CLASSES) == set(parameters.CLASSES.values())
    for node, table in parameters.TABLES.items():
        assert len({p.name for p in table}) == len(table), node
        for p in table:
            assert p.type in parameters.TYPES and p.description, (node, p.name)
            assert parameters.problem(p, p.default) is None, (node, p.name, p.default)
            assert p.range is None or p.type in ("int", "double", "double[]"), (node, p.name)


@pytest.mark.parametrize("node,name,value,rule", [
    ("planner", "k", 2, "an odd integer in [1, 99]"),
    ("planner", "mc_samples", 1_000_000_000, "an integer in [1, 2000000]"),
    ("planner", "p_mode", "guess", "one of 'monte_carlo', 'three_sigma', 'fixed'"),
    ("sim", "tick_period", -0.01, "a number in [0.0001, 10] s"),
    ("sim", "tick_period", math.nan, "a number in [0.0001, 10] s"),
    ("sim", "duration", 600, "a number in [1, 1e9] s, written with a decimal point (600.0, not 600)"),
    ("sim", "wait_for", ["/sim/truth/roe"], "a list of 'topic=count' items"),
    ("sim", "epoch_utc", "yesterday", "an ISO-8601 UTC date-time"),
    ("radar_od", "stations", [], "a non-empty list of distinct station names"),
    ("radar_od", "stations", ["TIRA", "TIRA"], "a non-empty list of distinct station names"),
    ("radar_od", "station_altitudes_m", [1e5], "a non-empty list of numbers, each in [-500, 9000] m"),
    ("recorder", "topics", [1, 2], "a list of topic names"),
    ("safety_monitor", "period", -600.0, "a number in [1, 86400] s"),
    ("ic_planner", "axes", "TX", "distinct letters among R, T, N"),
])
def test_problem_names_the_rule(node, name, value, rule):
    why = parameters.problem(parameters.table(node)[name], value)
    assert why.startswith("must be ") and rule in why, why


def test_parameter_files_are_checked_against_the_tables():
    check = parameters.check_overrides
    check({"/**": {"use_sim_time": True, "scenario_file": ""}, "sim": {"wait_for": ["/a=1", ""], "seed": 3},
           "planner": {"k": 5, "qos_overrides./x.publisher.depth": 3}})  # good: no exception
    for overrides, text in [
        ({"sim": {"tick_period": -0.01}}, "F: sim.tick_period = -0.01: must be a number in [0.0001, 10] s"),
        ({"planner": {"k": 2}}, "F: planner.k = 2: must be an odd integer in [1, 99]"),
        ({"safety_monitor": {"period": -600}}, "F: safety_monitor.period = -600: must be a number in [1, 86400] s"),
        ({"safety_monitor": {"perod": 600.0}}, "F: safety_monitor.perod: no such parameter"),
        ({"/**": {"seed": -1}}, "F: /**.seed = -1: must be an integer in [0, 4294967295]"),
        ({"nobody": {"x": 1}}, "F: unknown node 'nobody'"),
    ]:
        with pytest.raises(ValueError) as exc:
            check(overrides, "F")
        assert str(exc.value).startswith(text), str(exc.value)
        assert "\n" not in str(exc.value)


# ------------------------------------------------------------------------------------------------ declared = table
@pytest.fixture
def context(tmp_path, monkeypatch, ros_context):
    monkeypatch.chdir(tmp_path)
    init("-p", "mc_samples:=100", "-p", "port:=0", "-p", f"output:={tmp_path / 'bag'}")
    yield tmp_path


@pytest.mark.dds
def test_declared_parameters_and_descriptors_are_the_tables(context):
    """Every node declares exactly its table's parameters (besides rclpy's own), with the table's default and the
    descriptor made from it (type, description, rule, range, read_only)."""
    given = {"mc_samples": 100, "port": 0, "output": str(context / "bag")}
    for name in CLASSES:
        node = node_class(name)()
        try:
            declared = {n for n in node._parameters if n not in parameters.ROS_PARAMETERS}
            assert declared == {p.name for p in parameters.TABLES[name]}, name
            for p in parameters.TABLES[name]:
                value = node.get_parameter(p.name).value
                want = given.get(p.name, p.default)
                assert (list(value) if isinstance(want, list) else value) == want, (name, p.name)
                d, w = node.describe_parameter(p.name), descriptor(p)
                assert (d.type, d.description, d.additional_constraints, d.read_only) == \
                    (w.type, w.description, w.additional_constraints, w.read_only), (name, p.name)
                assert list(d.floating_point_range) == list(w.floating_point_range), (name, p.name)
                assert list(d.integer_range) == list(w.integer_range), (name, p.name)
        finally:
            node.destroy_node()
    # the ground_bridge without output_dir: a dated directory in the working directory, as the recorder's bag
    assert len(list(context.glob("ccsds_*"))) == 1


@pytest.mark.dds
def test_settable_parameter_follows_and_keeps_its_rule(context):
    from roe_sep.nodes.analysis_server import AnalysisServer

    node = AnalysisServer()
    try:
        assert node.set_parameters([Parameter("deploy_step", value=1200.0)])[0].successful
        assert node.step == 1200.0  # the next request uses it
        for bad in (Parameter("deploy_step", value=0.5), Parameter("deploy_model", value="gmat"),
                    Parameter("deploy_step", value=600), Parameter("cluster_file", value="x.yaml")):
            result = node.set_parameters([bad])[0]
            assert not result.successful, bad.name
        assert node.step == 1200.0 and node.model == "nonlinear"
        assert "must be one of 'nonlinear', 'linear'" in node.set_parameters(
            [Parameter("deploy_model", value="gmat")])[0].reason
    finally:
        node.destroy_node()


@pytest.mark.dds
def test_a_type_mismatch_is_refused_in_one_message(context):
    init("-p", "topics:=[1,2]", "-p", "exclude:=[]")
    from roe_sep.nodes.recorder import RecorderNode

    with pytest.raises(ParameterError, match=r"^parameter 'topics' must be a list of topic names, got \[1, 2\]$"):
        RecorderNode()


@pytest.mark.dds
def test_declare_refuses_a_parameter_of_no_table(context):
    node = rclpy.create_node("stranger")
    try:
        with pytest.raises(KeyError):
            declare(node, "k")
    finally:
        node.destroy_node()


# ------------------------------------------------------------------------------------------------ executables
def console_script(name, *args, timeout=ONE_LINE_TIMEOUT):
    """Run a console script of setup.py as pip's wrapper does (``sys.argv[0]`` its name), with this tree."""
    module, func = entry_points()[name].split(":")
    code = f"import sys; sys.argv[0] = {name!r}; from {module} import {func}; sys.exit({func}())"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=timeout,
                          env=ros_env(), cwd=ROOT)


@pytest.mark.parametrize("script", sorted(entry_points()))
def test_every_executable_answers_help(script):
    """``--help`` and ``-h``: the usage and the parameter table, exit 0, without starting a node (the planner would
    run its 100,000-sample sweep first and never return)."""
    for flag in ("--help", "-h"):
        proc = console_script(script, flag)
        assert proc.returncode == 0, (flag, proc.stderr)
        assert "usage:" in proc.stdout, proc.stdout
        for p in parameters.TABLES.get(script, ()):
            assert f"  {p.name} ({p.type}, default" in proc.stdout and parameters.rule_text(p) in proc.stdout
        assert "Traceback" not in proc.stderr


@pytest.mark.dds  # the node's rclpy.init refuses the parameter (or the --params-file)
@pytest.mark.parametrize("script,args,needles", [
    ("planner", ["-p", "mc_samples:=1000000000"], ["planner", "'mc_samples'", "an integer in [1, 2000000]"]),
    ("radar_od", ["-p", "stations:=[]"], ["radar_od", "'stations'", "a non-empty list of distinct station names"]),
    ("radar", ["-p", "seed:=abc"], ["radar", "'seed'", "an integer in [0, 4294967295]", "'abc'"]),
    ("radar", ["-p", "station_latitudes_deg:=[1.0,2.0]"], ["radar", "'station_latitudes_deg'",
                                                           "one per station of 'stations'"]),
    ("recorder", ["-p", "topics:=[1,2]"], ["recorder", "'topics'", "a list of topic names", "[1, 2]"]),
    ("sim", ["-p", "duration:=600"], ["sim", "'duration'", "(600.0, not 600)"]),
    ("safety_monitor", ["--params-file", "{missing}"], ["safety_monitor", "--params-file", "{missing}",
                                                         "no such file"]),
    ("ic_planner", ["--params-file", "{malformed}"], ["ic_planner", "{malformed}", "Couldn't parse params file"]),
])
def test_bad_parameter_ends_in_one_line(script, args, needles, tmp_path):
    files = {"{missing}": str(tmp_path / "missing.yaml"), "{malformed}": str(tmp_path / "bad.yaml")}
    (tmp_path / "bad.yaml").write_text("ic_planner: {ros__parameters: {window: [unclosed\n")
    args = [files.get(a, a) for a in args]
    proc = console_script(script, "--ros-args", *args)
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr and "array(" not in lines[0]
    for needle in needles:
        assert files.get(needle, needle) in lines[0], lines[0]


# ------------------------------------------------------------------------------------------------ at run time
def _wait(node, call, timeout=30.0):
    """The answer to ``call()`` (a parameter client request), sent once more when the first gets none within half
    of ``timeout``: Fast DDS drops a service's response when the client's response reader is not yet matched, and
    ``services_are_ready`` sees only the request side (ros2/rmw_fastrtps#390; one full test run lost one)."""
    for wait in (timeout / 2, timeout / 2):
        future = call()
        deadline = time.monotonic() + wait
        while not future.done() and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.1)
        if future.done():
            return future.result()
    raise AssertionError("no answer from the parameter services")


@pytest.mark.dds
def test_running_node_refuses_a_set_outside_the_table(tmp_path, ros_context):
    """``ros2 param set`` is a SetParameters call: rclpy refuses a value outside the range, a read-only parameter,
    a wrong type; the table's other rules (choices) by the node's callback. ``ros2 param get /recorder topics``
    answers [] (its default is set, not only its type)."""
    procs = {"analysis_server": start_node("analysis_server"),
             "recorder": start_node("recorder", "-p", f"output:={tmp_path / 'bag'}",
                                    "-p", "flush_period:=0.5", "-p", "exclude:=['/rosout']",
                                    "-r", "__node:=recorder_params_test")}
    node = rclpy.create_node("param_tester")
    try:
        server = AsyncParameterClient(node, "analysis_server")
        recorder = AsyncParameterClient(node, "recorder_params_test")
        deadline = time.monotonic() + 60
        while not (server.services_are_ready() and recorder.services_are_ready()) and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.2)
        assert server.services_are_ready() and recorder.services_are_ready()

        def set_(client, name, value):
            return _wait(node, lambda: client.set_parameters([Parameter(name, value=value)])).results[0]

        below = set_(server, "deploy_step", 0.5)
        assert not below.successful and "out of range" in below.reason.lower()
        nan = set_(server, "deploy_density", math.nan)
        assert not nan.successful
        choice = set_(server, "deploy_model", "gmat")
        assert not choice.successful and "must be one of 'nonlinear', 'linear'" in choice.reason
        read_only = set_(server, "cluster_file", "/tmp/x.yaml")
        assert not read_only.successful and "read-only" in read_only.reason
        wrong_type = set_(server, "deploy_step", 600)
        assert not wrong_type.successful
        assert set_(server, "deploy_step", 1200.0).successful
        values = _wait(node, lambda: server.get_parameters(["deploy_step", "deploy_model"])).values
        assert values[0].double_value == 1200.0 and values[1].string_value == "nonlinear"
        described = _wait(node, lambda: server.describe_parameters(["deploy_step"])).descriptors[0]
        assert described.floating_point_range[0].from_value == 1.0 and not described.read_only

        got = _wait(node, lambda: recorder.get_parameters(["topics", "exclude", "flush_period"])).values
        assert got[0].type == ParameterType.PARAMETER_STRING_ARRAY and list(got[0].string_array_value) == []
        assert list(got[1].string_array_value) == ["/rosout"] and got[2].double_value == 0.5
        assert not set_(recorder, "flush_period", 2.0).successful  # read-only: its timer is made at start-up
    finally:
        node.destroy_node()
        codes = {name: stop_node(p) for name, p in procs.items()}
    assert all(code == 0 for code, _ in codes.values()), codes
