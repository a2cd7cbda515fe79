"""The documentation is checked, not copied: README.md and docs/*.md against the code.

- Every fenced ``console`` block preceded by ``<!-- checked -->`` is run: each ``$ roe-sep ...`` line as a command
  from the repository root, its output (stdout and stderr as the process wrote them) compared exactly with the lines
  that follow it. Only the working directory is normalised (written ``$PWD``). ``<!-- checked: dds -->`` blocks start
  DDS nodes: they run in a test marked ``dds``, from a temporary directory.
- The generated blocks (``python -m roe_sep.docgen``) are current, and the scan behind the topic table sees the
  subscribers the simulator waits for (:data:`roe_sep.graph.SUBSCRIBERS`).
- A fenced block preceded by ``<!-- excerpt: FILE -->`` is an excerpt of a recorded result (``bench/results/...``):
  its lines appear in FILE in the same order, a ``...`` line standing for lines left out. With
  ``<!-- excerpt: {out}/NAME from: roe-sep ... {out} ... -->`` the command first writes FILE into a temporary
  ``{out}``. The wall-clock ``CREATION_DATE`` of a CCSDS file is the only value normalised.
- Every relative link and image points to an existing file, every ``#anchor`` to a heading of its page.
"""

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))
CHECKED = re.compile(r"^<!-- checked(?:: (?P<kind>\w+))? -->\n```console\n(?P<body>.*?)^```$", re.M | re.S)
COMMAND_TIMEOUT = 600  # s: a DDS run on a loaded machine takes minutes; the others a few seconds
EXCERPT = re.compile(r"^<!-- excerpt: (?P<file>\S+)(?: from: (?P<cmd>.+?))? -->\n```[^\n]*\n(?P<body>.*?)^```$",
                     re.M | re.S)
VARIABLE = re.compile(r"^(CREATION_DATE\s*=).*$", re.M)  # wall-clock time of writing a CCSDS file
FENCE = re.compile(r"^```.*?^```$", re.M | re.S)
LINK = re.compile(r"!?\[[^\]]*\]\((?P<target>[^)\s]+)\)")


def checked_blocks(kind=None):
    """[(page name, block index, [(command, expected output)])] of the checked blocks of ``kind`` (None: plain)."""
    out = []
    for page in PAGES:
        for k, match in enumerate(CHECKED.finditer(page.read_text(encoding="utf-8"))):
            if match["kind"] == kind:
                out.append((page.relative_to(ROOT).as_posix(), k, commands(match["body"])))
    return out


def commands(body):
    """[(command, expected output)] of a console block: ``$ `` lines and the lines after each."""
    pairs = []
    for line in body.splitlines():
        if line.startswith("$ "):
            pairs.append((line[2:], []))
        elif pairs:
            pairs[-1][1].append(line)
        else:
            raise ValueError(f"output before the first command: {line!r}")
    return [(cmd, "\n".join(lines)) for cmd, lines in pairs]


def run_documented(command, cwd):
    """The output of one documented command, with ``cwd`` written ``$PWD``."""
    argv = shlex.split(command)
    assert argv[0] == "roe-sep", f"a checked command runs roe-sep only: {command!r}"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    proc = subprocess.run([sys.executable, "-m", "roe_sep.cli", *argv[1:]], cwd=cwd, env=env, text=True,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=COMMAND_TIMEOUT)
    return proc.stdout.rstrip("\n").replace(str(cwd), "$PWD")


def mismatch(command, expected, actual):
    """'' when equal, else the first differing line of both."""
    if expected == actual:
        return ""
    exp, act = expected.splitlines(), actual.splitlines()
    k = next((i for i, (a, b) in enumerate(zip(exp, act)) if a != b), min(len(exp), len(act)))
    return (f"{command!r}: line {k + 1} differs\n  documented: {exp[k] if k < len(exp) else '<end>'!r}\n"
            f"  actual:     {act[k] if k < len(act) else '<end>'!r}")


def _ids(blocks):
    return [f"{page}#{k}" for page, k, _ in blocks]


