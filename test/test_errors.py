"""roe_sep.errors: one root for every exception roe_sep raises on purpose, and values in messages as plain Python."""

import ast
import builtins
import collections
import importlib
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from roe_sep import errors
from roe_sep.checks import check_number
from roe_sep.cli import main
from roe_sep.core.config import scenario_from_dict
from roe_sep.core.deployment.sweep import CubeSat, DeploymentConfig
from roe_sep.core.montecarlo.sweep import MonteCarloConfig
from roe_sep.core.separation.double_impulse import SeparationConfig, design
from roe_sep.validate import maneuver

ROOT = Path(__file__).resolve().parents[1] / "roe_sep"
EXCEPTIONS = {name for name in dir(builtins) if isinstance(getattr(builtins, name), type)
              and issubclass(getattr(builtins, name), BaseException)}


def exception_classes_outside_errors():
    """``module:Class`` of every class outside roe_sep/errors.py whose base is a builtin exception or is named like
    one (``...Error``, ``...Exception``)."""
    out = []
    for path in sorted(ROOT.rglob("*.py")):
        if path == ROOT / "errors.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef):
                bases = [b.attr if isinstance(b, ast.Attribute) else getattr(b, "id", "") for b in node.bases]
                if any(b in EXCEPTIONS or b.endswith(("Error", "Exception")) for b in bases):
                    out.append(f"{path.relative_to(ROOT.parent)}:{node.name}")
    return out


ERROR_CLASSES = sorted((v for v in vars(errors).values() if isinstance(v, type) and issubclass(v, BaseException)),
                       key=lambda cls: cls.__name__)


def test_every_exception_class_is_defined_in_errors():
    assert exception_classes_outside_errors() == []
    assert errors.RoeSepError in ERROR_CLASSES and errors.Interrupted in ERROR_CLASSES


@pytest.mark.parametrize("cls", ERROR_CLASSES, ids=[c.__name__ for c in ERROR_CLASSES])
def test_each_exception_class_is_under_the_root_documented_and_used(cls):
    """Defined in errors.py, a RoeSepError (the one other class, Interrupted, is a stop signal: a KeyboardInterrupt
    and no error), with a docstring of its own, named in docs/developers.md "Errors and stamps", and raised or caught
    somewhere else in roe_sep."""
    assert cls.__module__ == "roe_sep.errors"
    if cls is errors.Interrupted:
        assert issubclass(cls, KeyboardInterrupt) and not issubclass(cls, Exception)
    else:
        assert issubclass(cls, errors.RoeSepError) and issubclass(cls, ValueError)
    assert (vars(cls).get("__doc__") or "").strip(), f"{cls.__name__} has no docstring"
    guide = (ROOT.parent / "docs" / "developers.md").read_text(encoding="utf-8")
    section = guide.split("## Errors and stamps", 1)[1].split("\n## ", 1)[0]
    named = re.search(rf"`(roe_sep\.errors\.)?{cls.__name__}`", section)
    assert named, f"docs/developers.md 'Errors and stamps' does not name {cls.__name__}"
    users = [path for path in ROOT.rglob("*.py") if path != ROOT / "errors.py"
             and re.search(rf"\b{cls.__name__}\b", path.read_text(encoding="utf-8"))]
    assert users, f"{cls.__name__} is used nowhere in roe_sep"


def test_the_root_and_its_other_kinds():
    assert issubclass(errors.RoeSepError, ValueError) and issubclass(errors.DefinitionNotFound, LookupError)


@pytest.mark.parametrize("where, name", [
    ("roe_sep.core.config", "ConfigError"), ("roe_sep.nodes.params", "ParameterError"),
    ("roe_sep.bag", "BagError"), ("roe_sep.bag.definitions", "DefinitionNotFound"),
    ("roe_sep.ndm.messages", "NdmError"), ("roe_sep.validate", "BadMessage"), ("roe_sep.core.frames", "EopError"),
    ("roe_sep.core.separation.double_impulse", "InfeasibleDesignError"),
    ("roe_sep.core.acquisition.planner", "AcquisitionInfeasible"),
    ("roe_sep.core.acquisition.planner", "InvalidAcquisitionConfig"),
])
def test_the_modules_that_raise_them_re_export_the_same_class(where, name):
    if where == "roe_sep.nodes.params":
        pytest.importorskip("rclpy")
    assert getattr(importlib.import_module(where), name) is getattr(errors, name)


