"""The object detector on held-out rendered scenes: what it counts, how well its masks fit,
what it confuses, what it invents, and what a frame costs on one CPU thread.

Data: a set rendered by ``tamp detect render`` (its test scenes: object-wise split, unknown
shapes never seen in training). Weights: the shipped ``tamp/models/weights`` file by default,
``--weights FILE`` any other (a proposal classifier's or a segmentation network's, the same
rows, to compare). Per view ``Detector.detect`` (`tamp.sim.core.detector`) finds the objects;
`tamp.sim.core.segtrain.score_view` scores them against the label image's instances (an
object held in the gripper is not counted: `segtrain.true_instances`). Rows:

- per class: counting accuracy over the views where the class is present or predicted (the
  per-view count is what LOTS consumes), pixel IoU;
- totals: views with every count right, mask IoU of matched instances, false positives per
  view, unknown objects reported as a task class, the instance confusion matrix (JSON);
- objects wholly inside the image: the same scores with the instances and detections that
  reach the image's edge left out (an object cut by the edge is often unnameable; the cell
  looks at a workspace from above its centre, so what it counts lies inside the view);
- touching clutter: counting accuracy of a class in the views where two of its instances
  touch (masks within one pixel), the case no depth jump may separate;
- the seeded noisy detector (`tamp.sim.core.detection_noise`, levels ``low`` and ``high``)
  applied to the same detections: views with every count right, false positives per view;
- CPU time per frame on one thread (process time of the whole ``detect`` call) at the
  detector's resolution (160 x 90) and for the LOTS wrist camera's 320 x 180 images
  (subsampled, masks and points at full resolution);
- per scene kind (``scene_kinds``): the scores of the views of scenes with a stack of tower
  parts, with the tray, with an object lying across another, and of the plain ones (a set
  rendered before those kinds existed is all plain). A view of the tray is given its fixtures
  as the cell gives them (`segdata.view_fixtures`: the floor as the plane, the walls left out).

``--baseline FILE`` scores other weights on the same views (``before``: the counts, the
totals and the scene kinds), each ``--candidate FILE`` likewise (``candidate``,
``candidate_2`` ...: weights tried and not shipped); ``--also DATA`` scores further held-out
sets with each of them (``held_out_sets``: ``after`` the ``--weights`` file, ``before``,
the candidates). Prints
the tables and one JSON line; ``--out FILE`` writes the JSON there
(``benchmarks/results/detector.json`` is the committed run).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402
import torch  # noqa: E402
from scipy import ndimage  # noqa: E402

from tamp.sim.core.cropnet import WEIGHTS_FILE  # noqa: E402
from tamp.sim.core.detection_noise import perturb  # noqa: E402
from tamp.sim.core.detector import Detector  # noqa: E402
from tamp.sim.core.segdata import read_info, read_scene, scene_file, view_fixtures  # noqa: E402
from tamp.sim.core.segtrain import (  # noqa: E402
    Tally,
    predicted_map,
    report,
    score_view,
    true_instances,
)


def touching_classes(truth) -> set[int]:
    """Classes with two instances whose masks touch (within one pixel) in this view."""
    out = set()
    for i, (c, m) in enumerate(truth):
        grown = ndimage.binary_dilation(m, iterations=2)
        for c2, m2 in truth[i + 1 :]:
            if c2 == c and (grown & m2).any():
                out.add(c)
    return out


def on_border(mask: np.ndarray) -> bool:
    """Whether a mask reaches the image's edge (the object may be cut by it)."""
    return bool(mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any())


#: the scene kinds scored apart (`segdata.Scene.tags`; ``plain``: none of them)
SCENE_KINDS = ("plain", "stack", "tray", "across")


def compact(tally: Tally) -> dict:
    """The scores of a tally that a comparison needs: counts per class, views with every count
    right, task-class instances, false positives, unknown objects given a task class."""
    r = report(tally)
    return {
        "views": r["views"],
        "counting_accuracy": {k: c["accuracy"] for k, c in r["counting_accuracy"].items()},
        "views_all_counts_right": r["views_all_counts_right"],
        "task_instances": r["task_instances"],
        "false_positives_per_view": r["false_positives_per_view"],
        "unknown_objects": r["unknown_objects"],
        "unknown_reported_as_task_class": r["unknown_reported_as_task_class"],
    }


