"""The one typed loader: a YAML section read into a dataclass, driven by the dataclass itself.

A scenario type declares each file field once, with its default, bounds, choices and unit, as
a dataclass field made by `spec`; `load_dataclass` reads a `tamp.fileio.Fields` mapping into
it, recursing into nested dataclasses, tuples and mappings of them, and gives the strict
errors of `tamp.fileio` (``FILE: dotted.field: reason``, `InputError`, CLI exit 2): an
unknown key, a missing field, a wrong type, a value out of bounds. Relations between fields
(a period no shorter than the time step, a workspace within reach) are checked by the
dataclass's own ``check(self, f: Fields)`` method, called once the section is built, so a
file is refused before anything uses it. Fields made without `spec` (e.g. ``source``, a
run's sample) are not read from the file.

Example::

    @dataclass(frozen=True)
    class Control:
        period: float = spec(0.01, min=0.001, max=0.05, unit="s", help="skill tick")
        speed: float = spec(0.35, min=0.0, strict_min=True, max=1.0, unit="m/s")

    control = load_dataclass(Control, Fields(data, file).sub("control", {}))

`describe` lists every field with its default, bounds and unit (for docs and schemas).
"""

from __future__ import annotations

import dataclasses
import types
import typing
from collections.abc import Callable, Mapping
from dataclasses import MISSING, dataclass
from typing import Any, TypeVar

from tamp.errors import InputError, short_repr
from tamp.fileio import Fields, check_number

T = TypeVar("T")
_META = "tamp.schema"


@dataclass(frozen=True)
class Spec:
    """How one dataclass field is read from a file (see `spec`)."""

    key: str | None = None
    min: float | None = None
    max: float | None = None
    strict_min: bool = False
    choices: tuple[str, ...] | None = None
    unit: str = ""
    help: str = ""
    required: bool = False
    min_items: int = 0
    parse: Callable[[Any, Fields, str], Any] | None = None


