"""The docs stay true: every shell example of README.md and docs/*.md is run and its output
compared; links resolve; quoted commands parse; docs/architecture.md matches the import ranks.

An example is a fenced block line ``$ COMMAND`` followed by the output it shows. Rules, so
that docs cannot drift silently:
- ``# exit N`` after the command gives the expected exit status (default 0);
- the shown lines must appear in the real output in order and consecutively, except where
  a line ``...`` or ``…`` (alone) skips any number of lines or one inside a line matches any
  text; a blank line ends the example's output;
- an annotation ``   <- text`` at the end of a shown line is a comment, not output;
- timings are normalised on both sides (``7.1 s``, ``8.5x``, ``58.3 ms``), nothing else.
The examples are marked slow (each is a subprocess run of the CLI; `make test` runs them).
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
ENTRY = {"tamp": "tamp.commands.main", "tamp-verify": "tamp.commands.verify"}
_TIMING = re.compile(r"\b\d+(?:\.\d+)?(?= ?(?:s\b|ms\b|x\b|µs\b))")


@dataclass
class Example:
    file: str
    line: int
    command: str
    exit: int
    shown: list[str]

    @property
    def id(self) -> str:
        return f"{self.file}:{self.line}"


def _examples() -> list[Example]:
    found = []
    for doc in DOCS:
        lines = doc.read_text(encoding="utf-8").splitlines()
        in_block = False
        current: Example | None = None
        for n, line in enumerate(lines, 1):
            if line.startswith("```"):
                in_block = not in_block
                current = None
                continue
            if not in_block:
                continue
            if line.startswith("$ "):
                text = line[2:]
                code = 0
                m = re.search(r"\s+#\s*(.*)$", text)
                if m:
                    text = text[: m.start()]
                    em = re.match(r"exit (\d+)", m.group(1))
                    code = int(em.group(1)) if em else 0
                current = Example(doc.name, n, text.strip(), code, [])
                found.append(current)
            elif current is not None and not line.strip():
                current = None
            elif current is not None:
                shown = re.sub(r"\s+<-\s.*$", "", line).replace("…", "...").rstrip()
                current.shown.append(shown)
    return found


def _norm(line: str) -> str:
    return _TIMING.sub("<n>", line.rstrip())


def _matches(shown: str, actual: str) -> bool:
    shown, actual = _norm(shown), _norm(actual)
    if "..." not in shown:
        return shown == actual
    pattern = ".*".join(re.escape(part) for part in shown.split("..."))
    return re.fullmatch(pattern, actual) is not None


def _compare(shown: list[str], actual: list[str]) -> str | None:
    """None when ``shown`` matches ``actual`` (see the module docstring), else why not."""
    chunks: list[list[str]] = [[]]
    for line in shown:
        if line.strip() == "...":
            chunks.append([])
        else:
            chunks[-1].append(line)
    pos = 0
    for k, chunk in enumerate(chunks):
        if not chunk:
            continue
        anchored = k == 0
        start_range = [pos] if anchored else range(pos, len(actual) - len(chunk) + 1)
        for start in start_range:
            if start + len(chunk) <= len(actual) and all(
                _matches(s, actual[start + i]) for i, s in enumerate(chunk)
            ):
                pos = start + len(chunk)
                break
        else:
            return f"not found in order: {chunk[0]!r}"
    return None


def _params():
    out = []
    for ex in _examples():
        # every example is a subprocess run of the CLI: slow for the quick loop (make test runs
        # them all, as CI does)
        out.append(pytest.param(ex, id=ex.id, marks=[pytest.mark.slow]))
    return out


@pytest.mark.parametrize("example", _params())
def test_doc_example_output(example: Example, tmp_path):
    argv = shlex.split(example.command)
    assert argv[0] in ENTRY, f"{example.id}: only tamp and tamp-verify examples are run"
    env = {**os.environ, "DRAKE_ALLOW_NETWORK": "meshcat", "PYTHONPATH": str(ROOT)}
    proc = subprocess.run(
        [sys.executable, "-m", ENTRY[argv[0]], *argv[1:]],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=600,
    )
    assert proc.returncode == example.exit, (
        f"{example.id}: exit {proc.returncode}, expected {example.exit}\n{proc.stderr}"
    )
    why = _compare(example.shown, proc.stdout.splitlines())
    assert why is None, f"{example.id}: {why}\n--- actual output ---\n{proc.stdout}"


def test_the_comparison_itself():
    actual = ["a", "b 7.1 s", "c", "d", "e"]
    assert _compare(["a", "b 9.9 s"], actual) is None
    assert _compare(["a", "...", "d", "e"], actual) is None
    assert _compare(["a", "c"], actual) is not None  # consecutive unless "..." between
    assert _compare(["b..."], actual) is not None  # the first chunk is anchored at the top
    assert _compare(["...", "c", "e"], actual) is not None
    assert _compare(["...", "d", "e"], actual) is None
    assert _compare(["a", "...", "x"], actual) is not None


# --- the architecture page stays true --------------------------------------------------------

ARCHITECTURE = ROOT / "docs" / "architecture.md"


def _section(text: str, title: str) -> str:
    """The body of the ``## title`` section of a Markdown page."""
    m = re.search(rf"^## {re.escape(title)}\n(.*?)(?=^## |\Z)", text, re.M | re.S)
    assert m, f"docs/architecture.md has no '## {title}' section"
    return m.group(1)


