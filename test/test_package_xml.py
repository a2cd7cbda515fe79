"""package.xml declares every run-time dependency of setup.py, so that ``rosdep install`` gives a ROS user what ``pip
install`` gives a venv: each ``install_requires`` entry has its rosdep key among the ``exec_depend`` and each Python
key there is an ``install_requires`` entry. Keys rosdistro lacks are the ``python3-<name>-pip`` keys of
rosdep/roe_sep.yaml, each installing that very pip requirement."""

import ast
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
# install_requires names with a system key in rosdistro's rosdep/python.yaml (ros/rosdistro 000730dc); every other
# name is python3-<name>-pip
SYSTEM_KEYS = {"numpy": "python3-numpy", "scipy": "python3-scipy", "pyyaml": "python3-yaml", "tqdm": "python3-tqdm"}


def install_requires():
    """setup.py's ``install_requires`` strings, read from its syntax tree (setup() is not run)."""
    tree = ast.parse((ROOT / "setup.py").read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.keyword) and node.arg == "install_requires":
            return [ast.literal_eval(elt) for elt in node.value.elts]
    raise AssertionError("setup.py has no install_requires")


def project(requirement):
    """The project name of a requirement string ('dask[distributed]>=2024.1' -> 'dask')."""
    return re.match(r"[A-Za-z0-9._-]+", requirement).group(0).lower()


def rosdep_key(requirement):
    name = project(requirement)
    return SYSTEM_KEYS.get(name, f"python3-{name}-pip")


def exec_depends():
    root = ET.parse(ROOT / "package.xml").getroot()
    return [e.text.strip() for e in root.findall("exec_depend")]


def test_every_install_requires_entry_has_its_rosdep_key():
    declared = exec_depends()
    missing = [(r, rosdep_key(r)) for r in install_requires() if rosdep_key(r) not in declared]
    assert not missing, f"package.xml lacks <exec_depend> for {missing}"


def test_every_python_key_of_package_xml_is_an_install_requires_entry():
    expected = {rosdep_key(r) for r in install_requires()}
    python_keys = [k for k in exec_depends() if k.startswith("python3-")]
    assert len(python_keys) == len(set(python_keys)), python_keys
    assert set(python_keys) == expected, set(python_keys) ^ expected


def test_pip_keys_install_the_setup_py_requirement():
    rules = yaml.safe_load((ROOT / "rosdep" / "roe_sep.yaml").read_text(encoding="utf-8"))
    pip_keys = {rosdep_key(r): r for r in install_requires() if rosdep_key(r).endswith("-pip")}
    assert set(rules) == set(pip_keys)
    for key, requirement in pip_keys.items():
        for os_name in ("debian", "fedora", "ubuntu"):
            assert rules[key][os_name]["pip"]["packages"] == [requirement], (key, os_name)
    assert not set(SYSTEM_KEYS.values()) & set(rules)  # rosdistro's own keys are not redefined