PLAIN = checked_blocks()
DDS = checked_blocks("dds")


def test_the_pages_have_checked_blocks():
    pages = {page for page, _, _ in PLAIN + DDS}
    assert {"README.md", "docs/cli.md", "docs/failures.md", "docs/run.md"} <= pages


@pytest.mark.parametrize("page, index, pairs", PLAIN, ids=_ids(PLAIN))
def test_documented_output_is_what_the_code_prints(page, index, pairs):
    problems = [mismatch(cmd, expected, run_documented(cmd, ROOT)) for cmd, expected in pairs]
    assert [p for p in problems if p] == []


@pytest.mark.dds
@pytest.mark.parametrize("page, index, pairs", DDS, ids=_ids(DDS))
def test_documented_run_output_is_what_the_code_prints(page, index, pairs, tmp_path):
    problems = [mismatch(cmd, expected, run_documented(cmd, tmp_path)) for cmd, expected in pairs]
    assert [p for p in problems if p] == []


def test_a_wrong_documented_output_is_caught():
    pairs = commands("$ roe-sep design --spl-dv nan\nroe-sep design: error: something else\n")
    (cmd, expected), = pairs
    report = mismatch(cmd, expected, run_documented(cmd, ROOT))
    assert "line 1 differs" in report and "expected a finite number" in report


# ------------------------------------------------------------------------------------------- excerpts
def excerpts():
    """[(page, file, command or None, body)] of the excerpt blocks."""
    return [(page.relative_to(ROOT).as_posix(), m["file"], m["cmd"], m["body"]) for page in PAGES
            for m in EXCERPT.finditer(page.read_text(encoding="utf-8"))]


def excerpt_problem(body, text):
    """'' when every segment of ``body`` (split at ``...`` lines) occurs in ``text`` as consecutive lines, in order;
    else the first segment line that does not."""
    lines = VARIABLE.sub(r"\1", text).splitlines()
    pos = 0
    segments = [[]]
    for line in VARIABLE.sub(r"\1", body).splitlines():
        if line.strip() == "...":
            segments.append([])
        else:
            segments[-1].append(line)
    for segment in filter(None, segments):
        n = len(segment)
        found = next((i for i in range(pos, len(lines) - n + 1) if lines[i:i + n] == segment), None)
        if found is None:
            return f"not in the file (in this order): {segment[0]!r} ... ({n} lines)"
        pos = found + n
    return ""


EXCERPTS = excerpts()


def test_the_pages_have_excerpts():
    assert {page for page, *_ in EXCERPTS} >= {"docs/campaigns.md", "docs/ground_segment.md"}


@pytest.mark.parametrize("page, file, command, body", EXCERPTS, ids=[f"{e[0]}:{e[1]}" for e in EXCERPTS])
def test_documented_excerpt_is_in_the_recorded_file(page, file, command, body, tmp_path):
    if command:
        out = tmp_path / "out"
        assert run_documented(command.replace("{out}", str(out)), ROOT) is not None
    path = Path(file.replace("{out}", str(tmp_path / "out")))
    text = (path if path.is_absolute() else ROOT / path).read_text(encoding="utf-8")
    assert excerpt_problem(body, text) == ""


def test_an_excerpt_not_in_the_file_is_caught():
    text = "a\nb\nc\nCREATION_DATE = 2026-11-25T00:00:00\nd\n"
    assert excerpt_problem("a\nb\n...\nCREATION_DATE = 2020-01-01\nd\n", text) == ""
    assert excerpt_problem("a\nc\n", text) != ""  # not consecutive
    assert excerpt_problem("d\n...\na\n", text) != ""  # not in order


# ------------------------------------------------------------------------------------------ generated
def test_generated_tables_are_current():
    from roe_sep import docgen

    text = docgen.DOC.read_text(encoding="utf-8")
    assert docgen.render(text, docgen.generated()) == text, "docs are stale: run python -m roe_sep.docgen"


