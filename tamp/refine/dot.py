"""The robots' state machines as Graphviz DOT (Fig. 1(a), Fig. 13).

One cluster per robot. A behavior is a box (section, motion, triggering event, rate); a
solid edge is the transition its gating event fires. Behaviors that start together
(Fig. 13(b)) hang off one fork point; an absorbed behavior's event is drawn as a dotted
edge to a completion marker (it no longer gates). Dashed edges between the robots are the
events a behavior waits for (``waits for``) or ends after (``ends after``).
"""

from __future__ import annotations

from tamp.refine.program import Behavior, Program, event_id, split_event


def _q(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _node(robot: str, name: str) -> str:
    return _q(f"{robot}.{name}")


def _label(p: Program, b: Behavior) -> str:
    lines = [b.name, f"{b.section}: {b.motion.describe()}", f"event: {b.event.describe()}"]
    lines.append(f"P = {p.rate(b):g} Hz" + (" · manipulates" if b.manipulates else ""))
    return "\\n".join(x.replace('"', "'") for x in lines)


def program_dot(program: Program) -> str:
    """DOT text of both state machines and the events that synchronise them."""
    out = [
        f"digraph {_q(program.name)} {{",
        "  rankdir=TB; compound=true;",
        '  node [shape=box, style="rounded", fontname="Helvetica", fontsize=10];',
        '  edge [fontname="Helvetica", fontsize=9];',
    ]
    for r in program.robots:
        out.append(f"  subgraph {_q('cluster_' + r.name)} {{")
        out.append(f"    label={_q(f'{r.name} ({r.model})')};")
        start = _q(f"{r.name}.start")
        out.append(f'    {start} [shape=circle, label="", width=0.2, style=filled];')
        end = _q(f"{r.name}.end")
        out.append(f'    {end} [shape=doublecircle, label="", width=0.2];')
        prev = start
        prev_label = "start"
        for g, group in enumerate(r.groups()):
            tail = group[-1]  # the group's last behavior (a group is never empty)
            src = prev
            if len(group) > 1:
                fork = _q(f"{r.name}.fork{g}")
                out.append(f'    {fork} [shape=point, width=0.08, label=""];')
                out.append(f"    {prev} -> {fork} [label={_q(prev_label)}];")
                src = fork
            for i in group:
                b = r.behaviors[i]
                node = _node(r.name, b.name)
                style = ', style="rounded,dashed"' if not r.gating(i) else ""
                out.append(f"    {node} [label={_q(_label(program, b))}{style}];")
                edge_label = "" if len(group) > 1 else f" [label={_q(prev_label)}]"
                out.append(f"    {src} -> {node}{edge_label};")
                if not r.gating(i):
                    marker = _q(f"{r.name}.{b.name}.marker")
                    text = _q(event_id(r.name, b.name) + " (marker)")
                    out.append(f"    {marker} [shape=note, fontsize=8, label={text}];")
                    out.append(f"    {node} -> {marker} [style=dotted, arrowhead=none];")
            last = r.behaviors[tail]
            prev = _node(r.name, last.name)
            prev_label = event_id(r.name, last.name)
        out.append(f"    {prev} -> {end} [label={_q(prev_label)}];")
        out.append("  }")
    for r in program.robots:
        for b in r.behaviors:
            node = _node(r.name, b.name)
            for w in b.waits_for:
                src = _node(*split_event(w))
                out.append(
                    f'  {src} -> {node} [style=dashed, color="firebrick", '
                    f'fontcolor="firebrick", label={_q("waits for " + w)}, constraint=false];'
                )
            if b.event.after:
                src = _node(*split_event(b.event.after))
                out.append(
                    f'  {src} -> {node} [style=dashed, color="royalblue", '
                    f'fontcolor="royalblue", label={_q("ends after " + b.event.after)}, '
                    "constraint=false];"
                )
    out.append("}")
    return "\n".join(out) + "\n"