def _top_level_packages() -> set[str]:
    names = set()
    for p in (ROOT / "tamp").iterdir():
        if p.name == "models":  # model data (SDFs, weights), no code
            continue
        if p.is_dir() and (p / "__init__.py").exists():
            names.add(f"tamp.{p.name}")
        elif p.suffix == ".py" and p.name != "__init__.py":
            names.add(f"tamp.{p.stem}")
    return names


def _layer_table():
    """RANK and PEERS of tests/test_layers.py (loaded by path: it is the one source)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("_layers", ROOT / "tests" / "test_layers.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.RANK, module.PEERS


def _tiers(text: str) -> dict[str, int]:
    tiers = {}
    for line in _section(text, "Import arrows").splitlines():
        m = re.match(r"\|\s*(\d+)\s*\|(.*)\|\s*$", line)
        if m:
            for name in re.findall(r"`([\w.]+)`", m.group(2)):
                tiers[name] = int(m.group(1))
    return tiers


def test_architecture_names_every_top_level_package():
    text = ARCHITECTURE.read_text(encoding="utf-8")
    tiers = _tiers(text)
    missing = sorted(n for n in _top_level_packages() if f"`{n}`" not in text)
    assert not missing, f"docs/architecture.md does not name {missing}"
    untiered = sorted(_top_level_packages() - set(tiers))
    assert not untiered, f"docs/architecture.md's tier table lacks {untiered}"


def test_architecture_arrows_match_the_layer_ranks():
    """The tier table orders the packages exactly as RANK does, and the peer imports it
    allows within a tier are RANK's same-rank PEERS."""
    text = ARCHITECTURE.read_text(encoding="utf-8")
    tiers = _tiers(text)
    rank, peers = _layer_table()
    rank = {k: v for k, v in rank.items() if k != "tamp"}
    assert set(tiers) == set(rank), (
        f"tier table {sorted(set(tiers) - set(rank))} vs RANK {sorted(set(rank) - set(tiers))}"
    )
    wrong = [
        (a, b)
        for a in rank
        for b in rank
        if (tiers[a] < tiers[b]) != (rank[a] < rank[b])
        or (tiers[a] == tiers[b]) != (rank[a] == rank[b])
    ]
    assert not wrong, f"docs/architecture.md orders these pairs unlike RANK: {wrong[:5]}"
    stated = re.search(
        r"Imports allowed between packages of one tier:(.*?)\.\s*$",
        _section(text, "Import arrows"),
        re.M | re.S,
    )
    assert stated, "docs/architecture.md does not state the imports allowed within a tier"
    doc_peers = set(re.findall(r"`([\w.]+)` → `([\w.]+)`", stated.group(1)))
    assert doc_peers or stated.group(1).strip() == "none"
    same_rank = {(a, b) for a, b in peers if rank.get(a) == rank.get(b)}
    assert doc_peers == same_rank


# --- links and commands in the docs ----------------------------------------------------------

PAGES = [*DOCS, ROOT / "CHANGELOG.md"]
_LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")


