"""Meshcat views of a workcell: a live view while it runs, or a self-contained recording.

Every workcell adds the same `MeshcatVisualizer` (illustration geometry, 30 frames per
second) and records the same way: the visualizer keeps the frames while the simulator
runs, then `save_recording` replays them into the Meshcat scene and writes Meshcat's
static HTML (the animation embedded, openable offline). This is the only module that
imports `Meshcat`.
"""

from __future__ import annotations

from pathlib import Path

from pydrake.geometry import Meshcat, MeshcatVisualizer, MeshcatVisualizerParams, Role

FRAME_RATE = 30.0


def new_meshcat() -> Meshcat:
    """A local Meshcat server on a free port (its URL: ``web_url()``)."""
    return Meshcat(0)


def add_visualizer(builder, scene_graph, meshcat: Meshcat) -> MeshcatVisualizer:
    """A visualizer of ``scene_graph``'s illustration geometry, published at `FRAME_RATE`."""
    params = MeshcatVisualizerParams(publish_period=1.0 / FRAME_RATE, role=Role.kIllustration)
    return MeshcatVisualizer.AddToBuilder(builder, scene_graph, meshcat, params)


def start_recording(visualizer: MeshcatVisualizer) -> None:
    """Keep every published frame (before the simulator starts)."""
    visualizer.StartRecording(set_transforms_while_recording=False)


def save_recording(visualizer: MeshcatVisualizer, meshcat: Meshcat, path: str | Path) -> str:
    """Stop recording and write the animation as one self-contained HTML file at ``path``."""
    visualizer.StopRecording()
    visualizer.PublishRecording()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(meshcat.StaticHtml())
    return str(out)
