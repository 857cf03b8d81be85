"""The rosbridge v2 wire format: strict JSON in and out, op validation, fragment reassembly.

rosbridge v2 (RobotWebTools' ``ROSBRIDGE_PROTOCOL.md``) sends one JSON object per WebSocket
message with a string ``op``. This module is the one place that turns raw frames into
checked `Op` records and records into text, so the server never sees a half-parsed message:

- text and binary frames both carry UTF-8 JSON (ROS#'s WebSocketNetProtocol sends binary
  frames in 1,024-byte continuation pieces; the WebSocket library reassembles those);
- ``NaN``/``Infinity`` are refused on input and never sent (`dumps` uses ``allow_nan=False``;
  a browser's ``JSON.parse`` rejects them), output is ASCII (ROS# decodes ASCII);
- ``id`` may be a string, an int or null (ROS# sends ``"id": null``; null means absent);
- type names are canonical without ``/msg/`` or ``/srv/`` (ROS 1 and ROS 2 spellings);
- ``fragment`` ops are reassembled under size, count and age limits (`Fragments`).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from typing import Any

#: The ops a client may send (rosbridge v2, plus ``set_level`` and the fragment op).
CLIENT_OPS = frozenset(
    {
        "advertise",
        "unadvertise",
        "publish",
        "subscribe",
        "unsubscribe",
        "call_service",
        "advertise_service",
        "unadvertise_service",
        "service_response",
        "fragment",
        "set_level",
    }
)

#: Fields each op must carry, with the JSON types they must have.
REQUIRED: dict[str, dict[str, type | tuple[type, ...]]] = {
    "advertise": {"topic": str, "type": str},
    "unadvertise": {"topic": str},
    "publish": {"topic": str, "msg": dict},
    "subscribe": {"topic": str},
    "unsubscribe": {"topic": str},
    "call_service": {"service": str},
    "advertise_service": {"service": str, "type": str},
    "unadvertise_service": {"service": str},
    "service_response": {"service": str},
    "fragment": {"id": (str, int), "data": str, "num": int, "total": int},
    "set_level": {"level": str},
}

#: Optional fields and their types (others are ignored, as rosbridge does).
OPTIONAL: dict[str, type | tuple[type, ...]] = {
    "type": str,
    "latch": bool,
    "queue_size": int,
    "throttle_rate": (int, float),
    "queue_length": int,
    "fragment_size": int,
    "compression": str,
    "args": (dict, list),
    "timeout": (int, float),
}

LEVELS = ("info", "warning", "error", "none")


class WireError(ValueError):
    """A message that cannot be used; the text says why (sent in a ``status`` when asked)."""


@dataclass
class Op:
    """One checked client message: its op, its id (None when absent or null) and fields."""

    op: str
    id: str | int | None
    fields: dict[str, Any]

    def get(self, key: str, default: Any = None) -> Any:
        return self.fields.get(key, default)


def _refuse_constant(name: str) -> float:
    raise WireError(f"{name} is not a finite number")


def loads(data: str | bytes) -> Any:
    """Parse one frame's JSON; NaN, Infinity and invalid UTF-8 are a `WireError`."""
    if isinstance(data, bytes | bytearray | memoryview):
        try:
            data = bytes(data).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise WireError(f"binary frame is not UTF-8 JSON (byte {exc.start})") from None
    try:
        return json.loads(data, parse_constant=_refuse_constant)
    except WireError:
        raise
    except RecursionError:
        raise WireError("JSON nested too deeply") from None
    except ValueError as exc:
        raise WireError(f"bad JSON: {str(exc)[:80]}") from None


def dumps(message: dict[str, Any]) -> str:
    """Compact ASCII JSON; a NaN or infinity anywhere raises `ValueError` (never sent)."""
    return json.dumps(message, allow_nan=False, ensure_ascii=True, separators=(",", ":"))


def finite(value: Any, where: str = "msg") -> None:
    """Refuse non-finite floats anywhere in ``value`` (they cannot arrive through `loads`,
    but messages built in Python can carry them)."""
    stack = [(value, where)]
    while stack:
        v, w = stack.pop()
        if isinstance(v, float) and not math.isfinite(v):
            raise WireError(f"{w}: {v} is not a finite number")
        if isinstance(v, dict):
            stack.extend((x, f"{w}.{k}") for k, x in v.items())
        elif isinstance(v, list):
            stack.extend((x, f"{w}[{i}]") for i, x in enumerate(v))


