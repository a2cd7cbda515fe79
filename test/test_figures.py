"""Every figure in the docs from one source, and every quoted path real (README.md and docs/*.md).

- A measured figure -- a number with the unit s, min, h, CPU-s, MB, runs/h or tests -- is written as a figure
  marker, ``<!-- figure: bench/results/FILE.json KEY FORMAT -->VALUE<!-- /figure -->``, whose VALUE
  ``python -m roe_sep.docgen --figures`` renders from the result file; or it sits in a fenced block (checked console
  output, an excerpt of a result file, a command) or in inline code. Anything else is a figure retyped by hand.
  README.md and docs/developers.md hold none; every other page holds no more than its budget (:data:`BUDGET`, the
  figures still to move into markers or excerpts: the count may only go down).
- Every repository path quoted in backticks (``roe_sep/...``, ``test/...``, ``bench/...``, ``docs/...``,
  ``config/...``, ``scripts/...``; ``*`` and ``{a,b}`` as in the shell) exists.
"""

import glob
import re
from pathlib import Path

import pytest

from roe_sep import docgen

ROOT = Path(__file__).resolve().parents[1]
PAGES = docgen.PAGES
FENCE = re.compile(r"^```.*?^```$", re.M | re.S)
INLINE_CODE = re.compile(r"`[^`\n]+`")
UNIT = r"(?:CPU-s|runs/h|min|s|h|MB|tests)"
NUMBER = r"\d[\d,]*(?:\.\d+)?"
FIGURE = re.compile(rf"(?<![\w.,·⁰¹²³⁴⁵⁶⁷⁸⁹/-]){NUMBER}(?:\s?[–-]\s?{NUMBER})?\s?{UNIT}(?![\w/-])")
STRICT = {"README.md", "docs/developers.md"}
# figures still retyped by hand, per page: may only go down (move each into a figure marker or an excerpt block)
BUDGET = {"docs/benchmarks.md": 225, "docs/campaigns.md": 50, "docs/cli.md": 5, "docs/collision.md": 8,
          "docs/contingencies.md": 31, "docs/failures.md": 4, "docs/ground_segment.md": 14, "docs/parameters.md": 5,
          "docs/ros_interface.md": 16, "docs/run.md": 34, "docs/seeds.md": 51}
# a path of the repository: a file with an extension, or a folder (``roe_sep/...`` ends with ``/``: ``roe_sep/radar_od``
# is a diagnostic name), or a module of roe_sep written from its package (``nodes/spin.py``); a pytest node id
# (``file::test``) is its file
QUOTED_PATH = re.compile(r"""`((?:(?:test|bench|docs|config|scripts)/[^`\s<>:]*)|roe_sep/[^`\s<>:]*(?:\.\w+|/)
                         |(?:nodes|core|bag|cli|campaign|engine|ndm|plots)/[^`\s<>:]*\.py)(?:::\w+)?`""", re.X)


def handwritten_figures(text):
    """[(line number, figure)] of the figures of ``text`` outside figure markers, fenced blocks and inline code."""
    prose = FENCE.sub(lambda m: "\n" * m[0].count("\n"), text)
    prose = INLINE_CODE.sub("", docgen.FIGURE.sub("", prose))
    return [(k, m[0]) for k, line in enumerate(prose.splitlines(), 1) for m in FIGURE.finditer(line)]


def _name(page):
    return page.relative_to(ROOT).as_posix()


@pytest.mark.parametrize("page", PAGES, ids=_name)
def test_figures_are_rendered_from_their_result_files(page):
    text = page.read_text(encoding="utf-8")
    assert docgen.render_figures(text) == text, "figures are stale: run python -m roe_sep.docgen --figures"


@pytest.mark.parametrize("page", PAGES, ids=_name)
def test_no_figure_is_retyped_by_hand(page):
    name = _name(page)
    found = handwritten_figures(page.read_text(encoding="utf-8"))
    limit = 0 if name in STRICT else BUDGET.get(name, 0)
    assert len(found) <= limit, f"{name}: figures without a source (write a figure marker): {found}"


def test_a_figure_typed_by_hand_is_caught():
    old = ("runs (about 0.3 s). `make test-unit` (`-m \"not dds and not slow\"`, about 1,100 tests in about a minute)\n"
           "criterion ([run.md](docs/run.md)). A run takes 16–19 s on an idle 2-core machine, 27.9 CPU-s, 1,908 runs/h")
    assert [f for _, f in handwritten_figures(old)] == ["0.3 s", "1,100 tests", "16–19 s", "27.9 CPU-s",
                                                          "1,908 runs/h"]
    marked = "about <!-- figure: bench/results/commands.json tests_unit , -->1,240<!-- /figure --> tests"
    assert handwritten_figures(marked) == []
    assert handwritten_figures("```console\n$ roe-sep run\n1.2 s\n```\n`--runs 100` at 3.25 days, Eq. 22") == []


def test_a_stale_or_unsourced_figure_marker_is_refused():
    marker = "<!-- figure: bench/results/commands.json tests_total , -->{}<!-- /figure -->"
    assert docgen.render_figures(marker.format("1")) != marker.format("1")
    with pytest.raises(ValueError, match="no_such_key"):
        docgen.render_figures("<!-- figure: bench/results/commands.json no_such_key -->1<!-- /figure -->")
    with pytest.raises(ValueError, match="not a number"):
        docgen.render_figures("<!-- figure: bench/results/commands.json about -->1<!-- /figure -->")
    assert docgen.main(["--figures", "--check"]) == 0


def _expand(pattern):
    """The shell's ``{a,b}`` alternatives of ``pattern``."""
    m = re.search(r"\{([^{}]*)\}", pattern)
    if not m:
        return [pattern]
    return [p for alt in m[1].split(",") for p in _expand(pattern[:m.start()] + alt + pattern[m.end():])]


def missing_paths(text):
    """The repository paths quoted in ``text`` that match no file or directory."""
    return [path for path in QUOTED_PATH.findall(text)
            if not any(glob.glob(str(root / p.rstrip("/"))) for p in _expand(path)
                       for root in (ROOT, ROOT / "roe_sep"))]


@pytest.mark.parametrize("page", PAGES, ids=_name)
def test_every_quoted_path_exists(page):
    assert missing_paths(page.read_text(encoding="utf-8")) == []


def test_a_dead_path_is_caught():
    assert missing_paths("`test/core/test_sweep_store.py` and `roe_sep/nodes/cdr.py`, `roe_sep/core/`") == [
        "test/core/test_sweep_store.py", "roe_sep/nodes/cdr.py"]
    assert missing_paths("`nodes/cdr.py` and `nodes/spin.py`") == ["nodes/cdr.py"]
    assert missing_paths("`bench/results/bench_stream_1e6.{json,md}`, `bench/results/mc_1e7_*`, `test/core`") == []
    assert missing_paths("`test/nodes/test_lockstep.py::test_x`, `roe_sep/radar_od` (a diagnostic name)") == []
    assert missing_paths("`test/nodes/test_lockstep.py.orig::test_x`") == ["test/nodes/test_lockstep.py.orig"]