def test_show_writes_plain_python():
    point = collections.namedtuple("Point", "x y")
    assert errors.show(np.float64(0.0)) == "0.0" and errors.show(np.int64(3)) == "3"
    assert errors.show([np.float64(97.0), np.float64(0.0)]) == "[97.0, 0.0]"
    assert errors.show(np.array([[1.0, np.nan]])) == "[[1.0, nan]]" and errors.show(np.bool_(True)) == "True"
    assert errors.show((np.float32(1.5),)) == "(1.5,)" and errors.show({"a": np.int8(1)}) == "{'a': 1}"
    assert errors.show(point(np.float64(1.0), 2)) == "Point(x=1.0, y=2)"
    assert errors.show("abc") == "'abc'" and errors.show(None) == "None" and errors.show(b"x") == "b'x'"
    assert errors.show(CubeSat(cd=np.float64(2.0))) == "CubeSat(cd=2.0, area=0.06, mass=24.0)"


def _raise(exc):
    raise exc


def _nan_dv(dv):
    return SimpleNamespace(epoch=SimpleNamespace(sec=1, nanosec=0), dv_rtn=SimpleNamespace(x=dv[0], y=dv[1], z=dv[2]),
                           mean_arg_latitude=0.0, spacecraft="carrier")


# (what, call, the value as the message must show it): each call raises with a NumPy value in its message
NUMPY_MESSAGES = [
    # the deployment service (analysis_server answers str(exc) of this check)
    ("deployment inclination", lambda: DeploymentConfig(inclinations_deg=(0.0,)).validate(), "got [0.0]"),
    ("deployment dv array", lambda: DeploymentConfig(dv=np.array([np.nan])).validate(), "got [nan]"),
    ("deployment cubesat", lambda: DeploymentConfig(cubesat=CubeSat(cd=np.float64(-1.0))).validate(), "cd=-1.0"),
    ("check_number", lambda: check_number("--spl-dv", np.float64(np.nan), 0.0, 10.0), "got nan"),
    ("config spl_dv", lambda: scenario_from_dict({"separation": {"spl_dv": np.float64(np.nan)}}), "got nan"),
    ("config p_values", lambda: scenario_from_dict({"monte_carlo": {"p_values": np.array([0.05])}}), "got [0.05]"),
    ("design k", lambda: design(SeparationConfig(k=np.int64(2))), "got 2"),
    ("design leading", lambda: design(SeparationConfig(leading=np.float64(2.0))), "got 2.0"),
    ("monte carlo samples", lambda: MonteCarloConfig(samples=np.int64(0)).validate(), "got 0"),
    ("message dv", lambda: maneuver("m", _nan_dv(np.array([np.nan, 0.0, 0.0]))), "m.dv_rtn = (nan, 0.0, 0.0)"),
    ("acquisition config", lambda: _raise(errors.InvalidAcquisitionConfig("x", "positive", np.float64(-1.0))),
     "got -1.0"),
]


@pytest.mark.parametrize("what, call, shown", NUMPY_MESSAGES, ids=[c[0] for c in NUMPY_MESSAGES])
def test_messages_show_no_numpy_repr(what, call, shown):
    with pytest.raises(ValueError) as info:
        call()
    message = str(info.value)
    assert "np." not in message and "array(" not in message and shown in message, message


def test_the_command_line_catches_the_root(monkeypatch, capsys):
    """Any RoeSepError, also one that is no other ValueError's kind (DefinitionNotFound is a LookupError), is bad
    input: one line, exit 2."""
    import roe_sep.cli.run as cli_run

    def refuse(argv):
        raise errors.DefinitionNotFound("package 'foo_msgs' not found in []")

    monkeypatch.setattr(cli_run, "delegated", refuse)
    assert main(["design"]) == 2
    assert capsys.readouterr().err == "roe-sep: error: package 'foo_msgs' not found in []\n"