def canonical_type(name: str) -> str:
    """``geometry_msgs/msg/PoseStamped`` (ROS 2) → ``geometry_msgs/PoseStamped`` (ROS 1)."""
    parts = name.strip().split("/")
    if len(parts) == 3 and parts[1] in ("msg", "srv", "action"):
        return f"{parts[0]}/{parts[2]}"
    return name.strip()


def _type_ok(value: Any, want: type | tuple[type, ...]) -> bool:
    if (
        isinstance(value, bool)
        and want is not bool
        and bool not in (want if isinstance(want, tuple) else (want,))
    ):
        return False  # JSON true is not a number or an id
    return isinstance(value, want)


def parse(message: Any) -> Op:
    """Check one decoded message against the op table; `WireError` says what is wrong."""
    if not isinstance(message, dict):
        raise WireError("a message must be a JSON object")
    op = message.get("op")
    if not isinstance(op, str):
        raise WireError("missing op")
    if op not in CLIENT_OPS:
        raise WireError(f"unknown op {op[:40]!r}")
    mid = message.get("id")
    if mid is not None and not _type_ok(mid, (str, int)):
        raise WireError(f"{op}: id must be a string or an integer")
    for key, want in REQUIRED[op].items():
        if key not in message or message[key] is None:
            raise WireError(f"{op}: missing field {key!r}")
        if not _type_ok(message[key], want):
            raise WireError(f"{op}: field {key!r} has the wrong type")
    for key, want in OPTIONAL.items():
        if key in message and message[key] is not None and key not in REQUIRED[op]:
            if not _type_ok(message[key], want):
                raise WireError(f"{op}: field {key!r} has the wrong type")
    fields = {k: v for k, v in message.items() if k not in ("op", "id") and v is not None}
    for key in ("topic", "service"):
        if key in fields and (not fields[key] or len(fields[key]) > 256):
            raise WireError(f"{op}: {key} must be 1 to 256 characters")
    if "type" in fields:
        fields["type"] = canonical_type(fields["type"])
    if op == "set_level" and fields["level"] not in LEVELS:
        raise WireError(f"set_level: level must be one of {', '.join(LEVELS)}")
    return Op(op, mid, fields)


@dataclass
class _Partial:
    total: int
    started: float
    parts: dict[int, str] = field(default_factory=dict)
    size: int = 0


class Fragments:
    """Reassembles ``fragment`` ops (``data`` pieces of one message, ``num`` 0…total−1, in any
    order) under limits: at most ``max_parts`` pieces, ``max_bytes`` in all, ``max_age`` s
    from the first piece to the last (rosbridge waits 600 s; a stalled sender should not hold
    memory that long), and ``max_pending`` messages in progress per client."""

    def __init__(
        self,
        *,
        max_bytes: int = 1 << 20,
        max_parts: int = 1000,
        max_age: float = 30.0,
        max_pending: int = 8,
    ):
        self.max_bytes = max_bytes
        self.max_parts = max_parts
        self.max_age = max_age
        self.max_pending = max_pending
        self._partial: dict[str | int, _Partial] = {}

    def add(self, op: Op, now: float | None = None) -> str | None:
        """Store one piece; the joined text once every piece is there, else None."""
        now = time.monotonic() if now is None else now
        self._expire(now)
        key, num, total, data = (
            op.id,
            op.fields["num"],
            op.fields["total"],
            op.fields["data"],
        )
        if not 1 <= total <= self.max_parts:
            raise WireError(f"fragment: total must be 1 to {self.max_parts}")
        if not 0 <= num < total:
            raise WireError("fragment: num must be 0 to total-1")
        part = self._partial.get(key)
        if part is None:
            if len(self._partial) >= self.max_pending:
                raise WireError(f"fragment: more than {self.max_pending} messages in progress")
            part = self._partial[key] = _Partial(total, now)
        if part.total != total:
            del self._partial[key]
            raise WireError("fragment: total changed between pieces")
        if num not in part.parts:
            part.size += len(data)
            part.parts[num] = data
        if part.size > self.max_bytes:
            del self._partial[key]
            raise WireError(f"fragment: message larger than {self.max_bytes} bytes")
        if len(part.parts) < total:
            return None
        del self._partial[key]
        return "".join(part.parts[i] for i in range(total))

    def _expire(self, now: float) -> None:
        for key in [k for k, p in self._partial.items() if now - p.started > self.max_age]:
            del self._partial[key]

    def __len__(self) -> int:
        return len(self._partial)
