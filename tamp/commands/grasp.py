"""`tamp grasp`: synthetic data, training, evaluation and prediction for HRG-Net (§IV-B).

    tamp grasp synth OUT --scenes N            render a Jacquard-format set with Drake
    tamp grasp train --dataset jacquard PATH --model hrgnet --input rgbd
    tamp grasp eval WEIGHTS --dataset jacquard PATH --split object
    tamp grasp predict IMAGE --weights W [--depth D] [--depth-range MIN,MAX] [--camera camera.json]

Heavy imports (torch, Drake) happen inside the handlers.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from tamp.commands.output import print_json
from tamp.errors import InfeasibleError, InputError
from tamp.grasp.networks import DEFAULT_NETWORK, FUSION_MODES, INPUT_CHANNELS, NETWORKS

#: `tamp grasp predict --depth-range` default (= tamp.grasp.depth.DEFAULT_DEPTH_RANGE)
DEPTH_RANGE = "0.05,5"


def default_weights() -> Path:
    """The shipped weights of the default network (HRG-Net), wherever tamp is installed."""
    from tamp.sim.core.models import models_dir

    return models_dir() / NETWORKS[DEFAULT_NETWORK].weights


def register(subparsers) -> None:
    parser = subparsers.add_parser("grasp", help="grasp detection: HRG-Net and baselines")
    sub = parser.add_subparsers(dest="grasp_command", metavar="ACTION", required=True)

    p = sub.add_parser("synth", help="render a synthetic grasp dataset (Jacquard format)")
    p.add_argument("out", help="output folder")
    p.add_argument("--scenes", type=int, default=100, help="number of scenes (default 100)")
    p.add_argument("--views", type=int, default=4, help="viewpoints per scene (default 4)")
    p.add_argument("--size", type=int, default=128, help="image side in pixels (default 128)")
    p.add_argument("--seed", type=int, default=0, help="seed of the scenes (default 0)")
    p.add_argument(
        "--jobs", type=int, default=1, help="render in N processes (same files; default 1)"
    )
    p.add_argument(
        "--table",
        # tamp.grasp.synthetic.TABLES (a test keeps them equal; importing it here would load
        # numpy on every start of the command line)
        choices=("plain", "mats"),
        default="plain",
        help="plain beige-grey table (default) or coloured mats of random hue under the objects",
    )
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.set_defaults(func=run_synth)

    p = sub.add_parser("train", help="train a grasp network")
    _dataset_args(p)
    p.add_argument(
        "--model",
        choices=list(NETWORKS),
        default=DEFAULT_NETWORK,
        help=f"the network to train (default {DEFAULT_NETWORK})",
    )
    p.add_argument(
        "--input",
        choices=list(INPUT_CHANNELS),
        default="rgbd",
        help="input channels (default rgbd)",
    )
    p.add_argument("--out", default="runs/grasp", help="checkpoint folder (default runs/grasp)")
    p.add_argument("--epochs", type=int, default=10, help="training epochs (default 10)")
    p.add_argument("--batch-size", type=int, default=8, help="images per batch (default 8)")
    p.add_argument("--batches-per-epoch", type=int, default=0, help="0: the whole split")
    p.add_argument("--lr", type=float, default=1e-3, help="(peak) learning rate")
    p.add_argument(
        "--schedule",
        choices=("cosine", "constant"),
        default="cosine",
        help="cosine annealing to zero over the whole run (default) or a constant rate",
    )
    p.add_argument(
        "--fusion",
        choices=FUSION_MODES,
        default="full",
        help="HRG-Net layer fusion: repeated exchange + multi-resolution head (full, default), "
        "head only (final), or none: the full-resolution branch alone (Table IV ablation)",
    )
    p.add_argument("--no-fusion", action="store_true", help="same as --fusion none")
    p.add_argument("--no-augment", action="store_true", help="no rotation/zoom augmentation")
    p.add_argument(
        "--model-arg",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="model constructor argument, VALUE in JSON (e.g. channels=16, widths=[8,16,32,64])",
    )
    p.add_argument("--resume", action="store_true", help="continue from OUT/last.pt")
    p.add_argument(
        "--nproc",
        type=int,
        default=1,
        help="DistributedDataParallel over N local processes (gloo on CPU); for several "
        "GPUs or machines launch with torchrun instead",
    )
    p.add_argument("--device", default="auto", help="auto, cpu, cuda, cuda:1 ...")
    p.add_argument("--threads", type=int, default=0, help="torch CPU threads (0: default)")
    p.add_argument(
        "--eval-limit", type=int, default=0, help="evaluate on at most N val/test images"
    )
    p.add_argument("--seed", type=int, default=0, help="split and initialisation seed")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true", help="print the training summary as JSON")
    p.set_defaults(func=run_train)

    p = sub.add_parser(
        "eval",
        help="rectangle-metric accuracy, width error and inference time",
        description="Evaluates on the test part of the split recorded in the weights unless "
        "--split/--seed/--test-fraction/--fold say otherwise (then with a warning).",
    )
    p.add_argument("weights", help="weights file (final.pt, best.pt or tamp/models/weights/*.pt)")
    _dataset_args(p, split_choices=("image", "object", "both"), size=None, recorded=True)
    p.add_argument("--device", default="cpu", help="cpu (default), cuda, cuda:1 ...")
    p.add_argument("--threads", type=int, default=0, help="torch CPU threads (0: default)")
    p.add_argument("--time-size", type=int, default=224, help="image side for the timing")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true", help="print the evaluation as JSON")
    p.set_defaults(func=run_eval)

    p = sub.add_parser(
        "calibrate",
        help="record the training split in a weights file and fit its width calibration",
        description="For weights trained before files recorded their split: say which split "
        "they were trained with; the file is rewritten with that split, a width calibration "
        "fitted on its validation part (else on training images) and the test accuracy.",
    )
    p.add_argument("weights", help="weights file")
    _dataset_args(p, size=None)
    p.add_argument("--seed", type=int, default=0, help="split seed of the training run")
    p.add_argument(
        "--weights-out",
        metavar="FILE",
        help="write the calibrated weights to FILE (default: overwrite WEIGHTS)",
    )
    p.add_argument("--json", action="store_true", help="print the calibration as JSON")
    p.set_defaults(func=run_calibrate)

    p = sub.add_parser("predict", help="grasps in an image (pixels; world frame with a camera)")
    p.add_argument("image", help="RGB image (.png/.jpg) or depth image (.tiff, metres)")
    p.add_argument("--depth", help="depth image (.tiff, metres) when IMAGE is the RGB image")
    p.add_argument(
        "--depth-range",
        # tamp.grasp.depth.DEFAULT_DEPTH_RANGE (a test keeps them equal; importing it here
        # would load numpy on every start of the command line)
        default=DEPTH_RANGE,
        metavar="MIN,MAX",
        help=f"the camera's valid depth in metres (default {DEPTH_RANGE}): holes (0, NaN) and "
        "depth outside it are masked and carry no grasp",
    )
    p.add_argument(
        "--weights",
        help=f"weights file (default: the shipped {NETWORKS[DEFAULT_NETWORK].weights_file})",
    )
    p.add_argument("--camera", help="JSON with K (3x3) and X_WC (4x4), as `grasp synth` writes")
    p.add_argument(
        "--intrinsics",
        nargs=4,
        type=float,
        metavar=("FX", "FY", "CX", "CY"),
        help="camera intrinsics in pixels (instead of --camera)",
    )
    p.add_argument("--pose", nargs=16, type=float, metavar="X", help="X_WC, 16 numbers row-major")
    p.add_argument("--top", type=int, default=1, help="number of grasps (default 1)")
    p.add_argument("--json", action="store_true", help="print the grasps as JSON")
    p.set_defaults(func=run_predict)


def _dataset_args(
    p: argparse.ArgumentParser,
    split_choices=("image", "object"),
    size: int | None = 224,
    recorded: bool = False,
) -> None:
    """Dataset and split flags; with ``recorded`` (eval) every split flag defaults to the
    split recorded in the weights (None here)."""
    p.add_argument(
        "--dataset",
        nargs=2,
        metavar=("{cornell,jacquard}", "PATH"),
        required=True,
        help="dataset kind and folder",
    )
    rec = " (default: as recorded in the weights)" if recorded else ""
    p.add_argument(
        "--split",
        choices=split_choices,
        default=None if recorded else "image",
        help="train/test split: by image or by object (eval: both reports each)"
        + (rec or " (default image)"),
    )
    p.add_argument(
        "--test-fraction",
        type=float,
        default=None if recorded else 0.1,
        help="test part of all images/objects" + (rec or " (default 0.1)"),
    )
    p.add_argument("--fold", type=int, help="test fold for k-fold cross-validation" + rec)
    p.add_argument(
        "--folds",
        type=int,
        default=None if recorded else 5,
        help="folds of k-fold cross-validation" + (rec or " (default 5)"),
    )
    if recorded:
        p.add_argument("--seed", type=int, default=None, help="split seed" + rec)
    else:
        p.add_argument(
            "--val-fraction",
            type=float,
            default=0.1,
            help="validation part (of all images/objects) that picks best.pt (default 0.1; "
            "0: none, no per-epoch evaluation)",
        )
    p.add_argument(
        "--size",
        type=int,
        default=size,
        help=f"network input side in pixels (default {size or 'the training size'})",
    )


def _kind(args) -> tuple[str, str]:
    kind, path = args.dataset
    if kind not in ("cornell", "jacquard"):
        raise InputError(f"--dataset: unknown kind {kind!r}; expected cornell or jacquard")
    return kind, path


def _model_args(items: list[str]) -> dict:
    out = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise InputError(f"--model-arg: expected KEY=VALUE, got {item!r}")
        try:
            out[key] = json.loads(value)
        except json.JSONDecodeError:
            raise InputError(f"--model-arg {key}: value {value!r} is not JSON") from None
    return out


def run_synth(args) -> int:
    from tamp.grasp.synthetic import SynthConfig, generate

    if args.scenes < 1 or args.views < 1 or args.jobs < 1 or args.size < 16:
        raise InputError("--scenes, --views and --jobs must be >= 1 and --size >= 16")
    cfg = SynthConfig(size=args.size, views=args.views, seed=args.seed, table=args.table)
    summary = generate(args.out, args.scenes, cfg, progress=True, jobs=args.jobs)
    if args.json:
        print_json(summary | {"out": args.out})
    else:
        print(f"{summary['images']} images, {summary['grasps']} grasps in {args.out}")
    return 0


def run_train(args) -> int:
    from tamp.grasp.train import TrainConfig, train

    if args.nproc < 1:
        raise InputError(f"--nproc must be >= 1, got {args.nproc}")
    if args.no_fusion and args.fusion != "full":
        raise InputError(f"--no-fusion contradicts --fusion {args.fusion}")
    if (args.no_fusion or args.fusion != "full") and not NETWORKS[args.model].fusion:
        raise InputError(f"--fusion/--no-fusion apply to HRG-Net only, not --model {args.model}")
    kind, path = _kind(args)
    kwargs = _model_args(args.model_arg)
    cfg = TrainConfig(
        dataset=kind,
        path=path,
        model=args.model,
        input=args.input,
        out=args.out,
        size=args.size,
        epochs=args.epochs,
        batch_size=args.batch_size,
        batches_per_epoch=args.batches_per_epoch,
        lr=args.lr,
        schedule=args.schedule,
        split=args.split,
        test_fraction=args.test_fraction,
        val_fraction=args.val_fraction,
        fold=args.fold,
        folds=args.folds,
        seed=args.seed,
        fusion="none" if args.no_fusion else args.fusion,
        augment=not args.no_augment,
        device=args.device,
        threads=args.threads,
        eval_limit=args.eval_limit,
        model_kwargs=kwargs,
    )
    try:
        if args.nproc > 1:
            from tamp.grasp.train import train_local_processes

            summary = train_local_processes(cfg, args.nproc, resume=args.resume)[0]
        else:
            summary = train(
                cfg,
                resume=args.resume,
                progress=not args.quiet,
                log=lambda m: print(m, file=sys.stderr, flush=True),
            )
    except TypeError as exc:  # a wrong --model-arg reaches the model constructor
        raise InputError(f"--model-arg: {exc}") from None
    if int(os.environ.get("RANK", "0")) != 0:
        return 0  # under torchrun only rank 0 reports
    if args.json:
        print_json(summary)
    else:
        line = (
            f"{args.model} ({summary['parameters']} parameters): final accuracy "
            f"{100 * summary['final_accuracy']:.1f}% on {summary['test_images']} test images; "
            f"weights in {Path(args.out) / 'final.pt'}"
        )
        if summary["best_epoch"] is not None:
            line += (
                f" (best validation epoch {summary['best_epoch']}: "
                f"{100 * summary['best_val_accuracy']:.1f}% on {summary['val_images']} images, "
                f"{Path(args.out) / 'best.pt'})"
            )
        print(line)
    return 0


def eval_spec(args, record: dict | None):
    """The split to evaluate: the weights' recorded split, changed by the flags given."""
    from tamp.grasp.splits import SplitSpec

    base = SplitSpec.from_dict(record) if record else SplitSpec()
    flags = {
        "kind": None if args.split == "both" else args.split,
        "seed": args.seed,
        "test_fraction": args.test_fraction,
        "fold": args.fold,
        "folds": args.folds,
    }
    changes = {k: v for k, v in flags.items() if v is not None}
    if args.test_fraction is not None and args.fold is None:
        changes["fold"] = None  # a test fraction replaces a recorded fold
    return SplitSpec.from_dict(base.as_dict() | changes)


