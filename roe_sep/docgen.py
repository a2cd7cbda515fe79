"""The generated parts of ``docs/ros_interface.md``: the topic and service table, read from the nodes' code, and
the message and service table, read from ``msg_defs``. ``python -m roe_sep.docgen`` rewrites the marked blocks;
``--check`` only compares them and exits 1 when the documentation is stale (``test/test_docs.py`` does the same).

Topics: every ``create_publisher``/``create_subscription``/``create_service`` call (and ``subscribe_decoded(node,
...)``) of a node module (``roe_sep/nodes/<node>.py``) and every ``publisher``/``subscribe`` call of its lockstep
helper, with the message type, topic name and QoS profile evaluated in the module's own namespace (a ``for`` loop
over a literal tuple of subscriptions is unrolled). Calls of the lockstep helper module itself belong to every
lockstep participant (:data:`roe_sep.graph.PARTICIPANTS`). Topics whose name is only known at run time (the recorder
and ``foxglove_view`` follow every topic) cannot be listed and are said so beside the table.

Messages: each field of ``msg_defs/msg/*.msg`` and ``msg_defs/srv/*.srv`` with the comment on its line (unit
first), each file's leading comment as its description.

Top of the layering (like the command line): it imports the nodes to evaluate their arguments.
"""

import argparse
import ast
import importlib
import json
import re
import sys
from pathlib import Path

from roe_sep import graph, interfaces

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "ros_interface.md"
MSG_DIR = ROOT / "msg_defs"
NODE_MODULES = graph.NODES + graph.OPTIONAL_NODES + ("analysis_server", "lifecycle_manager")
HELPERS = {"lockstep": graph.PARTICIPANTS}  # helper module -> the nodes whose endpoints its calls create
PUBLISH = {"create_publisher": 2, "publisher": 2}  # method -> position of the QoS argument
SUBSCRIBE = {"create_subscription": 3, "subscribe": 3}
# functions that create an endpoint on the node given first: name -> (kind, the QoS argument's position)
FUNCTIONS = {"subscribe_decoded": ("sub", 4)}
SERVE = {"create_service": None}
BLOCKS = ("topics", "messages")


def begin(name):
    return f"<!-- BEGIN GENERATED {name}: python -m roe_sep.docgen; do not edit by hand -->"


def end(name):
    return f"<!-- END GENERATED {name} -->"


# ----------------------------------------------------------------------------------------------- topics
def _bind(target, value):
    """{name: value} of a ``for`` target (a name or a tuple of names) bound to one element; None if it does not fit."""
    if isinstance(target, ast.Name):
        return {target.id: value}
    if isinstance(target, ast.Tuple) and isinstance(value, (tuple, list)) and len(value) == len(target.elts):
        out = {}
        for element, item in zip(target.elts, value):
            bound = _bind(element, item)
            if bound is None:
                return None
            out.update(bound)
        return out
    return None


