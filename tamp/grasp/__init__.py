"""Grasp detection (Zhou et al. §IV-B, §V-A): HRG-Net and baselines, datasets, training.

Modules: ``networks`` (the registry of networks: names, constructors, shipped weights; no
torch), ``rect`` (rectangles, IoU, the metric), ``formats`` (Cornell/Jacquard files),
``datasets`` (loaders, splits, augmentation), ``maps`` (targets and post-processing),
``models`` (HRG-Net, GG-CNN, GR-ConvNet), ``train``, ``evaluate``, ``predict`` (pixels and
world frame), ``objects`` and ``synthetic`` (the Drake-rendered dataset; only the latter
imports Drake). Torch is imported by ``models``, ``train``, ``evaluate``, not here.
"""