def test_docgen_check_refuses_a_stale_page(tmp_path):
    from roe_sep import docgen

    page = tmp_path / "ros_interface.md"
    text = docgen.DOC.read_text(encoding="utf-8")
    page.write_text(text, encoding="utf-8")
    assert docgen.main([str(page), "--check"]) == 0
    page.write_text(text.replace("| `/acquisition/plan` |", "| `/acquisition/plans` |"), encoding="utf-8")
    assert docgen.main([str(page), "--check"]) == 1
    assert docgen.main([str(page)]) == 0 and page.read_text(encoding="utf-8") == text
    page.write_text("no markers\n", encoding="utf-8")
    assert docgen.main([str(page), "--check"]) == 2


def test_the_topic_table_has_every_subscriber_the_simulator_waits_for():
    from roe_sep import docgen, graph

    table = docgen.graph_table()
    scanned = {topic: set(table[topic]["sub"]) - set(graph.OPTIONAL_NODES) for topic in graph.SUBSCRIBERS}
    waited = {topic: set(subs) - {"recorder"} for topic, subs in graph.SUBSCRIBERS.items()}
    assert scanned == waited


def test_the_topic_table_lists_every_topic_and_service_of_the_interface():
    from roe_sep import docgen, interfaces

    names = {v for k, v in vars(interfaces).items() if k.endswith(("_TOPIC", "_SERVICE"))}
    assert names - set(docgen.graph_table()) == set()


# ---------------------------------------------------------------------------------------------- links
def slugs(text):
    """GitHub's anchors of the headings of a page."""
    seen, out = {}, set()
    for line in FENCE.sub("", text).splitlines():
        match = re.match(r"#{1,6} (.+)", line)
        if not match:
            continue
        slug = re.sub(r"[^\w\- ]", "", match[1].strip().lower()).replace(" ", "-")
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        out.add(slug if n == 0 else f"{slug}-{n}")
    return out


def broken_links(page):
    text = page.read_text(encoding="utf-8")
    broken = []
    for match in LINK.finditer(FENCE.sub("", text)):
        target = match["target"]
        if re.match(r"[a-z]+:", target):
            continue
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists():
            broken.append(f"{target}: no such file")
        elif anchor and dest.suffix == ".md" and anchor not in slugs(dest.read_text(encoding="utf-8")):
            broken.append(f"{target}: no heading #{anchor}")
    return broken


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_relative_link_resolves(page):
    assert broken_links(page) == []


def test_a_broken_link_is_caught(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("# A heading\n\n[ok](#a-heading) [bad](#no-heading) [gone](missing.md) ![img](x.png)\n",
                    encoding="utf-8")
    assert broken_links(page) == ["#no-heading: no heading #no-heading", "missing.md: no such file",
                                  "x.png: no such file"]


def test_the_readme_contingency_table_is_the_recorded_one():
    """The README's short table is :func:`compact_markdown` of the recorded rows (bench/results/contingency_table.json),
    as studies/contingency_table.py --compact-md wrote it."""
    from roe_sep.campaign.contingency_table import compact_markdown

    rows = json.loads((ROOT / "bench/results/contingency_table.json").read_text(encoding="utf-8"))
    table = compact_markdown(rows)
    assert (ROOT / "bench/results/contingency_table_compact.md").read_text(encoding="utf-8") == table
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert table in readme, "README.md's contingency table differs from the recorded rows"


def test_the_contingency_table_is_the_recorded_one():
    """docs/contingencies.md shows the table studies/contingency_table.py wrote from the campaigns
    (bench/results/contingency_table.md, the Markdown of the recorded rows bench/results/contingency_table.json:
    a column recorded without its data "n/a"), row for row."""
    from roe_sep.campaign.contingency_table import markdown

    rows = json.loads((ROOT / "bench/results/contingency_table.json").read_text(encoding="utf-8"))
    text = (ROOT / "bench/results/contingency_table.md").read_text(encoding="utf-8")
    assert text == markdown(rows), "re-render: studies/contingency_table.py --from-json (its docstring)"
    recorded = text.splitlines()
    page = (ROOT / "docs/contingencies.md").read_text(encoding="utf-8").splitlines()
    assert recorded and [line for line in recorded if line not in page] == []
