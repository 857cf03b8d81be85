"""Small scenarios for the workcell tests, written next to the test's tmp_path."""

from __future__ import annotations

from pathlib import Path

import yaml

BASE = {
    "version": 1,
    "name": "test_cell",
    "plant": {"time_step": 0.004, "contact_model": "hydroelastic_with_fallback"},
    "camera": {"width": 320, "height": 180, "fov_y_deg": 42.5},
    "control": {"period": 0.01, "perception_period": 0.02, "speed": 0.4, "look_height": 0.47},
    "grasp": {"network": "hrgnet", "attempts": 2},
    "workspaces": {
        "A": {"center": [0.5, 0.25], "size": [0.34, 0.34]},
        "B": {"center": [0.5, -0.25], "size": [0.34, 0.34]},
    },
    "waste_basket": [0.2, -0.58],
    "objects": [],
}


def write_scenario(tmp: Path, objects: list[dict], **changes) -> Path:
    data = {**BASE, "objects": objects, **changes}
    path = tmp / "cell.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path
