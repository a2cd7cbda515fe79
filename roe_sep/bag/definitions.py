"""Message definitions for MCAP schemas, resolved from the installed interface packages (no rclpy).

:func:`full_text` returns the ``ros2msg`` schema text as rosbag2_storage_mcap writes it (Jazzy,
``message_definition_cache.cpp``): the type's own ``.msg`` file verbatim, then for every dependency, depth first in
sorted order and each only once, a line of 80 ``=``, ``MSG: pkg/Type`` (as the field spells it) and that ``.msg``.
:func:`type_hash` returns the type's ``RIHS01_...`` hash from the ``.json`` type description rosidl installs next
to the ``.msg``.
"""

import functools
import importlib
import json
import os
import re
import sys
from pathlib import Path

from ..errors import DefinitionNotFound

SEPARATOR = "=" * 80 + "\n"
# foo_msgs/Bar or foo_msgs/msg/Bar
_TYPENAME = re.compile(r"^([a-zA-Z][a-zA-Z0-9_]*)/((?:msg|srv)/)?([a-zA-Z][a-zA-Z0-9_]*)$")
# the type of each field line ("foo_msgs/Bar" in "foo_msgs/Bar[] bar"); same pattern as rosbag2
_FIELD_TYPE = re.compile(r"(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+")
PRIMITIVES = frozenset({"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32",
                        "uint32", "int64", "uint64", "string", "wstring"})


def split_type(name: str):
    """``pkg/msg/Type`` or ``pkg/Type`` -> ``(pkg, "msg", Type)``; ValueError for anything else."""
    m = _TYPENAME.match(name)
    if not m:
        raise ValueError(f"not a ROS message type name: {name!r} (expected pkg/msg/Type)")
    return m.group(1), (m.group(2) or "msg/").rstrip("/"), m.group(3)


def canonical_type(name: str) -> str:
    """``pkg/Type`` -> ``pkg/msg/Type``."""
    pkg, ns, typ = split_type(name)
    return f"{pkg}/{ns}/{typ}"


def _prefixes():
    """Install prefixes to search: AMENT_PREFIX_PATH, then this interpreter's prefix (the venv of the PyPI wheels,
    where AMENT_PREFIX_PATH is usually unset)."""
    seen = []
    for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) + [sys.prefix]:
        if p and p not in seen:
            seen.append(p)
    return seen


@functools.lru_cache(maxsize=None)
def share_dir(package: str) -> Path:
    """``<prefix>/share/<package>``: ament_index first, the interpreter's prefix as fallback."""
    try:
        from ament_index_python.packages import get_package_share_directory

        return Path(get_package_share_directory(package))
    except Exception:  # noqa: BLE001  (PackageNotFoundError, or OSError when AMENT_PREFIX_PATH is unset)
        pass
    for prefix in _prefixes():
        d = Path(prefix) / "share" / package
        if d.is_dir():
            return d
    raise DefinitionNotFound(f"package {package!r} not found in {_prefixes()}")


@functools.lru_cache(maxsize=None)
def msg_text(name: str) -> str:
    """The installed ``.msg`` text of a type, verbatim."""
    pkg, ns, typ = split_type(name)
    path = share_dir(pkg) / ns / f"{typ}.msg"
    try:
        return path.read_text(encoding="utf-8")
    except OSError:
        raise DefinitionNotFound(f"no message definition for {name}: {path} not found") from None


def dependencies(text: str, package: str):
    """Non-primitive field types of a ``.msg`` text, as written (``pkg/Type``; bare names get ``package/``)."""
    deps = set()
    for m in _FIELD_TYPE.finditer(text):
        t = m.group(1)
        if t in PRIMITIVES:
            continue
        deps.add(t if "/" in t else f"{package}/{t}")
    return sorted(deps)


@functools.lru_cache(maxsize=None)
def full_text(name: str) -> str:
    """The full ``ros2msg`` schema text of ``name`` with every dependency (rosbag2 layout)."""
    seen = set()

    def append(type_name, depth):
        if depth <= 0:
            raise RecursionError(f"message definition of {name} nests too deeply")
        text = msg_text(type_name)
        out = text
        for dep in dependencies(text, split_type(type_name)[0]):
            if dep not in seen:
                seen.add(dep)
                out += "\n" + SEPARATOR + f"MSG: {dep}\n" + append(dep, depth - 1)
        return out

    return append(name, 50)


@functools.lru_cache(maxsize=None)
def type_hash(name: str) -> str:
    """``RIHS01_<hex>`` of the type from its installed type description; '' if not available."""
    pkg, ns, typ = split_type(name)
    try:
        data = json.loads((share_dir(pkg) / ns / f"{typ}.json").read_text(encoding="utf-8"))
    except (OSError, ValueError, DefinitionNotFound):
        return ""
    want = f"{pkg}/{ns}/{typ}"
    for entry in data.get("type_hashes", []):
        if entry.get("type_name") == want:
            return entry.get("hash_string", "")
    return ""


def message_class(name: str):
    """The generated Python class of ``pkg/msg/Type`` (imports the interface package, not rclpy)."""
    pkg, ns, typ = split_type(name)
    return getattr(importlib.import_module(f"{pkg}.{ns}"), typ)