def _slug(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    import unicodedata

    text = heading.strip().lower()
    kept = "".join(
        c
        for c in text
        if c in " -" or unicodedata.category(c)[0] in "LMN" or unicodedata.category(c) == "Pc"
    )
    return kept.replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    found: set[str] = set()
    in_block = False
    for line in page.read_text(encoding="utf-8").splitlines():
        if line.startswith("```"):
            in_block = not in_block
        elif not in_block and line.startswith("#"):
            slug = _slug(line.lstrip("#"))
            n, candidate = 0, slug
            while candidate in found:
                n += 1
                candidate = f"{slug}-{n}"
            found.add(candidate)
    return found


def _outside_code(text: str) -> str:
    """The page without its fenced blocks and inline code (links there are not links)."""
    text = re.sub(r"^```.*?^```", "", text, flags=re.M | re.S)
    return re.sub(r"`[^`\n]*`", "", text)


def _generated(dest: Path) -> bool:
    """A file of the site drawn at build time (docs/hooks.py's PICTURES), not committed."""
    docs = ROOT / "docs"
    if not dest.is_relative_to(docs):
        return False
    return dest.relative_to(docs).as_posix() in _hooks().PICTURES


def test_every_link_resolves():
    """Every relative link of README.md, CHANGELOG.md and docs/*.md names a file of the
    repository, and every #anchor a heading of the page it points to."""
    bad = []
    for page in PAGES:
        for target in _LINK.findall(_outside_code(page.read_text(encoding="utf-8"))):
            if re.match(r"[a-z]+:", target):  # http:, https:, mailto:
                continue
            path, _, anchor = target.partition("#")
            dest = (page.parent / path).resolve() if path else page
            if _generated(dest):
                continue
            if not dest.exists():
                bad.append(f"{page.name}: {target}: no such file")
            elif anchor and dest.suffix == ".md" and anchor not in _anchors(dest):
                bad.append(f"{page.name}: {target}: no such heading")
    assert not bad, "\n".join(bad)


def _quoted_commands() -> list[tuple[str, str]]:
    """Concrete ``tamp``/``tamp-verify`` command lines quoted in fenced blocks (``$``
    examples and plain lines alike; backslash continuations joined). Synopses with
    placeholders (``[...]``, ``a|b``, ``…``, ``KIND``) are skipped: they are not runnable."""
    found = []
    for page in DOCS:
        in_block, pending = False, ""
        for n, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
            if line.startswith("```"):
                in_block, pending = not in_block, ""
                continue
            if not in_block:
                continue
            text = pending + line.strip()
            pending = ""
            if text.endswith("\\"):
                pending = text[:-1] + " "
                continue
            text = text.removeprefix("$ ")
            if not re.match(r"tamp(-verify)? ", text):
                continue
            text = re.sub(r"\s+#.*$", "", text)
            if re.search(r"[\[\]|…<>{}]|\.\.\.|\b[A-Z]{3,}\b", text):
                continue
            found.append((f"{page.name}:{n}", text))
    return found


@pytest.mark.parametrize("where,command", _quoted_commands(), ids=lambda v: str(v)[:60])
def test_quoted_commands_parse(where, command):
    """Every concrete command the docs quote is accepted by the CLI's own parser (names and
    options exist, values have the right types); nothing is run."""
    from tamp.commands.main import COMMANDS, build_parser
    from tamp.commands.verify import make_parser

    argv = shlex.split(command)
    if argv[0] == "tamp":  # only the subcommand's own module: the others need not import
        assert argv[1] in COMMANDS, f"{where}: no subcommand {argv[1]!r}"
        parser = build_parser("tamp", [argv[1]], "tamp.commands")
    else:
        parser = make_parser()
    try:
        parser.parse_args(argv[1:])
    except SystemExit as exc:
        pytest.fail(f"{where}: `{command}` does not parse (exit {exc.code})")


# --- no bookkeeping in the code's words or the docs ------------------------------------------

#: References to the project's bookkeeping (seed files, issue numbers, notes kept outside the
#: repository): the code and the docs cite the papers by authors and section instead, and state
#: measured facts themselves.
BOOKKEEPING = re.compile(r"seed 00|issue [0-9]|FIELD_NOTES|\.\./shared|design card")


def test_no_bookkeeping_references():
    """``grep -rn "seed 00\\|issue [0-9]\\|FIELD_NOTES\\|\\.\\./shared" tamp README.md
    docs`` finds nothing (and no "design card")."""
    files = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*"))]
    files += sorted((ROOT / "tamp").rglob("*"))
    hits = []
    for path in files:
        if not path.is_file() or "__pycache__" in path.parts:
            continue
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:  # binary data (weights, images): no words to check
            continue
        for n, line in enumerate(text.splitlines(), 1):
            if BOOKKEEPING.search(line):
                hits.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()}")
    assert not hits, "\n".join(hits)


# --- the docs site (mkdocs.yml, docs/hooks.py) ----------------------------------------------


