"""Strict loading of the versioned YAML interchange files.

Every loader in the project goes through `load_yaml` and `Fields`, so unknown keys, missing
fields and wrong types all produce the same kind of message: ``FILE: dotted.field: reason``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import yaml

from tamp.errors import InputError

SUPPORTED_VERSIONS = (1,)


def load_yaml(path: str | Path, *, kind: str) -> tuple[dict[str, Any], str]:
    """Read a YAML mapping with a supported ``version``; returns (data, file name for errors)."""
    p = Path(path)
    name = str(path)
    if not p.is_file():
        raise InputError(f"{kind} file not found", file=name)
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"not a UTF-8 text file (byte {exc.start})", file=name) from None
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror}", file=name) from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark else ""
        raise InputError(f"not valid YAML{where}", file=name) from None
    if not isinstance(data, dict):
        raise InputError(f"a {kind} file must be a YAML mapping", file=name)
    version = data.get("version")
    if version is None:
        raise InputError("missing field", file=name, field="version")
    if version not in SUPPORTED_VERSIONS:
        raise InputError(
            f"unsupported version {version!r} (supported: {list(SUPPORTED_VERSIONS)})",
            file=name,
            field="version",
        )
    return data, name


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
                raise self.error(str(key), f"unknown key (allowed: {', '.join(sorted(allowed))})")

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
            raise self.error(key, f"expected a non-empty string, got {value!r}")
        if choices is not None and value not in set(choices):
            raise self.error(key, f"expected one of {sorted(choices)}, got {value!r}")
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
            raise self.error(key, f"expected an integer, got {value!r}")
        if min is not None and value < min:
            raise self.error(key, f"must be >= {min}, got {value}")
        return value

    def bool(self, key: str, default: Any = ...) -> bool:
        value = self.raw(key, default)
        if not isinstance(value, bool):
            raise self.error(key, f"expected true or false, got {value!r}")
        return value

    def vector(self, key: str, n: int, default: Any = ...) -> tuple[float, ...]:
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
    """A finite real number within bounds, or an `InputError` naming file and field."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(f"expected a finite number, got {value!r}", file=file, field=field)
    if min is not None and (value <= min if strict_min else value < min):
        op = ">" if strict_min else ">="
        raise InputError(f"must be {op} {min}, got {value}", file=file, field=field)
    if max is not None and value > max:
        raise InputError(f"must be <= {max}, got {value}", file=file, field=field)
    return float(value)


def check_vector(value: Any, n: int, file: str, field: str) -> tuple[float, ...]:
    """A list of exactly ``n`` finite numbers."""
    if not isinstance(value, list | tuple) or len(value) != n:
        raise InputError(f"expected a list of {n} numbers, got {value!r}", file=file, field=field)
    return tuple(check_number(v, file, f"{field}[{i}]") for i, v in enumerate(value))
