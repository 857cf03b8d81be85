"""Build-time parts of the docs site (an MkDocs hook, named in ``mkdocs.yml``).

Nothing here is committed output: every build regenerates it from the code, so the site
cannot go stale.

- The CLI reference (``reference/cli.md``) is written from the argparse parsers themselves:
  `tamp.commands.main.build_parser` for ``tamp`` and `tamp.commands.verify.make_parser` for
  ``tamp-verify``, walked subcommand by subcommand.
- The file-format page (``reference/formats.md``) gets its table of formats, and the site
  gets one JSON Schema per format under ``schemas/``, from `tamp.commands.schema.FORMATS`
  (the registry ``tamp schema`` prints from).
- The landing page's pictures (`PICTURES`: Case 3's grown tree, a counterexample on its
  automaton) are drawn from the code (`picture_files`).
- The notebooks (``notebooks/*.ipynb``), the committed benchmark results
  (``benchmarks/results/``) and the examples (``examples/``) live outside ``docs/``; they are
  added to the site as they are (notebooks are rendered, not executed), and a page's relative
  link to one of them is rewritten to its place in the site.

A page asks for generated content with a marker line ``<!-- generated: NAME -->``.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import warnings
from pathlib import Path

# Spot's SWIG bindings warn on import (as in pytest's configuration, not ours to fix).
warnings.filterwarnings(
    "ignore", message="builtin type .* has no __module__ attribute", category=DeprecationWarning
)

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # the build runs from the repository root, installed or not
    sys.path.insert(0, str(ROOT))

#: Folders outside docs/ whose files are published as they are (glob patterns under ROOT).
PUBLISHED = ("notebooks/*.ipynb", "benchmarks/results/*", "examples/*.py")
MARKER = re.compile(r"^<!-- generated: ([\w-]+) -->$", re.M)
_LINK = re.compile(r"(\]\()([^)\s#]+)(#[^)\s]*)?(\))")


# --- the CLI reference -----------------------------------------------------------------------


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    """The subcommand parsers of ``parser``, in the order its help lists them."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _option_rows(parser: argparse.ArgumentParser) -> list[tuple[str, str, str]]:
    """(invocation, help, default) of every argument of ``parser`` except --help, in
    argparse's own words (its formatter expands ``%(default)s`` and metavars)."""
    formatter = parser._get_formatter()
    rows = []
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction | argparse._SubParsersAction):
            continue
        name = formatter._format_action_invocation(action)
        help_text = formatter._expand_help(action) if action.help else ""
        default = ""
        if (
            action.option_strings
            and action.nargs != 0
            and action.default not in (None, False, [], (), argparse.SUPPRESS)
            and not isinstance(action, argparse._VersionAction)
        ):
            default = f"`{action.default}`"
        rows.append((name, help_text, default))
    return rows