def _hooks():
    """docs/hooks.py, loaded by path (it is the site's build hook, not a package module)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("_docs_hooks", ROOT / "docs" / "hooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _nav_entries() -> list[str]:
    import yaml

    class _Loader(yaml.SafeLoader):  # mkdocs.yml may hold !!python/name tags: not used here
        pass

    config = yaml.load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"), Loader=_Loader)
    found: list[str] = []

    def walk(node):
        if isinstance(node, str):
            found.append(node)
        elif isinstance(node, list):
            for item in node:
                walk(item)
        elif isinstance(node, dict):
            for value in node.values():
                walk(value)

    walk(config["nav"])
    return found


def test_site_nav_names_existing_pages_and_every_page():
    """Each nav entry is a page of docs/ or a notebook; each page of docs/ is in the nav."""
    entries = _nav_entries()
    missing = [e for e in entries if not (ROOT / "docs" / e).exists() and not (ROOT / e).exists()]
    assert not missing, f"mkdocs.yml's nav names missing pages: {missing}"
    pages = {p.relative_to(ROOT / "docs").as_posix() for p in (ROOT / "docs").rglob("*.md")}
    assert not pages - set(entries), (
        f"pages not in mkdocs.yml's nav: {sorted(pages - set(entries))}"
    )
    notebooks = {f"notebooks/{p.name}" for p in (ROOT / "notebooks").glob("*.ipynb")}
    assert notebooks <= set(entries), (
        f"notebooks not in the nav: {sorted(notebooks - set(entries))}"
    )


def test_api_reference_names_importable_modules():
    """Every ``::: module`` of the API pages imports (a renamed module fails here, fast)."""
    import importlib

    names = []
    for page in sorted((ROOT / "docs" / "reference" / "api").glob("*.md")):
        names += re.findall(r"^::: ([\w.]+)$", page.read_text(encoding="utf-8"), re.M)
    assert len(names) >= 12
    for name in names:
        importlib.import_module(name)


def test_cli_reference_covers_every_command():
    """The generated CLI page has a section per subcommand, nested ones included, and a row
    per option."""
    from tamp.commands.main import COMMANDS
    from tamp.commands.verify import make_parser

    text = _hooks().cli_markdown()
    headings = re.findall(r"^#+ `([^`]+)`$", text, re.M)
    for name in COMMANDS:
        assert f"tamp {name}" in headings
    verify = make_parser()
    for action in verify._actions:
        for name in getattr(action, "choices", None) or {}:
            if isinstance(action.choices, dict):
                assert f"tamp-verify {name}" in headings
    assert "tamp simulate smp-mro" in headings and "tamp grasp train" in headings
    assert "| `--cost {distance,time,success}` | edge weights | `distance` |" in text


def test_formats_page_lists_every_format_and_its_keys():
    """The formats page names every `tamp schema` format, links its schema and tabulates
    its keys (read from the schema: the derived ones show the dataclasses' defaults)."""
    from tamp.commands.schema import FORMATS

    hooks = _hooks()
    table, fields = hooks.formats_markdown(), hooks.format_fields_markdown()
    for name in FORMATS:
        assert f"| `{name}` |" in table and f"[{name}.json](../schemas/{name}.json)" in table
        assert f'??? info "`{name}`:' in fields
    assert "| `executor.max_sim_time` | number &gt; 0 | `300.0` |" in fields
    assert set(hooks.schema_files()) == {f"schemas/{name}.json" for name in FORMATS}


@pytest.mark.slow
def test_site_builds_strictly(tmp_path):
    """`mkdocs build --strict` (what `make docs` runs) passes: no broken link, anchor or API
    reference; the generated CLI and API pages, the schemas and the notebooks are there."""
    import json

    site = tmp_path / "site"
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    assert "WARNING" not in proc.stderr, proc.stderr[-4000:]
    cli = (site / "reference" / "cli" / "index.html").read_text(encoding="utf-8")
    assert "tamp simulate smp-mro" in cli and "tamp-verify bt" in cli
    world = (site / "reference" / "api" / "world" / "index.html").read_text(encoding="utf-8")
    assert 'id="tamp.world.interface.World"' in world
    assert "observe" in world and "doc-signature" in world
    from tamp.commands.schema import FORMATS

    for name in FORMATS:
        assert json.loads((site / "schemas" / f"{name}.json").read_text())["title"]
    for nb in (ROOT / "notebooks").glob("*.ipynb"):
        assert (site / "notebooks" / nb.stem / "index.html").exists()
    assert (site / "guides" / "robot-adapter" / "index.html").exists()
    for picture in _hooks().PICTURES:
        assert (site / picture).read_text(encoding="utf-8").lstrip().startswith(("<?xml", "<svg"))
    assert (site / "examples" / "robot_adapter.py").exists()
