"""The registry of grasp networks: one entry per network, read by every place that names one.

HRG-Net (Zhou et al., IEEE T-ASE 2023, §IV-B, Fig. 5) and the two baselines it is compared
with in §V-A (GG-CNN [49], GR-ConvNet [57]) are registered here with their constructor, the
weights file shipped for them in ``tamp/models/weights`` and their input. The grasp CLI
(``tamp grasp train --model``), the LOTS workcell (``grasp.network`` of a scenario file,
``tamp simulate lots --grasp``), training and the benchmarks take their names from
:data:`NETWORKS`.

No torch here: the scenario loader and ``tamp --help`` read the registry without loading it.
The network classes (`tamp.grasp.models`) are imported when a model is built.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

#: Input modes and their channel counts: depth, colour, colour + depth.
INPUT_CHANNELS = {"d": 1, "rgb": 3, "rgbd": 4}
#: HRG-Net's layer-fusion settings (`tamp.grasp.models.HRGNet`; "none" is Table IV's ablation).
FUSION_MODES = ("full", "final", "none")
#: Folder of the shipped weights, relative to the project's ``models/`` folder.
WEIGHTS_FOLDER = "weights"


@dataclass(frozen=True)
class GraspNetwork:
    """One grasp network: how to build it, and the weights shipped for it.

    ``constructor`` is ``"module:Class"``, imported only by :meth:`model_class` so that the
    registry loads without torch; the class takes the input channel count first.
    ``weights_file`` lies in ``tamp/models/weights`` and was trained for input ``input``.
    ``fusion``: the constructor takes HRG-Net's ``fusion`` setting (:data:`FUSION_MODES`).
    """

    name: str
    title: str
    constructor: str
    weights_file: str
    input: str
    citation: str
    fusion: bool = False

    @property
    def input_channels(self) -> int:
        """Channels of the input the shipped weights expect."""
        return INPUT_CHANNELS[self.input]

    @property
    def weights(self) -> str:
        """The shipped weights file relative to the ``models/`` folder (the ``tamp_models``
        package: `tamp.sim.core.models.models_dir`)."""
        return f"{WEIGHTS_FOLDER}/{self.weights_file}"

    def model_class(self) -> type:
        """The network's ``torch.nn.Module`` class (imports torch)."""
        module, _, cls = self.constructor.partition(":")
        return getattr(importlib.import_module(module), cls)


#: Every grasp network by name; the first is the default (the paper's own).
NETWORKS: dict[str, GraspNetwork] = {
    net.name: net
    for net in (
        GraspNetwork(
            name="hrgnet",
            title="HRG-Net",
            constructor="tamp.grasp.models:HRGNet",
            weights_file="hrgnet_synth_rgbd.pt",
            input="rgbd",
            citation="Zhou et al., IEEE T-ASE 2023, §IV-B, Fig. 5",
            fusion=True,
        ),
        GraspNetwork(
            name="grconvnet",
            title="GR-ConvNet",
            constructor="tamp.grasp.models:GRConvNet",
            weights_file="grconvnet_synth_rgbd.pt",
            input="rgbd",
            citation="Kumra, Joshi and Sahin, IEEE/RSJ IROS 2020 ([57] of Zhou et al.)",
        ),
        GraspNetwork(
            name="ggcnn",
            title="GG-CNN",
            constructor="tamp.grasp.models:GGCNN",
            weights_file="ggcnn_synth_rgbd.pt",
            input="rgbd",
            citation="Morrison, Corke and Leitner, RSS 2018 ([49] of Zhou et al.)",
        ),
    )
}
#: The network used when none is named: HRG-Net.
DEFAULT_NETWORK = next(iter(NETWORKS))


def network(name: str) -> GraspNetwork:
    """The registered network ``name``; ValueError naming the known ones otherwise."""
    try:
        return NETWORKS[name]
    except KeyError:
        raise ValueError(f"unknown model {name!r}; expected one of {list(NETWORKS)}") from None
