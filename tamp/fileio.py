"""Strict loading of the versioned YAML interchange files.

Every loader in the project goes through `load_yaml` and `Fields`, so unknown keys, missing
fields and wrong types all produce the same kind of message: ``FILE: dotted.field: reason``.
What is refused before any field is read: duplicate keys (YAML would keep the last one
silently), more than `MAX_ALIASES` aliases or `MAX_DEPTH` levels of nesting (an alias bomb
would otherwise hang the loader), files over `MAX_BYTES`, and a ``version`` that is not the
integer 1 (``true`` is not 1). Numbers must be finite and, unless a field says otherwise,
within ±`MAX_MAGNITUDE`; messages quote at most a short prefix of a bad value.

The JSON documents the project writes (every ``--json`` output, the MR link's plan result)
carry ``"schema": JSON_SCHEMA`` first (`with_schema`).
"""

from __future__ import annotations

import gc
import math
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Literal, overload

import yaml
from yaml.composer import Composer
from yaml.constructor import SafeConstructor
from yaml.resolver import Resolver

from tamp.errors import InputError, short_repr

SUPPORTED_VERSIONS = (1,)
MAX_BYTES = 16 * 1024 * 1024
MAX_ALIASES = 1000
MAX_DEPTH = 64
#: Default bound on any number of a file: far beyond any workcell (metres, seconds, Hz).
MAX_MAGNITUDE = 1e6


class _LimitError(Exception):
    """Raised by the strict loader; `load_yaml` turns it into an `InputError`."""


class _Strict:
    """Duplicate keys refused, aliases and nesting bounded: the checks of both loaders.

    Mixed into a loader whose composer is PyYAML's Python `Composer` (the C composer of
    libyaml recurses without a limit: a file nested 100,000 deep crashes the process).
    """

    _aliases = 0
    _depth = 0

    def compose_node(self, parent, index):  # type: ignore[no-untyped-def]
        if self.check_event(yaml.AliasEvent):  # type: ignore[attr-defined]
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                raise _LimitError(f"more than {MAX_ALIASES} YAML aliases")
        self._depth += 1
        if self._depth > MAX_DEPTH:
            raise _LimitError(f"nested deeper than {MAX_DEPTH} levels")
        try:
            return Composer.compose_node(self, parent, index)  # type: ignore[arg-type]
        finally:
            self._depth -= 1

    def construct_mapping(self, node, deep=False):  # type: ignore[no-untyped-def]
        seen: set = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)  # type: ignore[attr-defined]
            try:
                duplicate = key in seen
            except TypeError:  # an unhashable key: the base class reports it
                break
            if duplicate:
                line = key_node.start_mark.line + 1
                raise _LimitError(f"duplicate key {short_repr(key)} (line {line})")
            seen.add(key)
        return SafeConstructor.construct_mapping(self, node, deep=deep)  # type: ignore[arg-type]


class _StrictLoader(_Strict, yaml.SafeLoader):
    """PyYAML's pure-Python safe loader with the strict checks (when libyaml is absent)."""


_LOADER: type = _StrictLoader
if getattr(yaml, "__with_libyaml__", False):  # pragma: no branch - libyaml is usual
    from yaml._yaml import CParser

    class _CStrictLoader(_Strict, CParser, Composer, SafeConstructor, Resolver):  # type: ignore[misc]
        """libyaml's scanner and parser (C, ~10x faster), PyYAML's composer and safe
        constructor (Python) with the strict checks: the same documents, the same refusals."""

        def __init__(self, stream) -> None:  # type: ignore[no-untyped-def]
            CParser.__init__(self, stream)
            Composer.__init__(self)
            SafeConstructor.__init__(self)
            Resolver.__init__(self)

        # CParser's own versions compose in C without the checks: take the Python ones
        # (the stubs type these for a Composer `self`; the loader is one)
        get_single_node = Composer.get_single_node  # pyright: ignore[reportAssignmentType]
        check_node = Composer.check_node  # pyright: ignore[reportAssignmentType]
        get_node = Composer.get_node  # pyright: ignore[reportAssignmentType]

    _LOADER = _CStrictLoader

