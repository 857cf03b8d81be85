"""`tamp detect`: the workcells' object detector: render its data, train it, evaluate it.

    tamp detect render OUT --scenes N            Drake renders of both cells' catalogues
    tamp detect render OUT --camera mast         the SMP-MRO youBot's mast camera's views
    tamp detect train DATA --out DIR --kind classifier    the proposal classifier (CPU)
    tamp detect train DATA --out DIR             a small segmentation network (CPU or GPU)
    tamp detect eval WEIGHTS DATA                held-out scenes: counts, IoU, confusion, time

The classes are the LOTS cell's catalogue and the SMP-MRO cell's object kinds, plus
``unknown`` shapes and the person's hand (`tamp.sim.core.segdata`). Heavy imports (torch,
Drake) happen inside the handlers.
"""

from __future__ import annotations

from functools import partial
from pathlib import Path

from tamp.commands.output import print_json, progress
from tamp.errors import InputError


def workcell_catalogue():
    """(the catalogue's `SegClass`es, the gripper, hand and tray `Fixtures`): the LOTS
    cell's classes with their palettes, then the SMP-MRO cell's packaged object kinds; the
    tray is Example 1's basket in W^B."""
    from tamp.sim.core.models import sdf_path
    from tamp.sim.core.segdata import object_class, read_fixtures
    from tamp.sim.lots.catalogue import ARM, CLASSES, PERSON
    from tamp.sim.smp.robot import OBJECT_KINDS

    classes = [
        object_class(c.name, c.sdf, c.palette, [float(x) for x in c.colour.split()[:3]], c.body)
        for c in CLASSES.values()
    ]
    classes += [object_class(k.name, k.sdf, link=k.body) for k in OBJECT_KINDS.values()]
    fixtures = read_fixtures(
        sdf_path("lots_arm"),
        sdf_path("lots_person_hand"),
        hand_link=ARM.hand_body,
        finger_links=ARM.finger_bodies,
        camera_frame=ARM.camera_frame,
        tcp_frame=ARM.tcp_frame,
        person_link=PERSON.hand_body,
        tray_sdf=sdf_path("lots_tray"),
    )
    return classes, fixtures


def default_weights() -> Path:
    """The shipped detector weights, wherever tamp is installed."""
    from tamp.sim.core.cropnet import WEIGHTS_FILE
    from tamp.sim.core.models import models_dir

    return models_dir() / "weights" / WEIGHTS_FILE


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "detect", help="object detector from RGB-D: render data, train, evaluate"
    )
    sub = parser.add_subparsers(dest="detect_command", metavar="ACTION", required=True)

    p = sub.add_parser("render", help="render the detector's data set (Drake, object-wise split)")
    p.add_argument("out", help="output folder")
    p.add_argument("--scenes", type=int, default=200, help="number of scenes (default 200)")
    p.add_argument("--views", type=int, default=4, help="viewpoints per scene (default 4)")
    p.add_argument("--seed", type=int, default=0, help="seed of the scenes and split (default 0)")
    p.add_argument("--jobs", type=int, default=1, help="render in N processes (same files)")
    p.add_argument(
        "--camera",
        choices=("wrist", "mast"),
        default="wrist",
        help="wrist: the LOTS arm's wrist camera over a table (default); mast: the SMP-MRO "
        "youBot's mast camera over the floor, its own arm in view (`tamp.sim.smp.mast_data`)",
    )
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.set_defaults(func=run_render)

    p = sub.add_parser("train", help="train the detector's proposal classifier or segmentation net")
    p.add_argument("data", help="folder written by `tamp detect render`")
    p.add_argument("--out", default="runs/detect", help="output folder (default runs/detect)")
    p.add_argument(
        "--kind",
        choices=("segmentation", "classifier"),
        default="segmentation",
        help="segmentation: the per-pixel network (default); classifier: the classifier of "
        "geometric proposals (the shipped detector)",
    )
    p.add_argument("--steps", type=int, default=3000, help="segmentation: optimiser steps")
    p.add_argument("--epochs", type=int, default=18, help="classifier: passes over the proposals")
    p.add_argument(
        "--batch-size",
        type=int,
        default=None,
        help="views (segmentation, default 16) or proposals (classifier, default 128) per step",
    )
    p.add_argument("--lr", type=float, default=3e-3, help="peak learning rate (default 3e-3)")
    p.add_argument("--width", type=int, default=16, help="channels of the first stage")
    p.add_argument("--init", help="start from these weights (same classes and --width)")
    p.add_argument(
        "--unknown-below",
        type=float,
        default=None,
        help="classifier: this unknown threshold (0-1) instead of the one chosen on the "
        "held-back scenes (default: chosen)",
    )
    p.add_argument("--device", default="auto", help="auto (a GPU when present), cpu, cuda ...")
    p.add_argument("--threads", type=int, default=0, help="torch CPU threads (0: default)")
    p.add_argument("--seed", type=int, default=0, help="initialisation and batch seed")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.add_argument("--json", action="store_true", help="print the training summary as JSON")
    p.set_defaults(func=run_train)

    p = sub.add_parser("eval", help="score weights on the held-out scenes of a rendered set")
    p.add_argument("weights", help="weights file (OUT/final.pt or tamp/models/weights/...)")
    p.add_argument("data", help="folder written by `tamp detect render`")
    p.add_argument("--out", help="write the evaluation JSON into this folder")
    p.add_argument("--max-views", type=int, default=0, help="score at most N views (0: all)")
    p.add_argument("--json", action="store_true", help="print the evaluation as JSON")
    p.set_defaults(func=run_eval)


