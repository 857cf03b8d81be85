"""How many threads torch may use for a network called inside a simulation step.

A workcell calls small networks (the detector's crop classifier, a grasp network) from its
Drake systems; campaigns run one simulation per core. With torch's default intra-op threads
(one per core) each call's second thread spin-waits for a core another process holds: on
the 2-core machine one HRG-Net call on a 180 px crop took 6-9 s of wall time and 1.0-1.4 s
of CPU (load average 14) against 0.5-0.7 s and 63-75 ms with one thread (measured in the
LOTS workcell). Every such call runs inside `torch_threads` (`INFERENCE_THREADS`).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

#: torch intra-op threads for a network called inside a simulation step
INFERENCE_THREADS = 1


@contextmanager
def torch_threads(n: int = INFERENCE_THREADS) -> Iterator[None]:
    """Run the block with ``n`` torch intra-op threads, then restore the previous number."""
    import torch

    before = torch.get_num_threads()
    if before != n:
        torch.set_num_threads(n)
    try:
        yield
    finally:
        if before != n:
            torch.set_num_threads(before)
