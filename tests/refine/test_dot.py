"""DOT export of the state machines (Fig. 1, Fig. 13): structure and a Graphviz render."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from tamp.refine.dot import program_dot
from tamp.refine.steps import parallelize

from .helpers import task


def test_sequential_program():
    dot = program_dot(task(4))
    assert dot.startswith('digraph "task4" {')
    assert 'subgraph "cluster_R1"' in dot and 'subgraph "cluster_R2"' in dot
    assert '"R1.lower_arm" -> "R1.approach" [label="R1.lower_arm"];' in dot
    assert '"R2.grip" -> "R1.pull_out" [style=dashed' in dot and "waits for R2.grip" in dot
    assert "marker" not in dot and "fork" not in dot


def test_parallel_group_has_fork_and_marker():
    p, _ = parallelize(task(4), {"R1.lower_arm": 57.0, "R1.approach": 68.0})
    dot = program_dot(p)
    assert '"R1.start" -> "R1.fork0" [label="start"];' in dot
    assert '"R1.fork0" -> "R1.lower_arm";' in dot and '"R1.fork0" -> "R1.approach";' in dot
    assert '"R1.lower_arm.marker"' in dot and "R1.lower_arm (marker)" in dot
    # the absorbed event no longer gates: pull_out follows the approach
    assert '"R1.approach" -> "R1.pull_out" [label="R1.approach"];' in dot
    assert '"R1.lower_arm" -> "R1.pull_out"' not in dot


@pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz not installed")
def test_graphviz_renders_it():
    p, _ = parallelize(task(4), {"R1.lower_arm": 57.0, "R1.approach": 68.0})
    out = subprocess.run(
        ["dot", "-Tsvg"], input=program_dot(p), capture_output=True, text=True, check=True
    )
    assert "<svg" in out.stdout and "pull_out" in out.stdout
