"""Train / validation / test splits of a grasp dataset, and the record of one in a weights file.

Splits (§V-A): ``image`` shuffles images; ``object`` keeps all images of an object on one side.
Either takes a test fraction, or ``fold`` of ``folds`` for k-fold cross-validation (the paper's
five folds on Cornell). A validation part is carved from the non-test units (``val_fraction``
of all units), so the test part of a seed does not depend on whether a run kept a validation
part: training picks its best epoch on the validation part, never on the test part.

A weights file records the split it was trained with (:func:`split_record`): the
:class:`SplitSpec`, the dataset kind and a fingerprint of the dataset (a SHA-256 of its sorted
sample ids) and of the test part. ``tamp grasp eval`` rebuilds exactly that split by default;
:func:`split_warnings` says what is wrong when it is asked for another split or given another
dataset, and how many test images the weights have seen in training.
"""

from __future__ import annotations

import hashlib
from dataclasses import asdict, dataclass, field, fields

import numpy as np

from tamp.errors import InputError

SPLITS = ("image", "object")


@dataclass(frozen=True, slots=True)
class SplitSpec:
    """How to split: kind (image/object), seed, fractions of units, or a k-fold test fold."""

    kind: str = "image"
    seed: int = 0
    test_fraction: float = 0.1
    val_fraction: float = 0.0
    fold: int | None = None
    folds: int = 5

    def as_dict(self) -> dict:
        return asdict(self)

    @staticmethod
    def from_dict(d: dict) -> SplitSpec:
        names = {f.name for f in fields(SplitSpec)}
        return SplitSpec(**{k: v for k, v in d.items() if k in names})

    def describe(self) -> str:
        part = (
            f"fold {self.fold}/{self.folds}"
            if self.fold is not None
            else (f"test {self.test_fraction:g}")
        )
        val = f", validation {self.val_fraction:g}" if self.val_fraction else ""
        return f"{self.kind}-wise, seed {self.seed}, {part}{val}"


@dataclass(frozen=True, slots=True)
class Split:
    """Sample indices of the three parts (sorted, disjoint)."""

    train: list[int]
    val: list[int] = field(default_factory=list)
    test: list[int] = field(default_factory=list)


def make_split(groups: list[str], spec: SplitSpec) -> Split:
    """The train / validation / test indices of samples whose objects are ``groups``."""
    if spec.kind not in SPLITS:
        raise InputError(f"unknown split {spec.kind!r}; expected one of {list(SPLITS)}")
    rng = np.random.default_rng(spec.seed)
    n = len(groups)
    if spec.kind == "image":
        units = [[int(i)] for i in rng.permutation(n)]
    else:
        by_group: dict[str, list[int]] = {}
        for i, g in enumerate(groups):
            by_group.setdefault(g, []).append(i)
        keys = sorted(by_group)
        units = [by_group[keys[k]] for k in rng.permutation(len(keys))]
    if len(units) < 2:
        raise InputError(
            f"a {spec.kind}-wise split needs at least 2 {spec.kind}s, got {len(units)}"
        )
    if not 0 <= spec.val_fraction < 1:
        raise InputError(f"validation fraction must be in [0, 1), got {spec.val_fraction}")
    if spec.fold is not None:
        if not 0 <= spec.fold < spec.folds:
            raise InputError(f"fold must be in 0..{spec.folds - 1}, got {spec.fold}")
        test_units = [u for k, u in enumerate(units) if k % spec.folds == spec.fold]
        rest = [u for k, u in enumerate(units) if k % spec.folds != spec.fold]
    else:
        if not 0 < spec.test_fraction < 1:
            raise InputError(f"test fraction must be in (0, 1), got {spec.test_fraction}")
        n_test = min(max(1, int(round(len(units) * spec.test_fraction))), len(units) - 1)
        test_units, rest = units[:n_test], units[n_test:]
    n_val = 0
    if spec.val_fraction > 0:
        n_val = max(1, int(round(len(units) * spec.val_fraction)))
        if n_val >= len(rest):
            raise InputError(
                f"validation fraction {spec.val_fraction:g} leaves no {spec.kind} for training"
                f" ({len(rest)} {spec.kind}s outside the test part)"
            )
    val_units, train_units = rest[:n_val], rest[n_val:]

    def flat(us: list[list[int]]) -> list[int]:
        return sorted(i for u in us for i in u)

    return Split(flat(train_units), flat(val_units), flat(test_units))


def fingerprint(ids) -> str:
    """SHA-256 (hex, first 16 digits) of the sorted sample ids."""
    h = hashlib.sha256("\n".join(sorted(ids)).encode())
    return h.hexdigest()[:16]


def split_record(dataset, spec: SplitSpec, split: Split) -> dict:
    """What a weights file stores about the split of ``dataset`` (a
    :class:`tamp.grasp.datasets.GraspDataset`) it was trained with: plain values only, so
    that ``torch.load(weights_only=True)`` reads it."""
    ids = dataset.ids()
    return {
        "dataset": dataset.kind,
        **spec.as_dict(),
        "samples": len(ids),
        "fingerprint": fingerprint(ids),
        "test_fingerprint": fingerprint(ids[i] for i in split.test),
        "train_images": len(split.train),
        "val_images": len(split.val),
        "test_images": len(split.test),
    }


def split_warnings(record: dict | None, dataset, spec: SplitSpec, split: Split) -> list[str]:
    """Why the evaluation on ``split`` of ``dataset`` (a :class:`tamp.grasp.datasets.
    GraspDataset`) may not measure unseen data, given the weights' split ``record`` (None: the
    weights record none). Empty when the test part is the recorded one."""
    if record is None:
        return [
            "the weights record no training split, so the test images may include training "
            f"images (evaluating {spec.describe()})"
        ]
    out = []
    trained = SplitSpec.from_dict(record)
    ids = dataset.ids()
    if record.get("dataset") != dataset.kind:
        out.append(f"the weights were trained on a {record.get('dataset')} set, not {dataset.kind}")
    if record.get("fingerprint") != fingerprint(ids):
        out.append(
            f"the dataset differs from the one the weights were trained on ({len(ids)} samples,"
            f" fingerprint {fingerprint(ids)}; recorded: {record.get('samples')} samples,"
            f" {record.get('fingerprint')}), so their training images cannot be excluded"
        )
        return out
    if fingerprint(ids[i] for i in split.test) == record.get("test_fingerprint"):
        return out
    out.append(
        f"evaluating {spec.describe()}, but the weights were trained with {trained.describe()}"
    )
    if trained.kind == "object" and spec.kind == "image":
        out.append(
            "an image-wise test set holds other views of the objects these object-wise weights "
            "were trained on"
        )
    seen = dataset.split(trained)
    test = set(split.test)
    in_train = len(test & set(seen.train))
    in_val = len(test & set(seen.val))
    if in_train or in_val:
        what = f"{in_train} of the {len(test)} test images are training images of these weights"
        if in_val:
            what += f" and {in_val} chose their epoch (validation)"
        out.append(what)
    return out