def spec(
    default: Any = MISSING,
    *,
    key: str | None = None,
    min: float | None = None,
    max: float | None = None,
    strict_min: bool = False,
    choices: typing.Iterable[str] | None = None,
    unit: str = "",
    help: str = "",
    min_items: int = 0,
    parse: Callable[[Any, Fields, str], Any] | None = None,
) -> Any:
    """A dataclass field read from the file under ``key`` (default: the field's name).

    ``default``: the value when the key is absent (its one statement; lists become tuples,
    a dataclass class means "its own defaults"); no default: the key is required. ``min`` /
    ``max`` bound numbers (and every number of a tuple); ``strict_min`` makes ``min``
    exclusive; ``choices`` bounds strings; ``min_items`` bounds a tuple's length. ``parse``:
    ``parse(raw, parent_fields, key) -> value`` for a field no type rule covers (e.g. an
    event grammar); it must raise `InputError` naming the field.
    """
    meta = {
        _META: Spec(
            key=key,
            min=min,
            max=max,
            strict_min=strict_min,
            choices=None if choices is None else tuple(choices),
            unit=unit,
            help=help,
            required=default is MISSING,
            min_items=min_items,
            parse=parse,
        )
    }
    if default is MISSING:
        return dataclasses.field(metadata=meta)
    if isinstance(default, type) and dataclasses.is_dataclass(default):
        return dataclasses.field(default_factory=default, metadata=meta)
    if isinstance(default, list):
        default = tuple(default)
    if isinstance(default, dict):
        frozen = dict(default)
        return dataclasses.field(default_factory=lambda: dict(frozen), metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def schema_fields(cls: type) -> list[tuple[dataclasses.Field, Spec, Any]]:
    """(field, spec, resolved type) of each file field of dataclass ``cls``, in order."""
    hints = typing.get_type_hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        s = f.metadata.get(_META)
        if s is not None:
            out.append((f, s, hints[f.name]))
    return out


def keys_of(cls: type) -> set[str]:
    """The file keys dataclass ``cls`` reads."""
    return {s.key or f.name for f, s, _ in schema_fields(cls)}


def load_dataclass(cls: type[T], f: Fields, *, extra_keys: typing.Iterable[str] = ()) -> T:
    """Read mapping ``f`` into dataclass ``cls`` (module docstring); ``extra_keys`` are keys
    the caller reads itself (they are allowed, not read here)."""
    f.check_keys(keys_of(cls) | set(extra_keys))
    values: dict[str, Any] = {}
    for fld, s, tp in schema_fields(cls):
        key = s.key or fld.name
        if not f.has(key):
            if s.required:
                raise f.error(key, "missing field")
            continue  # the dataclass default
        raw = f.raw(key)
        values[fld.name] = s.parse(raw, f, key) if s.parse else _read(tp, raw, f, key, s)
    obj = cls(**values)
    check = getattr(obj, "check", None)
    if callable(check):
        check(f)
    return obj


def _read(tp: Any, raw: Any, f: Fields, key: str, s: Spec) -> Any:
    """One value of type ``tp`` at ``f``'s ``key``."""
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    path = f"{f.path}.{key}" if f.path else key
    if origin in (typing.Union, types.UnionType):
        inner = [a for a in args if a is not type(None)]
        if len(inner) == 1:
            return _read(inner[0], raw, f, key, s)
        raise TypeError(f"{path}: unions other than X | None need a parse function")
    if origin is typing.Literal:
        return _string(raw, f, key, tuple(args))
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        return load_dataclass(tp, f.sub(key))
    if tp is bool:
        return f.bool(key)
    if tp is int:
        value = f.int(key, min=None if s.min is None else int(s.min))
        if s.max is not None and value > s.max:
            raise f.error(key, f"must be <= {int(s.max)}, got {value}")
        return value
    if tp is float:
        return f.float(key, min=s.min, max=s.max, strict_min=s.strict_min)
    if tp is str:
        return _string(raw, f, key, s.choices)
    if origin is tuple:
        if not isinstance(raw, list | tuple):
            raise f.error(key, f"expected a list, got {short_repr(raw)}")
        fixed = not (len(args) == 2 and args[1] is Ellipsis)
        if fixed and len(raw) != len(args):
            what = "numbers" if all(a is float for a in args) else "items"
            raise f.error(key, f"expected a list of {len(args)} {what}, got {short_repr(raw)}")
        if len(raw) < s.min_items:
            raise f.error(key, f"expected at least {s.min_items} item(s), got {len(raw)}")
        items = []
        for i, item in enumerate(raw):
            item_tp = args[i] if fixed else args[0]
            items.append(_item(item_tp, item, f, path, i, s))
        return tuple(items)
    if origin in (dict, Mapping) or tp is dict:
        if not isinstance(raw, Mapping):
            raise f.error(key, f"expected a mapping, got {short_repr(raw)}")
        value_tp = args[1] if args else Any
        sub = f.sub(key)
        out = {}
        for k in raw:
            if not isinstance(k, str):
                raise sub.error(short_repr(k), "keys must be strings")
            if s.choices is not None and k not in s.choices:
                raise sub.error(k, f"unknown key (allowed: {', '.join(sorted(s.choices))})")
            out[k] = raw[k] if value_tp is Any else _read(value_tp, raw[k], sub, k, Spec())
        return out
    if tp is Any:
        return raw
    raise TypeError(f"{path}: no rule reads type {tp!r}: give the field a parse function")


def _item(tp: Any, raw: Any, f: Fields, path: str, i: int, s: Spec) -> Any:
    """Item ``i`` of a list field: a number within the field's bounds, a string, or a
    dataclass read from a mapping (errors name ``path[i]``)."""
    where = f"{path}[{i}]"
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        if not isinstance(raw, Mapping):
            raise InputError("expected a mapping", file=f.file, field=where)
        return load_dataclass(tp, Fields(raw, f.file, where))
    if tp is float:
        return check_number(raw, f.file, where, s.min, s.max, s.strict_min)
    if tp is int:
        if isinstance(raw, bool) or not isinstance(raw, int):
            raise InputError(
                f"expected an integer, got {short_repr(raw)}", file=f.file, field=where
            )
        return raw
    if tp is str:
        if not isinstance(raw, str) or not raw:
            raise InputError(
                f"expected a non-empty string, got {short_repr(raw)}", file=f.file, field=where
            )
        if s.choices is not None and raw not in s.choices:
            raise InputError(
                f"expected one of {sorted(s.choices)}, got {short_repr(raw)}",
                file=f.file,
                field=where,
            )
        return raw
    if tp is Any:
        return raw
    args = typing.get_args(tp)
    if typing.get_origin(tp) is tuple and all(a in (float, Ellipsis) for a in args):
        n = None if Ellipsis in args else len(args)  # a point: a list of numbers
        if not isinstance(raw, list | tuple) or (n is not None and len(raw) != n):
            size = "" if n is None else f"{n} "
            raise InputError(
                f"expected a list of {size}numbers, got {short_repr(raw)}", file=f.file, field=where
            )
        return tuple(
            check_number(v, f.file, f"{where}[{j}]", s.min, s.max, s.strict_min)
            for j, v in enumerate(raw)
        )
    raise TypeError(f"{where}: no rule reads list items of type {tp!r}")


def _string(raw: Any, f: Fields, key: str, choices: tuple | None) -> str:
    """A non-empty string (one of ``choices`` when given)."""
    return f.str(key, choices=choices)


def describe(cls: type, prefix: str = "") -> list[dict[str, Any]]:
    """Every file field of ``cls`` (nested sections flattened to dotted keys): key, type,
    default, bounds, choices, unit, help. For reference pages and schema exports."""
    rows = []
    for fld, s, tp in schema_fields(cls):
        key = prefix + (s.key or fld.name)
        if isinstance(tp, type) and dataclasses.is_dataclass(tp):
            rows.extend(describe(tp, key + "."))
            continue
        if fld.default is not MISSING:
            default = fld.default
        elif fld.default_factory is not MISSING:
            default = fld.default_factory()
        else:
            default = None
        rows.append(
            {
                "key": key,
                "type": getattr(tp, "__name__", str(tp)),
                "required": s.required,
                "default": default,
                "min": s.min,
                "max": s.max,
                "choices": list(s.choices) if s.choices else None,
                "unit": s.unit,
                "help": s.help,
            }
        )
    return rows


#: The JSON Schema dialect `json_schema` writes.
JSON_SCHEMA_DIALECT = "https://json-schema.org/draft/2020-12/schema"


def json_schema(
    cls: type,
    *,
    title: str | None = None,
    extra: Mapping[str, Mapping[str, Any]] | None = None,
    required_extra: typing.Iterable[str] = (),
) -> dict[str, Any]:
    """A JSON Schema (draft 2020-12) of the files `load_dataclass` reads into ``cls``, so that
    an editor can check a file while it is written.

    Derived from the same `spec` fields the loader reads: types, required keys, defaults,
    bounds (``strict_min`` as ``exclusiveMinimum``), choices, list lengths, units and help (as
    ``description``), unknown keys refused. ``extra``: schemas of the keys the caller reads
    itself (``extra_keys`` of `load_dataclass`, e.g. ``version``); ``required_extra`` names
    those that are required. A field read by a ``parse`` function of its own (a grammar no
    type rule covers) is described but accepts any value: the loader remains the judge, and
    relations between fields (a dataclass's ``check``) are not expressed.
    """
    doc: dict[str, Any] = {"$schema": JSON_SCHEMA_DIALECT}
    if title:
        doc["title"] = title
    doc.update(_object_schema(cls))
    for key, sub in (extra or {}).items():
        doc["properties"][key] = dict(sub)
    required = [*doc.get("required", []), *required_extra]
    if required:
        doc["required"] = required
    return doc


def _object_schema(cls: type) -> dict[str, Any]:
    """The schema of a mapping read into dataclass ``cls``."""
    props: dict[str, Any] = {}
    required = []
    for fld, s, tp in schema_fields(cls):
        key = s.key or fld.name
        sub = {} if s.parse else _type_schema(tp, s)
        words = " ".join(w for w in (s.help, f"[{s.unit}]" if s.unit else "") if w)
        if s.parse and words:
            words += " (a grammar of its own: see the loader)"
        if words:
            sub["description"] = words
        if s.required:
            required.append(key)
        else:
            default = _json_default(fld)
            if default is not None:
                sub["default"] = default
        props[key] = sub
    doc: dict[str, Any] = {"type": "object", "properties": props, "additionalProperties": False}
    if cls.__doc__:
        doc["description"] = " ".join(cls.__doc__.split())
    if required:
        doc["required"] = required
    return doc


def _json_default(fld: dataclasses.Field) -> Any:
    """The field's default as JSON (None when it has none or it is not plain data)."""
    import json

    if fld.default is not MISSING:
        value = fld.default
    elif fld.default_factory is not MISSING:
        value = fld.default_factory()
    else:
        return None
    if dataclasses.is_dataclass(value) or value is None:
        return None
    try:
        return json.loads(json.dumps(value))
    except (TypeError, ValueError):
        return None


def _type_schema(tp: Any, s: Spec) -> dict[str, Any]:
    """The schema of one value of type ``tp`` read under spec ``s`` (mirrors `_read`)."""
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        inner = [a for a in args if a is not type(None)]
        return _type_schema(inner[0], s) if len(inner) == 1 else {}
    if origin is typing.Literal:
        return {"enum": list(args)}
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        return _object_schema(tp)
    if tp is bool:
        return {"type": "boolean"}
    if tp is int or tp is float:
        out: dict[str, Any] = {"type": "integer" if tp is int else "number"}
        if s.min is not None:
            out["exclusiveMinimum" if s.strict_min and tp is float else "minimum"] = s.min
        if s.max is not None:
            out["maximum"] = s.max
        return out
    if tp is str:
        out = {"type": "string", "minLength": 1}
        if s.choices is not None:
            out["enum"] = list(s.choices)
        return out
    if origin is tuple:
        fixed = not (len(args) == 2 and args[1] is Ellipsis)
        if fixed:
            items = [_type_schema(a, s) for a in args]
            return {
                "type": "array",
                "prefixItems": items,
                "minItems": len(args),
                "maxItems": len(args),
            }
        out = {"type": "array", "items": _type_schema(args[0], s)}
        if s.min_items:
            out["minItems"] = s.min_items
        return out
    if origin in (dict, Mapping) or tp is dict:
        value_tp = args[1] if args else Any
        out = {"type": "object"}
        if value_tp is not Any:
            out["additionalProperties"] = _type_schema(value_tp, Spec())
        if s.choices is not None:
            out["propertyNames"] = {"enum": list(s.choices)}
        return out
    return {}
