"""``tamp scenarios [KIND]``: the packaged scenario files, with their kind and what they are.

    tamp scenarios [KIND] [--json]

One line per file under ``tamp/scenarios``: the name a command takes (``tamp plan case2``,
``tamp simulate lots tower``), its kind (the file format of ``tamp schema``: demonstration,
lots-task, sim-smp, ...) and the start of its description (its ``description:`` field, else
its leading comment). ``KIND`` keeps one format; ``--json`` prints
``{"schema": 1, "scenarios": [{"name", "kind", "path", "description"}, ...]}``.
"""

from __future__ import annotations

import argparse
from dataclasses import asdict, dataclass
from pathlib import Path

from tamp.commands.output import print_json
from tamp.errors import InputError

#: Characters of a description that the listing keeps.
DESCRIPTION_SHOWN = 100


@dataclass(frozen=True)
class Packaged:
    """One packaged scenario file."""

    name: str
    kind: str
    path: str
    description: str


def register(sub: argparse._SubParsersAction) -> None:
    from tamp.commands.schema import FORMATS

    p = sub.add_parser(
        "scenarios",
        help="list the packaged scenario files (name, kind, description)",
        description=__doc__.splitlines()[0],
    )
    p.add_argument(
        "kind",
        metavar="KIND",
        nargs="?",
        help=f"only files of this kind: {', '.join(FORMATS)} (none: every file)",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=run)


def packaged(kind: str | None = None) -> list[Packaged]:
    """The files under ``tamp/scenarios`` of format ``kind`` (None: all), by kind and name."""
    from tamp.commands.schema import FORMATS
    from tamp.scenarios import ROOT

    if kind is not None and kind not in FORMATS:
        raise InputError(f"unknown kind {kind!r} (kinds: {', '.join(FORMATS)})", field="KIND")
    out = []
    for fmt in FORMATS.values():
        if kind is not None and fmt.name != kind:
            continue
        for path in fmt.example_files():
            if ROOT not in path.parents:
                continue  # a robot's domain file, not a scenario
            out.append(
                Packaged(
                    name=path.stem,
                    kind=fmt.name,
                    path=path.relative_to(ROOT.parent.parent).as_posix(),
                    description=description_of(path),
                )
            )
    return out


def description_of(path: Path) -> str:
    """The file's ``description:`` field, else its leading comment, on one line (at most
    `DESCRIPTION_SHOWN` characters)."""
    import yaml

    text = path.read_text(encoding="utf-8")
    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError:
        doc = None
    line = ""
    if isinstance(doc, dict) and isinstance(doc.get("description"), str):
        line = doc["description"].strip()
    else:
        comments = []
        for raw in text.splitlines():
            if not raw.startswith("#"):
                break
            comments.append(raw.lstrip("#").strip())
        line = " ".join(comments)
    line = " ".join(line.split())
    if len(line) > DESCRIPTION_SHOWN:
        line = line[: DESCRIPTION_SHOWN - 1].rstrip() + "…"
    return line


def run(args: argparse.Namespace) -> int:
    files = packaged(args.kind)
    if args.json:
        print_json({"scenarios": [asdict(f) for f in files]})  # with "schema": 1
        return 0
    width = max((len(f.name) for f in files), default=4)
    kinds = max((len(f.kind) for f in files), default=4)
    for f in files:
        print(f"{f.name:<{width}}  {f.kind:<{kinds}}  {f.description}")
    return 0