def _loops(tree, namespace):
    """{id(call): [binding, ...]} for the calls inside a ``for`` loop over a sequence known without running the node
    (a module constant, or a literal assigned in the same function), one binding {name: value} per iteration."""
    out = {}
    for func in ast.walk(tree):
        if not isinstance(func, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        literals = {t.id: node.value for node in ast.walk(func) if isinstance(node, ast.Assign)
                    for t in node.targets if isinstance(t, ast.Name) and isinstance(node.value, (ast.Tuple, ast.List))}
        for loop in ast.walk(func):
            if not isinstance(loop, ast.For):
                continue
            expr = literals.get(loop.iter.id, loop.iter) if isinstance(loop.iter, ast.Name) else loop.iter
            seq = _value(expr, namespace, {})
            if not isinstance(seq, (tuple, list)):
                continue
            bindings = [b for b in (_bind(loop.target, item) for item in seq) if b is not None]
            for stmt in loop.body:
                for call in ast.walk(stmt):
                    if isinstance(call, ast.Call):
                        out[id(call)] = bindings
    return out


def _value(expr, namespace, binding):
    """The value of ``expr`` in the module ``namespace`` with the loop ``binding`` ({name: value}); None if it
    cannot be known without running the node (``self...``, a function argument)."""
    try:
        return eval(compile(ast.Expression(expr), "<docgen>", "eval"), dict(namespace), dict(binding))  # noqa: S307
    except Exception:  # noqa: BLE001  (a name only bound at run time)
        return None


def _argument(call, position, keyword):
    if position is not None and len(call.args) > position:
        return call.args[position]
    return next((k.value for k in call.keywords if k.arg == keyword), None)


def endpoints(module_name):
    """[(kind, topic, type, qos)] of the calls in ``roe_sep.nodes.<module_name>``, kind 'pub', 'sub' or 'srv'."""
    module = importlib.import_module(f"roe_sep.nodes.{module_name}")
    tree = ast.parse(Path(module.__file__).read_text(encoding="utf-8"))
    loops = _loops(tree, vars(module))
    found = []
    for call in ast.walk(tree):
        if not isinstance(call, ast.Call):
            continue
        if isinstance(call.func, ast.Name) and call.func.id in FUNCTIONS:  # f(node, type, topic, ...)
            kind, position = FUNCTIONS[call.func.id]
            args = call.args[1:]
        elif isinstance(call.func, ast.Attribute):  # node.method(type, topic, ...)
            kinds = (("pub", PUBLISH), ("sub", SUBSCRIBE), ("srv", SERVE))
            kind, table = next(((k, t) for k, t in kinds if call.func.attr in t), (None, None))
            position, args = (table or {}).get(call.func.attr), call.args
        else:
            continue
        if kind is None or len(args) < 2:
            continue
        for binding in loops.get(id(call), [{}]):
            topic = _value(args[1], vars(module), binding)
            msg_type = _value(args[0], vars(module), binding)
            if not isinstance(topic, str) or msg_type is None:
                continue
            qos_expr = _argument(call, position, "qos_profile") if position is not None else None
            qos = _value(qos_expr, vars(module), binding) if qos_expr is not None else None
            found.append((kind, topic, msg_type, qos))
    return found


def type_name(cls):
    parts = cls.__module__.split(".")
    return f"{parts[0]}/srv/{cls.__name__}" if "srv" in parts else f"{parts[0]}/{cls.__name__}"


def qos_text(qos):
    if qos is None:
        return "–"
    if isinstance(qos, int):  # rclpy: a depth alone is KEEP_LAST, RELIABLE, VOLATILE
        return f"RELIABLE, VOLATILE, depth {qos}"
    depth = "KEEP_ALL" if qos.history.name == "KEEP_ALL" else f"depth {qos.depth}"
    return f"{qos.reliability.name}, {qos.durability.name}, {depth}"


def _policies(qos):
    """'RELIABILITY, DURABILITY' of a profile (a bare depth: rclpy's RELIABLE, VOLATILE); None if unknown."""
    if qos is None:
        return None
    return "RELIABLE, VOLATILE" if isinstance(qos, int) else f"{qos.reliability.name}, {qos.durability.name}"


def graph_table():
    """{topic: {'type', 'pub': {node: qos}, 'sub': {node: qos}, 'srv': {node}}} over every node."""
    table = {}
    owners = [(m, (m,)) for m in NODE_MODULES] + list(HELPERS.items())
    for module_name, nodes in owners:
        for kind, topic, msg_type, qos in endpoints(module_name):
            row = table.setdefault(topic, {"type": type_name(msg_type), "pub": {}, "sub": {}, "srv": set()})
            for node in nodes:
                if kind == "srv":
                    row["srv"].add(node)
                else:
                    row[kind][node] = qos
    return table


def _order(topic):
    names = [v for k, v in vars(interfaces).items() if k.endswith(("_TOPIC", "_SERVICE")) and isinstance(v, str)]
    return (names.index(topic) if topic in names else len(names), topic)


def _nodes(nodes):
    return ", ".join(sorted(nodes, key=lambda n: (NODE_MODULES + ("lockstep",)).index(n)
                            if n in NODE_MODULES else len(NODE_MODULES))) or "–"


def topics_block():
    table = graph_table()
    lines = ["| topic | type | QoS of the publisher | publishers | subscribers |", "|---|---|---|---|---|"]
    for topic in sorted((t for t in table if not table[t]["srv"]), key=_order):
        row = table[topic]
        offered = {qos_text(q) for q in row["pub"].values()}
        policies = {_policies(q) for q in row["pub"].values()}
        requested = sorted({_policies(q) for q in row["sub"].values()} - policies - {None})
        qos = "; ".join(sorted(offered)) or "–"
        if requested:
            qos += f" (subscribers: {'; '.join(requested)})"
        lines.append(f"| `{topic}` | `{row['type']}` | {qos} | {_nodes(row['pub'])} | {_nodes(row['sub'])} |")
    lines += ["", "| service | type | server |", "|---|---|---|"]
    for topic in sorted((t for t in table if table[t]["srv"]), key=_order):
        lines.append(f"| `{topic}` | `{table[topic]['type']}` | {_nodes(table[topic]['srv'])} |")
    return "\n".join(lines)


# --------------------------------------------------------------------------------------------- messages
def _cell(text):
    return text.replace("|", "\\|").strip()


def interface_rows(path):
    """(description, [(section, type, field, comment)]) of one .msg or .srv file."""
    description, rows, section, started = [], [], "request" if path.suffix == ".srv" else "", False
    for raw in path.read_text(encoding="utf-8").splitlines():
        line = raw.strip()
        if line == "---":
            section, started = "response", True
            continue
        if not line or line.startswith("#"):
            if not started and line.startswith("#"):
                description.append(line.lstrip("#").strip())
            continue
        started = True
        body, _, comment = line.partition("#")
        fields = body.split()
        if len(fields) >= 2:
            rows.append((section, fields[0], fields[1], comment.strip()))
    return " ".join(description), rows


def messages_block():
    lines = ["| interface | field | type | unit / meaning |", "|---|---|---|---|"]
    for kind in ("msg", "srv"):
        for path in sorted((MSG_DIR / kind).glob(f"*.{kind}")):
            description, rows = interface_rows(path)
            name = f"`{path.stem}`" if kind == "msg" else f"`{path.stem}.srv`"
            lines.append(f"| {name} | | | {_cell(description)} |")
            for section, ftype, field, comment in rows:
                label = f"{section}: `{field}`" if section else f"`{field}`"
                lines.append(f"| | {label} | `{ftype}` | {_cell(comment)} |")
    return "\n".join(lines)


# ----------------------------------------------------------------------------------------------- blocks
def generated():
    return {"topics": topics_block(), "messages": messages_block()}


def render(text, blocks):
    """``text`` with each marked block replaced; ValueError when a marker is missing."""
    for name, body in blocks.items():
        head, tail = begin(name), end(name)
        if head not in text or tail not in text:
            raise ValueError(f"no block {name!r} ({head} ... {tail})")
        before, rest = text.split(head, 1)
        _, after = rest.split(tail, 1)
        text = f"{before}{head}\n{body}\n{tail}{after}"
    return text


# ---------------------------------------------------------------------------------------------- figures
# a measured figure in a page: <!-- figure: bench/results/FILE.json KEY [FORMAT] -->VALUE<!-- /figure -->, VALUE
# rendered from the JSON result file (KEY a dotted path, list indices as numbers; FORMAT a format spec, default "")
FIGURE = re.compile(r"<!-- figure: (?P<file>bench/results/\S+) (?P<key>\S+)(?: (?P<fmt>\S+))? -->"
                    r"(?P<value>.*?)<!-- /figure -->")
PAGES = [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))