def run(data: Path, weights: Path | None, max_views: int, seed: int, full: bool = True) -> dict:
    """The benchmark of ``weights`` on the held-out scenes of ``data`` (module docstring);
    without ``full``, only the per-class counts, totals and scene kinds (no noisy detector,
    no timing)."""
    torch.set_num_threads(1)
    info = read_info(data)
    det = Detector.load(weights)
    names = list(det.classes)
    tally = Tally(names)
    kinds = {k: Tally(names) for k in SCENE_KINDS}
    noisy = {level: Tally(names) for level in ("low", "high")}
    inside = Tally(names)
    touch = {}
    times, times_full = [], []
    views = 0
    for s in info.test:
        scene = read_scene(scene_file(data, s))
        K = scene["K"]
        intr = (K[0, 0], K[1, 1], K[0, 2], K[1, 2])
        for v in range(len(scene["rgb"])):
            if max_views and views >= max_views:
                break
            rgb, depth, X_WC = scene["rgb"][v], scene["depth"][v], scene["X_WC"][v]
            size = (depth.shape[1], depth.shape[0])
            known = view_fixtures(scene, depth, intr, X_WC) if isinstance(det, Detector) else {}
            t0 = time.process_time()
            found = det.detect(rgb, depth, intr, X_WC, **known)
            times.append(time.process_time() - t0)
            truth, small = true_instances(
                scene["inst"][v], scene["inst_cls"][v], det.min_pixels, depth, names
            )
            for kind in [str(t) for t in scene.get("tags", ())] or ["plain"]:
                score_view(kinds[kind], found, truth, small)
            if not full:
                score_view(tally, found, truth, small)
                views += 1
                continue
            if views % 4 == 0 and not known:  # the wrist camera's full size: every fourth view
                big_rgb = rgb.repeat(2, 0).repeat(2, 1)
                big_depth = depth.repeat(2, 0).repeat(2, 1)
                big_intr = (2 * intr[0], 2 * intr[1], 2 * intr[2] + 0.5, 2 * intr[3] + 0.5)
                t0 = time.process_time()
                det.detect(big_rgb, big_depth, big_intr, X_WC)
                times_full.append(time.process_time() - t0)
            score_view(tally, found, truth, small, scene["cls"][v],
                       predicted_map(found, names, depth.shape))  # fmt: skip
            cut = [m for _, m in truth if on_border(m)]
            score_view(inside, [d for d in found if not on_border(d.mask)],
                       [(c, m) for c, m in truth if not on_border(m)], small + cut)  # fmt: skip
            for level, t in noisy.items():
                out = perturb(found, seed=seed, frame=views, level=level, classes=names[2:],
                              depth=depth, intrinsics=intr, X_WC=X_WC)  # fmt: skip
                score_view(t, out, truth, small)
            pred = [d.cls for d in found]
            for c in touching_classes(truth):
                n_true = sum(1 for k, _ in truth if k == c)
                ok, total = touch.get(names[c], (0, 0))
                touch[names[c]] = (ok + int(pred.count(names[c]) == n_true), total + 1)
            views += 1
        if max_views and views >= max_views:
            break
    by_kind = {k: compact(t) for k, t in kinds.items() if t.views}
    if not full:
        return {"data": str(data), **compact(tally), "scene_kinds": by_kind}
    doc = {
        "benchmark": "detector",
        "weights": str(weights) if weights else f"tamp/models/weights/{WEIGHTS_FILE}",
        "data": str(data),
        "test_scenes": len(info.test),
        "resolution": list(det.size),
        "kind": det.meta.get("kind"),
        "parameters": det.meta.get("parameters"),
        "split": det.meta.get("split"),
        **report(tally),
        "inside_image": {
            k: report(inside)[k]
            for k in (
                "views_all_counts_right",
                "task_instances",
                "false_positives_per_view",
                "task_class_false_positives_per_view",
            )
        },
        "touching_same_class": {
            k: {"correct": a, "views": b, "accuracy": round(a / b, 4)}
            for k, (a, b) in sorted(touch.items())
        },
        "noisy": {
            level: {
                "views_all_counts_right": report(t)["views_all_counts_right"],
                "false_positives_per_view": report(t)["false_positives_per_view"],
                "counting_accuracy": {
                    k: c["accuracy"] for k, c in report(t)["counting_accuracy"].items()
                },
            }
            for level, t in noisy.items()
        },
        # per image size: the data's own, and twice it (the wrist camera's full size; not
        # for views with known fixtures, whose data are rendered at their camera's size)
        "cpu_ms_per_frame_1_thread": {
            f"{w * k}x{h * k}": {
                "median": round(1000 * float(np.median(t)), 2),
                "p90": round(1000 * float(np.percentile(t, 90)), 2),
                "frames": len(t),
            }
            for k, t in ((1, times), (2, times_full))
            if t
            for w, h in [size]
        },
        "machine": f"{os.cpu_count()} cores; process time of this process on one torch thread",
        "scene_kinds": by_kind,
    }
    return doc


