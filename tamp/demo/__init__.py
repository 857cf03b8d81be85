"""Demonstration layer (SMP-MRO §IV-A): MR frames, goals G and ordering constraints C."""

from tamp.demo.build import cyclic_swap, make_demonstration
from tamp.demo.frames import UNITY_TO_ROS, MRFrame
from tamp.demo.loader import demonstration_from_dict, load_demonstration
from tamp.demo.model import Demonstration, Goal

__all__ = [
    "UNITY_TO_ROS",
    "Demonstration",
    "Goal",
    "MRFrame",
    "cyclic_swap",
    "demonstration_from_dict",
    "load_demonstration",
    "make_demonstration",
]
