"""Traces of sets of atomic propositions: finite words and lassos (prefix + cycle).

A *letter* is the set of propositions that are true at one position; every other
proposition is false there (a full valuation: a letter that names only some of them is
not "don't care", which would accept traces too easily).

Two input forms:

- word syntax (``--word``), close to Spot's ``parse_word``:
  ``p1 & !p2; p2; {}; cycle{p1; !p1}``. Letters are separated by ``;``; a letter is a
  conjunction of literals ``p`` / ``!p`` (names: identifiers or double-quoted strings) or
  ``{}`` for "nothing true"; ``cycle{…}`` (last) makes the word a lasso, repeated forever.
  A negative literal only documents intent: unnamed propositions are false anyway.
- trace files (YAML or JSON, ``version: 1``)::

      version: 1
      trace:               # the letters, in order (the prefix of a lasso)
        - [p1]             # a list of the propositions that are true ...
        - "p2 & !p1"       # ... or one letter in word syntax
        - []
      cycle:               # optional: repeated forever (infinite-word semantics)
        - [p2]
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from tamp.errors import InputError
from tamp.fileio import Fields, load_yaml

Letter = frozenset[str]

_NAME = re.compile(r'\s*(!*)\s*([A-Za-z_][\w.]*|"[^"]*")\s*$')


@dataclass(frozen=True)
class Word:
    """A finite word (``cycle is None``) or a lasso ``prefix · cycle^ω``."""

    prefix: tuple[Letter, ...]
    cycle: tuple[Letter, ...] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "prefix", tuple(frozenset(x) for x in self.prefix))
        if self.cycle is not None:
            if len(self.cycle) == 0:
                raise ValueError("a lasso needs a non-empty cycle")
            object.__setattr__(self, "cycle", tuple(frozenset(x) for x in self.cycle))

    @staticmethod
    def finite(letters: Iterable[Iterable[str]]) -> Word:
        return Word(tuple(frozenset(x) for x in letters), None)

    @staticmethod
    def lasso(prefix: Iterable[Iterable[str]], cycle: Iterable[Iterable[str]]) -> Word:
        return Word(tuple(frozenset(x) for x in prefix), tuple(frozenset(x) for x in cycle))

    @property
    def is_lasso(self) -> bool:
        return self.cycle is not None

    def __len__(self) -> int:
        return len(self.prefix) + (len(self.cycle) if self.cycle else 0)

    def letter(self, i: int) -> Letter:
        """Letter at position ``i`` of the (unrolled) word."""
        if i < len(self.prefix):
            return self.prefix[i]
        if self.cycle is None:
            raise IndexError(i)
        return self.cycle[(i - len(self.prefix)) % len(self.cycle)]

    def props(self) -> set[str]:
        out: set[str] = set()
        for x in self.prefix + (self.cycle or ()):
            out |= x
        return out

    def format(self, aps: Iterable[str] | None = None) -> str:
        """Word syntax; with ``aps`` every letter is written as a full valuation over them."""
        aps = sorted(aps) if aps is not None else None

        def one(x: Letter) -> str:
            if aps is None:
                return " & ".join(_quote(p) for p in sorted(x)) if x else "{}"
            if not aps:
                return "{}"
            return " & ".join(_quote(p) if p in x else "!" + _quote(p) for p in aps)

        parts = [one(x) for x in self.prefix]
        if self.cycle is not None:
            parts.append("cycle{" + "; ".join(one(x) for x in self.cycle) + "}")
        return "; ".join(parts) if parts else "(empty)"

    def to_json(self) -> dict:
        out: dict = {"trace": [sorted(x) for x in self.prefix]}
        if self.cycle is not None:
            out["cycle"] = [sorted(x) for x in self.cycle]
        return out

    def __str__(self) -> str:
        return self.format()


def _quote(name: str) -> str:
    return name if re.fullmatch(r"[A-Za-z_][\w.]*", name) else f'"{name}"'


def parse_letter(text: str, *, field: str = "word", file: str | None = None) -> Letter:
    """One letter: ``p & !q & "r s"`` or ``{}``; returns the set of true propositions."""
    t = text.strip()
    if t in ("{}", ""):
        if t == "":
            raise InputError(
                "empty letter (write {} for a letter where nothing is true)", file=file, field=field
            )
        return frozenset()
    true: set[str] = set()
    false: set[str] = set()
    for lit in _split(t, "&"):
        m = _NAME.match(lit)
        if not m:
            raise InputError(
                f"letter {text.strip()!r}: {lit.strip()!r} is not a proposition or its "
                "negation (a letter is a conjunction of literals, e.g. 'p1 & !p2', or {})",
                file=file,
                field=field,
            )
        bangs, name = m.group(1), m.group(2).strip('"')
        if name in ("true", "false", "0", "1"):
            raise InputError(
                f"letter {text.strip()!r}: {name!r} is not a proposition", file=file, field=field
            )
        (false if len(bangs) % 2 else true).add(name)
    both = true & false
    if both:
        raise InputError(
            f"letter {text.strip()!r} contradicts itself on {sorted(both)}", file=file, field=field
        )
    return frozenset(true)


def _split(text: str, sep: str) -> list[str]:
    """Split on ``sep`` outside double quotes and braces."""
    out, cur, depth, quoted = [], [], 0, False
    for ch in text:
        if ch == '"':
            quoted = not quoted
        elif not quoted and ch == "{":
            depth += 1
        elif not quoted and ch == "}":
            depth -= 1
        if ch == sep and not quoted and depth == 0:
            out.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    out.append("".join(cur))
    return out


def parse_word(text: str, *, field: str = "--word", file: str | None = None) -> Word:
    """Parse word syntax (see module docstring); an empty string is the empty finite word."""
    t = text.strip()
    if t.count('"') % 2:
        raise InputError(f"unbalanced quote in {text!r}", file=file, field=field)
    cycle: list[Letter] | None = None
    parts = [p.strip() for p in _split(t, ";")] if t else []
    if parts and parts[-1] == "":
        parts.pop()  # a trailing ';' is harmless
    letters: list[Letter] = []
    for i, part in enumerate(parts):
        m = re.fullmatch(r"cycle\s*\{(.*)\}", part, flags=re.S)
        if m:
            if i != len(parts) - 1:
                raise InputError("cycle{…} must come last", file=file, field=field)
            inner = [p.strip() for p in _split(m.group(1), ";") if p.strip()]
            if not inner:
                raise InputError("cycle{} needs at least one letter", file=file, field=field)
            cycle = [
                parse_letter(p, field=f"{field}: cycle letter {j}", file=file)
                for j, p in enumerate(inner)
            ]
        else:
            if "{" in part.replace("{}", "") or "}" in part.replace("{}", ""):
                raise InputError(f"letter {i}: {part!r} does not parse", file=file, field=field)
            letters.append(parse_letter(part, field=f"{field}: letter {i}", file=file))
    return Word(tuple(letters), tuple(cycle) if cycle is not None else None)


def _file_letter(item: object, file: str, field: str) -> Letter:
    if isinstance(item, str):
        return parse_letter(item, field=field, file=file)
    if isinstance(item, Sequence) and not isinstance(item, str | bytes):
        names = set()
        for j, p in enumerate(item):
            if not isinstance(p, str) or not p:
                raise InputError(
                    f"expected a proposition name, got {p!r}", file=file, field=f"{field}[{j}]"
                )
            names.add(p)
        return frozenset(names)
    raise InputError(
        f"a letter is a list of true propositions or a string like 'p1 & !p2', got {item!r}",
        file=file,
        field=field,
    )


def load_trace(path: str | Path) -> Word:
    """Load a trace file (YAML or JSON, see module docstring); errors name file and field."""
    data, file = load_yaml(path, kind="trace")
    f = Fields(data, file)
    f.check_keys({"version", "trace", "cycle"})
    raw = f.raw("trace")
    if not isinstance(raw, list):
        raise f.error("trace", "expected a list of letters")
    prefix = [_file_letter(x, file, f"trace[{i}]") for i, x in enumerate(raw)]
    cycle = None
    if f.has("cycle"):
        rc = f.raw("cycle")
        if not isinstance(rc, list) or not rc:
            raise f.error("cycle", "expected a non-empty list of letters")
        cycle = [_file_letter(x, file, f"cycle[{i}]") for i, x in enumerate(rc)]
    return Word(tuple(prefix), tuple(cycle) if cycle is not None else None)