def table(doc: dict) -> str:
    lines = [
        f"detector on {doc['views']} held-out views ({doc['test_scenes']} scenes, "
        f"network {doc['resolution'][0]}x{doc['resolution'][1]}, {doc['parameters']} parameters)",
        f"{'class':<12} {'count acc':>9} {'views':>6} {'pixel IoU':>9} {'low noise':>9} "
        f"{'high noise':>10}",
    ]
    for k, c in doc["counting_accuracy"].items():
        acc = "-" if c["accuracy"] is None else f"{100 * c['accuracy']:.1f} %"
        iou = doc["pixel_iou"].get(k)
        low = doc["noisy"]["low"]["counting_accuracy"].get(k)
        high = doc["noisy"]["high"]["counting_accuracy"].get(k)
        lines.append(
            f"{k:<12} {acc:>9} {c['views']:>6} {'-' if iou is None else f'{iou:.3f}':>9} "
            f"{'-' if low is None else f'{100 * low:.1f} %':>9} "
            f"{'-' if high is None else f'{100 * high:.1f} %':>10}"
        )
    t = doc["cpu_ms_per_frame_1_thread"]
    lines += [
        f"views with every count right: {100 * doc['views_all_counts_right']:.1f} % "
        f"(noisy low {100 * doc['noisy']['low']['views_all_counts_right']:.1f} %, "
        f"high {100 * doc['noisy']['high']['views_all_counts_right']:.1f} %)",
        f"objects wholly inside the image: every count right in "
        f"{100 * doc['inside_image']['views_all_counts_right']:.1f} % of the views, "
        f"{doc['inside_image']['task_instances']['right_class']} of "
        f"{doc['inside_image']['task_instances']['total']} task-class instances with their class",
        f"mask IoU of matched instances: {doc['mask_iou_matched']} "
        f"({doc['matched_instances']} instances)",
        f"false positives per view: {doc['false_positives_per_view']} (task classes "
        f"{doc['task_class_false_positives_per_view']}; noisy low "
        f"{doc['noisy']['low']['false_positives_per_view']}, high "
        f"{doc['noisy']['high']['false_positives_per_view']})",
        "task-class instances: {right_class} of {total} with their class, {unknown_or_hand} "
        "unknown or hand, {other_task_class} another task class, {missed} missed".format(
            **doc["task_instances"]
        ),
        f"unknown objects reported as a task class: {doc['unknown_reported_as_task_class']} "
        f"of {doc['unknown_objects']}",
        "touching instances of one class, count right: "
        + ", ".join(
            f"{k} {c['correct']}/{c['views']}" for k, c in doc["touching_same_class"].items()
        ),
        "CPU per frame (one thread): "
        + ", ".join(f"{k} median {c['median']} ms (p90 {c['p90']})" for k, c in t.items()),
    ]
    return "\n".join(lines)


def kinds_table(after: dict, before: dict | None, title: str, label: str = "before") -> str:
    """Per scene kind and per class, the counting accuracy of the weights (and of other
    weights, ``before``, named ``label``), and the views with every count right."""
    lines = [title]
    for kind, a in after["scene_kinds"].items():
        b = (before or {}).get("scene_kinds", {}).get(kind)

        def pct(x):
            return "-" if x is None else f"{100 * x:.1f} %"

        lines.append(
            f"  {kind} ({a['views']} views): every count right {pct(a['views_all_counts_right'])}"
            + (f" ({label} {pct(b['views_all_counts_right'])})" if b else "")
            + f"; unknown as a task class {a['unknown_reported_as_task_class']} of "
            f"{a['unknown_objects']}"
            + (f" ({label} {b['unknown_reported_as_task_class']})" if b else "")
        )
        row = []
        for k, acc in a["counting_accuracy"].items():
            if acc is None:
                continue
            was = b["counting_accuracy"].get(k) if b else None
            row.append(f"{k} {pct(acc)}" + (f" ({label} {pct(was)})" if b else ""))
        lines.append("    " + ", ".join(row))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path, help="a set written by `tamp detect render`")
    parser.add_argument("--weights", type=Path, help="weights file (default: the shipped one)")
    parser.add_argument("--max-views", type=int, default=0, help="score at most N views")
    parser.add_argument("--seed", type=int, default=0, help="seed of the noisy detector")
    parser.add_argument("--out", type=Path, help="also write the JSON to this file")
    parser.add_argument(
        "--baseline", type=Path, help="weights to compare against on the same views (before)"
    )
    parser.add_argument(
        "--candidate",
        type=Path,
        action="append",
        default=[],
        help="weights tried and not shipped, on the same views (repeatable)",
    )
    parser.add_argument(
        "--also", type=Path, action="append", default=[], help="a further held-out set to score"
    )
    args = parser.parse_args(argv)
    doc = run(args.data, args.weights, args.max_views, args.seed)
    others = {"before": args.baseline} | {
        "candidate" + (f"_{k + 1}" if k else ""): w for k, w in enumerate(args.candidate)
    }
    for key, weights in others.items():
        if weights:
            doc[key] = {"weights": str(weights)} | run(
                args.data, weights, args.max_views, args.seed, full=False
            )
    doc["held_out_sets"] = [
        {"after": run(d, args.weights, args.max_views, args.seed, full=False)}
        | {
            key: {"weights": str(w)} | run(d, w, args.max_views, args.seed, full=False)
            for key, w in others.items()
            if w
        }
        for d in args.also
    ]
    print(table(doc))
    for key in others:
        if key in doc:
            print(kinds_table(doc, doc[key], f"scene kinds of {args.data}:", key))
    for extra in doc["held_out_sets"]:
        a = extra["after"]
        for key in [k for k in others if k in extra] or [None]:
            title = f"{a['data']} ({a['views']} views):"
            print(kinds_table(a, extra.get(key), title, key or "before"))
    text = json.dumps(doc)
    print(text)
    if args.out:
        args.out.write_text(json.dumps(doc, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
