"""Two house rules of every module in ``roe_sep/`` (docs/developers.md), as tests over the source with ``ast``:

* no function takes more than 5 positional parameters: the ones after the 5th are keyword-only (``*``), so a call
  never passes a sixth bare number. ``self``/``cls`` of a method are not counted (the caller does not write them:
  ``obj.m(a, b, c, d, e)`` is a call with five arguments); a ``*args`` is not a positional parameter;
* no docstring (module, class or function) is over 30 lines: a docstring holds the model, the contract and the
  citation; measurements and history go to docs/.

The failure message lists every offender as ``path:line name``.
"""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MAX_POSITIONAL = 5
MAX_DOC_LINES = 30

# Offenders kept while a change is in flight (none now): a listed name that no longer offends fails the test, so
# the list only shrinks.
HELD_POSITIONAL: set[str] = set()
HELD_DOCSTRINGS: set[str] = set()


def functions(tree: ast.Module):
    """``(qualified name, FunctionDef, is a method)`` of every function, nested ones included."""
    def walk(node, prefix, in_class):
        for ch in ast.iter_child_nodes(node):
            if isinstance(ch, ast.ClassDef):
                yield from walk(ch, f"{prefix}{ch.name}.", True)
            elif isinstance(ch, (ast.FunctionDef, ast.AsyncFunctionDef)):
                yield f"{prefix}{ch.name}", ch, in_class
                yield from walk(ch, f"{prefix}{ch.name}.", False)
            else:
                yield from walk(ch, prefix, in_class)
    yield from walk(tree, "", False)


def positional(f: ast.FunctionDef, method: bool) -> list:
    """The parameters a caller may pass by position, without a method's ``self``/``cls``."""
    pos = f.args.posonlyargs + f.args.args
    static = any(isinstance(d, ast.Name) and d.id == "staticmethod" for d in f.decorator_list)
    if method and not static and pos and pos[0].arg in ("self", "cls"):
        pos = pos[1:]
    return pos


def offenders(paths, root=ROOT):
    """``({'path name': line} of functions with too many positional parameters, {'path name': lines} of long
    docstrings)``."""
    args, docs = {}, {}
    for path in paths:
        rel = path.relative_to(root).as_posix()
        tree = ast.parse(path.read_text(encoding="utf-8"))
        nodes = [("<module>", tree)] + [(name, f) for name, f, _ in functions(tree)]
        nodes += [(n.name, n) for n in ast.walk(tree) if isinstance(n, ast.ClassDef)]
        for name, f, method in functions(tree):
            if len(positional(f, method)) > MAX_POSITIONAL:
                args[f"{rel} {name}"] = f.lineno
        for name, node in nodes:
            doc = ast.get_docstring(node, clean=False)
            if doc and doc.count("\n") + 1 > MAX_DOC_LINES:
                docs[f"{rel} {name}"] = doc.count("\n") + 1
    return args, docs


def sources():
    return sorted((ROOT / "roe_sep").rglob("*.py"))


def check(found, held, what):
    """Fail listing the offenders ``found`` that are not ``held``, and the held ones that no longer offend."""
    new = sorted(f"{k} ({v})" for k, v in found.items() if k not in held)
    assert new == [], f"{what}: {new}"
    stale = sorted(held - set(found))
    assert stale == [], f"fixed: remove from the held list: {stale}"


def test_no_function_takes_more_than_five_positional_parameters():
    check(offenders(sources())[0], HELD_POSITIONAL,
          f"more than {MAX_POSITIONAL} positional parameters (put a * after the 5th; path name (line))")


def test_no_docstring_is_over_thirty_lines():
    check(offenders(sources())[1], HELD_DOCSTRINGS,
          f"docstrings over {MAX_DOC_LINES} lines (move measurements and history to docs/; path name (lines))")


def test_the_checks_find_offenders(tmp_path):
    bad = tmp_path / "bad.py"
    long_doc = '"""' + "\n" * MAX_DOC_LINES + '"""'
    bad.write_text(f"{long_doc}\n\n\ndef f(a, b, c, d, e, g):\n    pass\n\n\n"
                   "def ok(a, b, c, d, e, *, g):\n    pass\n\n\n"
                   "class C:\n    def m(self, a, b, c, d, e):\n        pass\n\n    def n(self, a, b, c, d, e, g):\n"
                   f"        {long_doc}\n\n    @staticmethod\n    def s(a, b, c, d, e, g):\n        pass\n\n\n"
                   "def v(a, b, c, d, e, *args):\n    pass\n")
    args, docs = offenders([bad], tmp_path)
    assert sorted(args) == ["bad.py C.n", "bad.py C.s", "bad.py f"]
    assert docs == {"bad.py <module>": MAX_DOC_LINES + 1, "bad.py C.n": MAX_DOC_LINES + 1}