def figure_value(file: str, key: str, fmt: str = "") -> str:
    """The figure ``key`` of the result file ``file`` (relative to the repository) formatted with ``fmt``;
    ValueError when the file does not hold it."""
    try:
        value = json.loads((ROOT / file).read_text(encoding="utf-8"))
        for part in key.split("."):
            value = value[int(part)] if isinstance(value, list) else value[part]
    except (OSError, ValueError, KeyError, IndexError) as exc:
        raise ValueError(f"figure {file} {key}: {exc!r}") from None
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        raise ValueError(f"figure {file} {key}: not a number: {value!r}")
    return format(value, fmt)


def render_figures(text):
    """``text`` with the value of every figure marker rendered from its result file."""
    def one(m):
        head = m[0][:m.start("value") - m.start()]
        return f"{head}{figure_value(m['file'], m['key'], m['fmt'] or '')}<!-- /figure -->"

    return FIGURE.sub(one, text)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m roe_sep.docgen", description=__doc__.splitlines()[0])
    ap.add_argument("file", nargs="?", default=str(DOC), help="the page with the marked blocks")
    ap.add_argument("--check", action="store_true", help="exit 1 if the blocks are stale, write nothing")
    ap.add_argument("--figures", action="store_true",
                    help="render the figure markers of README.md and docs/*.md from bench/results/ instead")
    args = ap.parse_args(argv)
    if args.figures:
        return max([_update(page, render_figures, args.check) for page in PAGES])
    return _update(Path(args.file), lambda text: render(text, generated()), args.check)


def _update(path, rendering, check):
    """Rewrite (with ``check``: only compare) ``path`` as ``rendering`` renders it; exit status 0, 1 stale, 2 error."""
    try:
        text = path.read_text(encoding="utf-8")
        new = rendering(text)
    except (OSError, ValueError) as exc:
        print(f"docgen: error: {path}: {exc}", file=sys.stderr)
        return 2
    if check:
        if new != text:
            print(f"docgen: {path} is stale: run python -m roe_sep.docgen", file=sys.stderr)
            return 1
        return 0
    if new != text:
        path.write_text(new, encoding="utf-8")
        print(f"docgen: {path} updated")
    return 0


if __name__ == "__main__":
    sys.exit(main())