def run_eval(args) -> int:
    import dataclasses

    import torch

    from tamp.grasp.datasets import GraspDataset
    from tamp.grasp.evaluate import (
        calibration_of,
        evaluate,
        optimize_for_cpu,
        time_inference,
    )
    from tamp.grasp.splits import split_warnings
    from tamp.grasp.train import load_model

    if args.threads:
        torch.set_num_threads(args.threads)
    kind, path = _kind(args)
    model, meta = load_model(args.weights, args.device)
    size = args.size or int(meta["size"])
    dataset = GraspDataset(kind, path, size, meta["input"])
    record = meta.get("split")
    spec = eval_spec(args, record)
    kinds = ("image", "object") if args.split == "both" else (spec.kind,)
    result = {"weights": args.weights, "model": meta["model"], "input": meta["input"]}
    result["size"] = size
    result["trained_split"] = record
    result["width_calibration"] = meta.get("width_calibration")
    warnings: list[str] = []
    for split_kind in kinds:
        one = dataclasses.replace(spec, kind=split_kind)
        split = dataset.split(one)
        warnings += [f"{split_kind}-wise: {w}" for w in split_warnings(record, dataset, one, split)]
        r = evaluate(
            model,
            dataset,
            split.test,
            device=args.device,
            progress=not args.quiet,
            width_calibration=calibration_of(meta),
        )
        result[f"{split_kind}_wise"] = r.as_dict() | {"split": one.as_dict()}
    for w in warnings:
        print(f"tamp grasp eval: warning: {w}", file=sys.stderr)
    result["warnings"] = warnings
    timed = optimize_for_cpu(model) if args.device == "cpu" else model
    result["time"] = time_inference(
        timed, INPUT_CHANNELS[meta["input"]], args.time_size, device=args.device
    ) | {"size": args.time_size, "threads": torch.get_num_threads(), "device": args.device}
    if args.json:
        print_json(result)
    else:
        for split_kind in kinds:
            r = result[f"{split_kind}_wise"]
            one = dataclasses.replace(spec, kind=split_kind)
            print(
                f"{split_kind}-wise ({one.describe()}): {100 * r['accuracy']:.2f}% "
                f"({r['correct']}/{r['images']}); " + width_text(r["width"])
            )
        t = result["time"]
        print(
            f"inference at {args.time_size}x{args.time_size}: {t['median_ms']:.1f} ms "
            f"(median, min {t['min_ms']:.1f} ms, {t['threads']} threads, {args.device})"
        )
    return 0