for _cls in {_StrictLoader, _LOADER}:
    _cls.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _Strict.construct_mapping)


def parse_yaml_text(text: str, *, pure_python: bool = False) -> Any:
    """Parse one YAML document strictly (C scanner where libyaml exists, else pure Python).

    Raises `_LimitError` (duplicate key, aliases, nesting) or `yaml.YAMLError`. The cyclic
    garbage collector is paused meanwhile: the tree of fresh nodes and values has no cycles
    to collect, and full collections over it made a 20,000-step file cost 2.3 times as much
    per step as a 5,000-step one (parsing is linear without them).
    """
    loader = _StrictLoader if pure_python else _LOADER
    with gc_paused():
        return yaml.load(text, Loader=loader)  # noqa: S506 - safe constructors only


@contextmanager
def gc_paused() -> Iterator[None]:
    """Pause Python's cyclic garbage collector (if it was on) for a burst of allocations."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def load_yaml(path: str | Path, *, kind: str) -> tuple[dict[str, Any], str]:
    """Read a YAML mapping with a supported ``version``; returns (data, file name for errors)."""
    p = Path(path)
    name = str(path)
    if not p.is_file():
        raise InputError(f"{kind} file not found", file=name)
    if p.stat().st_size > MAX_BYTES:
        raise InputError(f"larger than {MAX_BYTES // (1024 * 1024)} MiB", file=name)
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"not a UTF-8 text file (byte {exc.start})", file=name) from None
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror}", file=name) from None
    try:
        data = parse_yaml_text(text)
    except _LimitError as exc:
        raise InputError(str(exc), file=name) from None
    except RecursionError:
        raise InputError(f"nested deeper than {MAX_DEPTH} levels", file=name) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark else ""
        raise InputError(f"not valid YAML{where}", file=name) from None
    if not isinstance(data, dict):
        raise InputError(f"a {kind} file must be a YAML mapping", file=name)
    check_version(data, name)
    return data, name


def check_version(data: dict[str, Any], source: str) -> None:
    """``data["version"]`` is present and one the project reads (the integer 1: ``true``
    is not 1); else `InputError` naming ``source`` and the field."""
    version = data.get("version")
    if version is None:
        raise InputError("missing field", file=source, field="version")
    if isinstance(version, bool) or version not in SUPPORTED_VERSIONS:
        raise InputError(
            f"unsupported version {short_repr(version)} (supported: {list(SUPPORTED_VERSIONS)})",
            file=source,
            field="version",
        )


class Fields:
    """A view of one YAML mapping that knows its file and dotted path, for precise errors."""

    def __init__(self, data: Any, file: str, path: str = ""):
        self.file = file
        self.path = path
        if not isinstance(data, Mapping):
            raise InputError("expected a mapping", file=file, field=path or "<root>")
        self.data = data

    def _field(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def error(self, key: str | None, message: str) -> InputError:
        return InputError(message, file=self.file, field=self._field(key) if key else self.path)

    def check_keys(self, allowed: Iterable[str]) -> None:
        allowed = set(allowed)
        for key in self.data:
            if key not in allowed:
                raise self.error(
                    short_repr(str(key), 40).strip("'"),
                    f"unknown key (allowed: {', '.join(sorted(allowed))})",
                )

    def has(self, key: str) -> bool:
        return key in self.data and self.data[key] is not None

    def raw(self, key: str, default: Any = ..., *, required: bool = True) -> Any:
        if key not in self.data or self.data[key] is None:
            if default is not ...:
                return default
            if required:
                raise self.error(key, "missing field")
            return None
        return self.data[key]

    def sub(self, key: str, default: Any = ...) -> Fields:
        return Fields(self.raw(key, default), self.file, self._field(key))

    def items(self, key: str, default: Any = ...) -> list[Fields | Any]:
        """A list field; mapping entries come back as `Fields` with indexed paths."""
        value = self.raw(key, default)
        if not isinstance(value, list):
            raise self.error(key, "expected a list")
        out: list[Fields | Any] = []
        for i, item in enumerate(value):
            path = f"{self._field(key)}[{i}]"
            out.append(Fields(item, self.file, path) if isinstance(item, Mapping) else item)
        return out

    def str(self, key: str, default: Any = ..., *, choices: Iterable[str] | None = None) -> str:
        value = self.raw(key, default)
        if not isinstance(value, str) or not value:
            raise self.error(key, f"expected a non-empty string, got {short_repr(value)}")
        if choices is not None and value not in set(choices):
            raise self.error(key, f"expected one of {sorted(choices)}, got {short_repr(value)}")
        return value

    def float(
        self,
        key: str,
        default: Any = ...,
        *,
        min: float | None = None,
        max: float | None = None,
        strict_min: bool = False,
    ) -> float:
        value = self.raw(key, default)
        return check_number(value, self.file, self._field(key), min, max, strict_min)

    def int(self, key: str, default: Any = ..., *, min: int | None = None) -> int:
        value = self.raw(key, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"expected an integer, got {short_repr(value)}")
        if abs(value) > 10**12:
            raise self.error(key, f"out of range: {short_repr(value)}")
        if min is not None and value < min:
            raise self.error(key, f"must be >= {min}, got {value}")
        return value

    def bool(self, key: str, default: Any = ...) -> bool:
        value = self.raw(key, default)
        if not isinstance(value, bool):
            raise self.error(key, f"expected true or false, got {short_repr(value)}")
        return value

    @overload
    def vector(self, key: str, n: Literal[2], default: Any = ...) -> tuple[float, float]: ...
    @overload
    def vector(self, key: str, n: Literal[3], default: Any = ...) -> tuple[float, float, float]: ...
    @overload
    def vector(self, key: str, n: int, default: Any = ...) -> tuple[float, ...]: ...
    def vector(self, key: str, n: int, default: Any = ...) -> tuple[float, ...]:
        """`check_vector` of field ``key``: exactly ``n`` finite numbers."""
        value = self.raw(key, default)
        return check_vector(value, n, self.file, self._field(key))


def check_number(
    value: Any,
    file: str,
    field: str,
    min: float | None = None,
    max: float | None = None,
    strict_min: bool = False,
) -> float:
    """A finite real number within bounds, or an `InputError` naming file and field.

    Without ``min``/``max`` the number must lie within ±`MAX_MAGNITUDE`.
    """
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"expected a number, got {short_repr(value)}", file=file, field=field)
    if not math.isfinite(value) or abs(value) > MAX_MAGNITUDE:
        raise InputError(
            f"expected a finite number within ±{MAX_MAGNITUDE:g}, got {short_repr(value)}",
            file=file,
            field=field,
        )
    if min is not None and (value <= min if strict_min else value < min):
        op = ">" if strict_min else ">="
        raise InputError(f"must be {op} {min}, got {value}", file=file, field=field)
    if max is not None and value > max:
        raise InputError(f"must be <= {max}, got {value}", file=file, field=field)
    return float(value)


@overload
def check_vector(value: Any, n: Literal[2], file: str, field: str) -> tuple[float, float]: ...
@overload
def check_vector(
    value: Any, n: Literal[3], file: str, field: str
) -> tuple[float, float, float]: ...
@overload
def check_vector(value: Any, n: int, file: str, field: str) -> tuple[float, ...]: ...
def check_vector(value: Any, n: int, file: str, field: str) -> tuple[float, ...]:
    """A list of exactly ``n`` finite numbers (typed as an ``n``-tuple for 2 and 3)."""
    if not isinstance(value, list | tuple) or len(value) != n:
        raise InputError(
            f"expected a list of {n} numbers, got {short_repr(value)}", file=file, field=field
        )
    return tuple(check_number(v, file, f"{field}[{i}]") for i, v in enumerate(value))


#: Version of the JSON documents the project writes (the ``"schema"`` key of each): raised
#: when a document changes in a way a reader must know about (a key removed or renamed).
JSON_SCHEMA = 1


def with_schema(payload: Any) -> Any:
    """``payload`` with ``"schema"`` first when it is a mapping that does not say it yet."""
    if isinstance(payload, dict) and "schema" not in payload:
        return {"schema": JSON_SCHEMA, **payload}
    return payload
