"""A run's timeline is read from its JSON document the same way for every workcell."""

from __future__ import annotations

from tamp.sim.core.timeline import Span, draw_timeline, spans


def test_spans_of_skills_person_and_behaviors():
    doc = {
        "workcell": "x",
        "sim_time": 9.0,
        "actions": [{"action": "Pick(O1)", "start": 1.0, "end": 2.0, "status": "FAILURE"}],
        "person_actions": [
            {"event": "add saw", "object": "saw#1", "start": 3.0, "end": 4.5},
            {"event": "never", "object": None, "start": None, "end": None},
        ],
        "timeline": [
            {"event": "R1.lift", "section": "arm", "start": 0.0, "end": 5.0},
            {"event": "R2.drive", "section": "base", "start": 5.0, "end": None},
            {"event": "R2.wait", "section": "base", "start": None, "end": None},
        ],
    }
    assert spans(doc) == [
        Span("Pick", "Pick(O1)", 1.0, 2.0, "FAILURE"),
        Span("person", "saw#1", 3.0, 4.5, "SUCCESS"),
        Span("R1 arm", "lift", 0.0, 5.0, "SUCCESS"),
        Span("R2 base", "drive", 5.0, None, None),  # still running when the run ended
    ]


def test_draw_timeline_writes_the_format_of_the_suffix(tmp_path):
    doc = {"sim_time": 2.0, "actions": [{"action": "MoveTo(O1)", "start": 0.0, "end": 2.0}]}
    png = draw_timeline(doc, tmp_path / "sub" / "t.png")
    assert png.read_bytes().startswith(b"\x89PNG")
    assert draw_timeline({}, tmp_path / "empty.svg").read_text().count("<svg") == 1