def run_calibrate(args) -> int:
    from tamp.grasp.datasets import GraspDataset
    from tamp.grasp.splits import SplitSpec
    from tamp.grasp.train import read_weights, record_split_and_calibrate

    kind, path = _kind(args)
    meta = read_weights(args.weights)["meta"]
    dataset = GraspDataset(kind, path, args.size or int(meta["size"]), meta["input"])
    spec = SplitSpec(
        args.split, args.seed, args.test_fraction, args.val_fraction, args.fold, args.folds
    )
    written = args.weights_out or args.weights
    meta = record_split_and_calibrate(args.weights, written, dataset, spec)
    if args.json:
        print_json(meta)
    else:
        c, t = meta["width_calibration"], meta["test"]
        print(
            f"{written}: split {spec.describe()} recorded; width calibration "
            f"{c['scale']:.3f} (median of {c['grasps']} grasps, {c['part']} images); test "
            f"accuracy {100 * t['accuracy']:.2f}% ({t['correct']}/{t['images']}), "
            + width_text(t["width"])
        )
    return 0


def width_text(width: dict) -> str:
    from tamp.grasp.evaluate import WidthError

    return WidthError(**width).describe()


def _camera(args):
    import numpy as np

    if args.camera:
        p = Path(args.camera)
        if not p.is_file():
            raise InputError("camera file not found", file=str(p))
        try:
            data = json.loads(p.read_text())
            K, X = np.array(data["K"], dtype=float), np.array(data["X_WC"], dtype=float)
        except (json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
            raise InputError(
                f"expected JSON with K (3x3) and X_WC (4x4): {exc}", file=str(p)
            ) from None
        if K.shape != (3, 3) or X.shape != (4, 4):
            raise InputError("K must be 3x3 and X_WC 4x4", file=str(p))
        return (K[0, 0], K[1, 1], K[0, 2], K[1, 2]), X
    if args.intrinsics and args.pose:
        return tuple(args.intrinsics), np.array(args.pose, dtype=float).reshape(4, 4)
    if args.intrinsics or args.pose:
        raise InputError("--intrinsics and --pose go together (or use --camera)")
    return None, None


def run_predict(args) -> int:
    """Exit 2 for a depth image that is no depth image (no valid pixel, negative values:
    `tamp.grasp.depth.DepthCheck.problem`), exit 1 with the reason when no grasp stands on
    valid depth."""
    from tamp.grasp import formats
    from tamp.grasp.depth import DepthRange, check_depth
    from tamp.grasp.predict import GraspPredictor

    if args.top < 1:
        raise InputError(f"--top must be >= 1, got {args.top}")
    depth_range = DepthRange.parse(args.depth_range)
    image = Path(args.image)
    rgb = depth = depth_file = None
    if image.suffix.lower() in (".tif", ".tiff"):
        depth, depth_file = formats.read_depth_tiff(image), image
    else:
        rgb = formats.read_rgb(image)
    if args.depth:
        depth, depth_file = formats.read_depth_tiff(args.depth), Path(args.depth)
    if depth is not None:
        check = check_depth(depth, depth_range)
        problem = check.problem()
        if problem and check.valid_count == 0 and (check.near or check.far):
            problem += "; --depth-range MIN,MAX sets the range"
        if problem:
            raise InputError(problem, file=str(depth_file))
    intrinsics, pose = _camera(args)
    predictor = GraspPredictor.load(args.weights or default_weights(), depth_range=depth_range)
    found = predictor.detect(rgb=rgb, depth=depth, intrinsics=intrinsics, X_WC=pose, n=args.top)
    grasps = found.grasps
    if not grasps:
        where = f"{depth_file}: " if depth_file is not None else ""
        raise InfeasibleError(f"{where}no grasp: {found.reason}")
    if args.json:
        print_json([g.as_dict() for g in grasps])
    else:
        for g in grasps:
            line = (
                f"pixel ({g.u:.1f}, {g.v:.1f}) angle {g.angle_deg:.1f} deg width "
                f"{g.width_px:.1f} px quality {g.quality:.3f}"
            )
            if g.position is not None:
                x, y, z = g.position
                line += (
                    f" | world ({x:.3f}, {y:.3f}, {z:.3f}) m yaw {g.yaw_deg:.1f} deg "
                    f"width {g.width_m * 100:.1f} cm"
                )
            print(line)
    return 0