def _escape(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ").replace("<", "&lt;").replace(">", "&gt;")


def _command_section(
    path: list[str], parser: argparse.ArgumentParser, helps: dict[str, str]
) -> list[str]:
    """The Markdown of one command and, after it, of each of its subcommands."""
    name = " ".join(path)
    lines = [f"{'#' * min(len(path) + 1, 4)} `{name}`", ""]
    summary = parser.description or helps.get(name, "")
    if summary:
        lines += [summary.strip().splitlines()[0], ""]
    usage = parser.format_usage().strip().removeprefix("usage: ").splitlines()
    usage = [usage[0], *(line.removeprefix(" " * len("usage: ")) for line in usage[1:])]
    lines += ["```text", *usage, "```", ""]
    rows = _option_rows(parser)
    if rows:
        lines += ["| argument | meaning | default |", "|---|---|---|"]
        lines += [f"| `{_escape(a)}` | {_escape(h)} | {d} |" for a, h, d in rows]
        lines.append("")
    children = _subcommands(parser)
    sub_help = {}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            sub_help = {f"{name} {c.dest}": c.help or "" for c in action._choices_actions}
    for child, child_parser in children.items():
        lines += _command_section([*path, child], child_parser, sub_help)
    return lines


def cli_markdown() -> str:
    """The CLI reference: every command and subcommand of ``tamp`` and ``tamp-verify``."""
    from tamp.commands.main import COMMANDS, build_parser
    from tamp.commands.verify import make_parser

    os.environ["COLUMNS"] = "100"  # argparse wraps usage lines at the terminal's width
    lines: list[str] = []
    for parser in (build_parser("tamp", COMMANDS, "tamp.commands"), make_parser()):
        lines += _command_section([parser.prog], parser, {})
    return "\n".join(lines)


# --- file formats ----------------------------------------------------------------------------


def formats_markdown() -> str:
    """One row per file format: its name for ``tamp schema``, what it is, its loader, the
    packaged examples, and a link to the JSON Schema the build writes."""
    from tamp.commands.schema import FORMATS

    lines = [
        "| format (`tamp schema NAME`) | what | read by | packaged files | schema |",
        "|---|---|---|---|---|",
    ]
    for name, fmt in FORMATS.items():
        folders: dict[str, list[str]] = {}
        for path in fmt.example_paths():
            folder, _, file_name = path.rpartition("/")
            folders.setdefault(folder, []).append(file_name)
        examples = "; ".join(
            f"`{folder}/`: " + ", ".join(names) for folder, names in folders.items()
        )
        lines.append(
            f"| `{name}` | {fmt.title} | `{fmt.loader}` | {examples} | "
            f"[{name}.json](../schemas/{name}.json) |"
        )
    return "\n".join(lines)


def _type_words(node: dict) -> str:
    """A schema node's type in a few words (``number > 0``, ``list of 3 numbers``)."""
    if "enum" in node:
        return "one of " + ", ".join(f"`{v}`" for v in node["enum"])
    if "const" in node:
        return f"`{node['const']}`"
    kind = node.get("type", "any")
    if kind == "array":
        n = node.get("minItems")
        items = node.get("items") or (node.get("prefixItems") or [{}])[0]
        size = f"{n} " if n is not None and n == node.get("maxItems") else ""
        words = _type_words(items)
        for kind in ("number", "string", "integer", "boolean"):  # plural: "3 numbers"
            if words.startswith(kind):
                words = kind + "s" + words[len(kind) :]
        return f"list of {size}{words}"
    if kind == "object" and "properties" not in node:
        value = node.get("additionalProperties")
        return f"mapping to {_type_words(value)}" if isinstance(value, dict) else "mapping"
    bounds = []
    if "minimum" in node:
        bounds.append(f">= {node['minimum']:g}")
    if "exclusiveMinimum" in node:
        bounds.append(f"> {node['exclusiveMinimum']:g}")
    if "maximum" in node:
        bounds.append(f"<= {node['maximum']:g}")
    return " ".join([kind, *bounds]) if kind != "any" else "any (its own grammar)"


def _schema_rows(node: dict, prefix: str = "") -> list[str]:
    """One table row per key of a JSON Schema object, nested sections as dotted keys."""
    rows = []
    required = set(node.get("required", ()))
    for key, sub in node.get("properties", {}).items():
        name = f"{prefix}{key}"
        if sub.get("type") == "object" and "properties" in sub:
            rows += _schema_rows(sub, name + ".")
            continue
        if sub.get("type") == "array" and "properties" in sub.get("items", {}):
            rows += _schema_rows(sub["items"], name + "[].")
            continue
        default = "required" if key in required else ""
        if "default" in sub:
            default = f"`{json.dumps(sub['default'])}`"
        words = _escape(sub.get("description", ""))
        rows.append(f"| `{name}` | {_escape(_type_words(sub))} | {default} | {words} |")
    return rows


def format_fields_markdown() -> str:
    """Every format's keys (from its JSON Schema), one collapsed table per format."""
    from tamp.commands.schema import FORMATS

    out = []
    for name, fmt in FORMATS.items():
        out += [f'??? info "`{name}`: {fmt.title}"', ""]
        table = ["| key | type | default | meaning |", "|---|---|---|---|"]
        table += _schema_rows(fmt.schema())
        out += [f"    {line}" for line in table] + [""]
    return "\n".join(out)


def schema_files() -> dict[str, str]:
    """``schemas/NAME.json`` → its text, for every format."""
    from tamp.commands.schema import FORMATS

    return {
        f"schemas/{name}.json": json.dumps(fmt.schema(), indent=2) + "\n"
        for name, fmt in FORMATS.items()
    }


#: Pictures drawn at build time, by their place in the site (see `picture_files`).
PICTURES = ("images/generated/case3_tree.svg", "images/generated/trace.svg")

#: The counterexample drawn for the landing page (as ``tamp-verify trace --finite --svg``).
TRACE = ("G !bad & F done", "a; bad; done")


def picture_files() -> dict[str, str]:
    """The pictures of the landing page, drawn from the code when the site is built: the
    tree SMP-MRO Case 3 grows (``tamp plan case3.yaml --execute --bt-dot tree.svg``) and a
    counterexample on its automaton (``tamp-verify trace ... --svg trace.svg``)."""
    from tamp.bt.export import to_dot
    from tamp.bt.run import execute_plan
    from tamp.demo import load_demonstration
    from tamp.pictures import render
    from tamp.rg import plan
    from tamp.scenarios import resolve
    from tamp.verification.draw import trace_dot
    from tamp.verification.words import parse_word

    demo = load_demonstration(resolve("case3.yaml"))
    report = execute_plan(demo, plan(demo).c_goal, events=demo.appear)
    formula, word = TRACE
    trace = trace_dot(formula, parse_word(word), finite=True, title=f"{formula}  on  {word}")
    drawn = (to_dot(report.executor.root), trace)
    return {uri: render(dot, "svg").decode() for uri, dot in zip(PICTURES, drawn, strict=True)}


GENERATED = {
    "cli": cli_markdown,
    "formats": formats_markdown,
    "format-fields": format_fields_markdown,
}


# --- MkDocs events ---------------------------------------------------------------------------


def on_files(files, config):
    """Add the published files from outside docs/ and the generated schemas."""
    from mkdocs.structure.files import File

    for pattern in PUBLISHED:
        for path in sorted(ROOT.glob(pattern)):
            if path.is_file() and files.get_file_from_path(path.relative_to(ROOT).as_posix()):
                continue
            if path.is_file():
                files.append(
                    File(
                        path.relative_to(ROOT).as_posix(),
                        src_dir=str(ROOT),
                        dest_dir=config["site_dir"],
                        use_directory_urls=config["use_directory_urls"],
                    )
                )
    for uri, text in {**schema_files(), **picture_files()}.items():
        files.append(File.generated(config, uri, content=text))
    return files


# Run before mkdocs-jupyter's on_files (default priority 0), which wraps the notebooks.
on_files.mkdocs_priority = 100  # type: ignore[attr-defined]


def on_page_markdown(markdown: str, page, config, files) -> str:
    """Fill ``<!-- generated: NAME -->`` markers; point links to published files outside
    docs/ at their place in the site."""

    def fill(m: re.Match) -> str:
        name = m.group(1)
        if name not in GENERATED:
            raise KeyError(f"{page.file.src_uri}: no generated content named {name!r}")
        return GENERATED[name]()

    markdown = MARKER.sub(fill, markdown)
    docs_dir = Path(config["docs_dir"]).resolve()
    page_dir = (docs_dir / page.file.src_uri).parent

    def relink(m: re.Match) -> str:
        target = m.group(2)
        if re.match(r"[a-z]+:", target):
            return m.group(0)
        dest = (page_dir / target).resolve()
        try:
            dest.relative_to(docs_dir)
            return m.group(0)  # inside docs/: MkDocs resolves it
        except ValueError:
            pass
        try:
            uri = dest.relative_to(ROOT).as_posix()
        except ValueError:
            return m.group(0)
        if files.get_file_from_path(uri) is None:
            return m.group(0)  # not published: MkDocs reports the broken link
        site_rel = os.path.relpath(uri, Path(page.file.src_uri).parent.as_posix() or ".")
        return f"{m.group(1)}{site_rel}{m.group(3) or ''}{m.group(4)}"

    return _LINK.sub(relink, markdown)