def run_render(args) -> int:
    from tamp.sim.core.segdata import DataConfig, generate

    if args.scenes < 1 or args.views < 1 or args.jobs < 1:
        raise InputError("--scenes, --views and --jobs must be >= 1")
    classes, fixtures = workcell_catalogue()
    if args.camera == "mast":
        from tamp.sim.smp import mast_data

        if args.jobs != 1:
            raise InputError(
                "--jobs: the mast camera's scenes render in one process", field="--jobs"
            )
        mast = mast_data.MastDataConfig(views=args.views, seed=args.seed)
        info = mast_data.generate(args.out, args.scenes, classes, mast)
    else:
        cfg = DataConfig(views=args.views, seed=args.seed)
        info = generate(args.out, args.scenes, classes, fixtures, cfg, jobs=args.jobs)
    summary = {
        "out": args.out,
        "scenes": info.scenes,
        "views": info.views,
        "train_scenes": len(info.train),
        "test_scenes": len(info.test),
        "classes": list(info.classes),
    }
    if args.json:
        print_json(summary)
    else:
        print(
            f"{info.views} views of {info.scenes} scenes ({len(info.train)} train, "
            f"{len(info.test)} test) in {args.out}"
        )
    return 0


def run_train(args) -> int:
    if args.steps < 1 or args.epochs < 1 or (args.batch_size is not None and args.batch_size < 1):
        raise InputError("--steps, --epochs and --batch-size must be >= 1")
    if args.lr <= 0 or args.width < 4:
        raise InputError("--lr must be > 0 and --width >= 4")
    train, done = _classifier(args) if args.kind == "classifier" else _segmenter(args)
    summary = train(args.data, args.out, log=None if args.quiet else (lambda m: progress(m)))
    if args.json:
        print_json(summary)
    else:
        print(f"{done(summary)}; weights {summary['weights']} ({summary['parameters']} parameters)")
    return 0


def _segmenter(args):
    """(the training call, its summary line) of the segmentation network."""
    from tamp.sim.core.segtrain import TrainSettings, train

    settings = TrainSettings(
        steps=args.steps,
        batch_size=args.batch_size or 16,
        lr=args.lr,
        width=args.width,
        device=args.device,
        threads=args.threads,
        seed=args.seed,
        init=args.init,
    )
    return partial(
        train, settings=settings
    ), lambda r: f"{r['steps']} steps in {r['seconds']:.0f} s on {r['device']}"


def _classifier(args):
    """(the training call, its summary line) of the crop classifier (``--kind classifier``)."""
    from tamp.sim.core.croptrain import TrainSettings, train

    if args.unknown_below is not None and not 0.0 < args.unknown_below < 1.0:
        raise InputError(f"must lie in (0, 1), got {args.unknown_below}", field="--unknown-below")
    if args.device not in ("auto", "cpu"):
        raise InputError(f"--device: the classifier trains on the CPU, not {args.device!r}")
    settings = TrainSettings(
        epochs=args.epochs,
        batch_size=args.batch_size or 128,
        lr=args.lr,
        width=args.width,
        threads=args.threads,
        seed=args.seed,
        init=args.init,
        unknown_below=args.unknown_below,
    )
    return (
        partial(train, settings=settings),
        lambda r: (
            f"{r['epochs']} epochs ({r['proposals']} proposals) in {r['cpu_seconds']:.0f} s "
            f"CPU; unknown below {r['unknown_below']}"
        ),
    )


def run_eval(args) -> int:
    from tamp.sim.core.segtrain import evaluate, format_report

    report = evaluate(args.weights, args.data, max_views=args.max_views)
    if args.out:
        import json

        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "detector_eval.json").write_text(json.dumps(report, indent=1))
    if args.json:
        print_json(report)
    else:
        print(format_report(report))
    return 0
