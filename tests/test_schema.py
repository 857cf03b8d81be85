"""The typed loader (`tamp.schema`): defaults stated once, strict file:field errors, nesting,
relations checked by the dataclass, and a description for reference pages."""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest
from hypothesis import given
from hypothesis import strategies as st

from tamp.errors import InputError
from tamp.fileio import Fields
from tamp.schema import describe, json_schema, keys_of, load_dataclass, spec


@dataclass(frozen=True)
class Camera:
    width: int = spec(320, min=32, max=1280, unit="px")
    fov_y_deg: float = spec(42.5, min=10.0, max=120.0, unit="deg")


@dataclass(frozen=True)
class Item:
    cls: str = spec(key="class", choices=("saw", "cap"))
    xy: tuple[float, float] = spec((0.0, 0.0), unit="m")


@dataclass(frozen=True)
class Cell:
    name: str = spec()
    time_step: float = spec(0.002, min=0.0005, max=0.01, unit="s")
    period: float = spec(0.01, min=0.0, strict_min=True, unit="s")
    camera: Camera = spec(Camera)
    heights: tuple[float, ...] = spec((0.34, 0.2), min=0.15, max=0.6, min_items=1)
    items: tuple[Item, ...] = spec(())
    tray: bool = spec(False)
    source: str = ""  # not a file field
    notes: list = field(default_factory=list)

    def check(self, f: Fields) -> None:
        if self.period < self.time_step:
            raise f.error("period", f"must be >= time_step ({self.time_step:g} s)")


def load(data: dict) -> Cell:
    return load_dataclass(Cell, Fields(data, "cell.yaml"))


def error_of(data: dict) -> str:
    with pytest.raises(InputError) as info:
        load(data)
    return str(info.value)


def test_defaults_come_from_the_dataclass():
    cell = load({"name": "a"})
    assert cell == Cell(name="a")
    assert cell.camera == Camera() and cell.heights == (0.34, 0.2) and cell.items == ()


def test_values_nested_sections_and_lists_of_sections():
    cell = load(
        {
            "name": "a",
            "camera": {"width": 640},
            "heights": [0.3],
            "items": [{"class": "saw", "xy": [0.1, -0.2]}, {"class": "cap"}],
            "tray": True,
        }
    )
    assert cell.camera == Camera(width=640)
    assert cell.heights == (0.3,)
    assert cell.items == (Item("saw", (0.1, -0.2)), Item("cap"))
    assert cell.tray is True


@pytest.mark.parametrize(
    ("data", "where", "why"),
    [
        ({}, "cell.yaml: name", "missing field"),
        ({"name": "a", "speed": 1}, "cell.yaml: speed", "unknown key"),
        ({"name": "a", "time_step": 0.1}, "cell.yaml: time_step", "must be <= 0.01"),
        ({"name": "a", "time_step": "x"}, "cell.yaml: time_step", "expected a number"),
        ({"name": "a", "period": 0.0}, "cell.yaml: period", "must be > 0.0"),
        ({"name": "a", "camera": {"width": 8}}, "cell.yaml: camera.width", "must be >= 32"),
        ({"name": "a", "camera": {"width": 2000}}, "cell.yaml: camera.width", "must be <= 1280"),
        ({"name": "a", "camera": {"focal": 1}}, "cell.yaml: camera.focal", "unknown key"),
        ({"name": "a", "heights": []}, "cell.yaml: heights", "at least 1 item"),
        ({"name": "a", "heights": [0.1]}, "cell.yaml: heights[0]", "must be >= 0.15"),
        ({"name": "a", "items": [{"class": "hat"}]}, "cell.yaml: items[0].class", "expected one"),
        ({"name": "a", "items": [{}]}, "cell.yaml: items[0].class", "missing field"),
        ({"name": "a", "items": [{"class": "saw", "xy": [1]}]}, "items[0].xy", "list of 2"),
        ({"name": "a", "items": ["saw"]}, "cell.yaml: items[0]", "expected a mapping"),
        ({"name": "a", "tray": 1}, "cell.yaml: tray", "expected true or false"),
        ({"name": "a", "period": 0.001}, "cell.yaml: period", "must be >= time_step"),
    ],
)
def test_errors_name_file_and_field(data, where, why):
    message = error_of(data)
    assert where in message and why in message


def test_fields_without_spec_are_not_read():
    assert "source" not in keys_of(Cell) and "notes" not in keys_of(Cell)
    assert "unknown key" in error_of({"name": "a", "source": "x"})


def test_describe_lists_nested_fields_with_units():
    rows = {r["key"]: r for r in describe(Cell)}
    assert rows["camera.width"]["default"] == 320 and rows["camera.width"]["unit"] == "px"
    assert rows["name"]["required"] and not rows["time_step"]["required"]
    assert rows["items"]["default"] == ()


@given(st.floats(allow_nan=True, allow_infinity=True))
def test_a_number_loads_exactly_when_it_is_within_bounds(x):
    data = {"name": "a", "time_step": x, "period": 1.0}
    inside = x == x and 0.0005 <= x <= 0.01
    if inside:
        assert load(data).time_step == x
    else:
        assert "cell.yaml: time_step" in error_of(data)


def test_json_schema_states_what_the_loader_checks():
    """`json_schema` derives types, bounds, choices, lengths and defaults from the specs;
    a file the loader accepts validates, one it refuses for a key or bound does not."""
    jsonschema = pytest.importorskip("jsonschema")
    doc = json_schema(Cell, extra={"version": {"const": 1}}, required_extra=["version"])
    jsonschema.Draft202012Validator.check_schema(doc)
    props = doc["properties"]
    assert doc["required"] == ["name", "version"] and doc["additionalProperties"] is False
    assert props["period"] == {
        "type": "number",
        "exclusiveMinimum": 0.0,
        "description": "[s]",
        "default": 0.01,
    }
    assert props["camera"]["properties"]["width"]["maximum"] == 1280
    assert props["heights"]["minItems"] == 1 and props["heights"]["default"] == [0.34, 0.2]
    item = props["items"]["items"]
    assert item["properties"]["class"]["enum"] == ["saw", "cap"]
    assert item["properties"]["xy"]["minItems"] == item["properties"]["xy"]["maxItems"] == 2
    assert "source" not in props and "notes" not in props
    ok = {"version": 1, "name": "a", "camera": {"width": 640}, "items": [{"class": "saw"}]}
    load({k: v for k, v in ok.items() if k != "version"})
    check = jsonschema.Draft202012Validator(doc)
    assert check.is_valid(ok)
    for bad in (
        {**ok, "camera": {"width": 16}},
        {**ok, "period": 0.0},
        {**ok, "items": [{"class": "hammer"}]},
        {**ok, "heights": []},
        {**ok, "extra": 1},
        {"version": 1},
    ):
        assert not check.is_valid(bad), bad
        with pytest.raises(InputError):
            load({k: v for k, v in bad.items() if k != "version"})
