"""The communication architecture (Table 1, Fig. 2, Fig. 8) as a network of FIFO servers.

Per robot: sensors ``S`` (force, IMU, odometry) sample at the sensor rate; the main CPU
``C1`` reads every sample and publishes one command message per control cycle (rate P)
with the setpoints of the robot's sections; sub-CPUs ``C2`` run the drivers; ``CC`` is
the communication channel between sub-CPUs and the main CPU. The categories differ in
what is shared (routes below; ``→`` is one hop, each a FIFO server):

- Category I (each S and each A has its own C): ``S_i → C2.S_i → C1`` and
  ``C1 → C2.A``. Sensors and commands meet only at the main CPU.
- Category II (sensors share a sub-CPU, actuators share another, one channel):
  ``S_i → C2.S → CC → C1`` and ``C1 → CC → C2.A``. They meet at the channel and at C1.
- Category III (sensors and actuators share one sub-CPU): ``S_i → C2 → CC → C1`` and
  ``C1 → CC → C2``. They meet at the sub-CPU, the channel and C1.

Each server has one service time per message kind (sensor sample, command). The numbers
are calibrated once per category (the packaged ``scenarios/refine/architecture.yaml``,
documented in docs/refinement.md) and never per task. The same file holds the
rate-search parameters of Fig. 5: the wait margin, the rate step and the probe window.

"Arrives without delay" (Fig. 5, Step 2) is read as: the sample waited no longer than an
unloaded network explains, i.e. at most one command message and the other sensors' samples
ahead of it at each server on its route (`Architecture.wait_threshold`), plus a small
margin. Below the knee (every ρ < 1) the waits of periodic streams stay at that level;
past it the backlog grows every second and the threshold is crossed within the probe
window.

Architecture file::

    version: 1
    name: pioneer_pair
    wait_margin: 0.005          # s above the unloaded worst wait that counts as "delayed"
    rate_step_hz: 1.0           # Fig. 5: P grows by this step
    probe_window: 4.0           # s of sensor data judged at each rate
    categories:
      I:   {main_cpu: {sensor: s, command: s}, sub_cpu: {sensor: s, command: s}}
      II:  {main_cpu: {...}, sub_cpu: {...}, channel: {sensor: s, command: s}}
      III: {main_cpu: {...}, sub_cpu: {...}, channel: {...}}
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from tamp.fileio import Fields, load_yaml
from tamp.refine.program import CATEGORIES, SENSORS
from tamp.refine.queues import Hop, Network, max_wait, periodic_waits
from tamp.refine.steps import RateSearch

COMMAND = "command"  # the stream of command messages (one per control cycle)
MAIN = "C1"
CHANNEL = "CC"


@dataclass(frozen=True)
class ServiceTimes:
    """Seconds a server spends on one sensor sample / one command message."""

    sensor: float
    command: float


@dataclass(frozen=True)
class CategoryModel:
    """Service times of one category's servers (``channel`` is None in Category I)."""

    main_cpu: ServiceTimes
    sub_cpu: ServiceTimes
    channel: ServiceTimes | None = None


@dataclass(frozen=True)
class Architecture:
    """Calibrated service times per category and the parameters of the rate search."""

    categories: Mapping[str, CategoryModel]
    wait_margin: float
    rate_step_hz: float
    probe_window: float
    name: str = "architecture"
    file: str | None = None

    def network(self, category: str, sensors: Sequence[str] = SENSORS) -> Network:
        """The FIFO network of one robot in ``category`` (routes in the module docstring)."""
        m = self.categories[category]
        routes: dict[str, tuple[Hop, ...]] = {}
        for s in sensors:
            main = Hop(MAIN, m.main_cpu.sensor)
            if category == "I":
                routes[s] = (Hop(f"C2.{s}", m.sub_cpu.sensor), main)
            else:
                sub = "C2.S" if category == "II" else "C2"
                assert m.channel is not None
                routes[s] = (Hop(sub, m.sub_cpu.sensor), Hop(CHANNEL, m.channel.sensor), main)
        cmd = Hop(MAIN, m.main_cpu.command)
        if category == "I":
            routes[COMMAND] = (cmd, Hop("C2.A", m.sub_cpu.command))
        else:
            sub = "C2.A" if category == "II" else "C2"
            assert m.channel is not None
            routes[COMMAND] = (cmd, Hop(CHANNEL, m.channel.command), Hop(sub, m.sub_cpu.command))
        return Network(routes)

    def wait_threshold(self, category: str, sensor: str, sensors: Sequence[str] = SENSORS) -> float:
        """Longest wait of a ``sensor`` sample that is not "delayed": at each server of its
        route one command and every other sensor's sample ahead of it, plus the margin."""
        net = self.network(category, sensors)
        total = self.wait_margin
        for hop in net.routes[sensor]:
            ahead = [h.service for h in net.routes[COMMAND] if h.server == hop.server]
            for other in sensors:
                if other != sensor:
                    ahead += [h.service for h in net.routes[other] if h.server == hop.server]
            total += sum(ahead)
        return total

    def search(
        self,
        category: str,
        current: float,
        sensor_rate: float,
        watched: Sequence[str] = SENSORS,
        sensors: Sequence[str] = SENSORS,
    ) -> RateSearch:
        """Fig. 5's search from the current rate, judging the ``watched`` sensors (the
        triggers of the behavior) against their thresholds; P never exceeds the sensor
        rate."""
        threshold = min(self.wait_threshold(category, s, sensors) for s in watched)
        return RateSearch(current, self.rate_step_hz, threshold, limit=sensor_rate)

    def probe_wait(
        self,
        category: str,
        sensor_rate: float,
        rate: float,
        watched: Sequence[str] = SENSORS,
        sensors: Sequence[str] = SENSORS,
    ) -> float:
        """The queue model's measurement of one probe: the longest wait of the ``watched``
        sensors' samples during ``probe_window`` at command rate ``rate``, every stream
        starting together on an empty network."""
        net = self.network(category, sensors)
        waits = periodic_waits(net, self.rates(sensor_rate, rate, sensors), self.probe_window)
        return max_wait(waits, watched)

    def rates(
        self, sensor_rate: float, command_rate: float, sensors: Sequence[str] = SENSORS
    ) -> dict[str, float]:
        """Message rates of every stream (for `Network.utilisation` and `periodic_waits`)."""
        out = {s: sensor_rate for s in sensors}
        out[COMMAND] = command_rate
        return out


def _times(f: Fields, key: str) -> ServiceTimes:
    t = f.sub(key)
    t.check_keys(("sensor", "command"))
    return ServiceTimes(t.float("sensor", min=0.0), t.float("command", min=0.0))


def load_architecture(path: str | Path) -> Architecture:
    """Read and validate an architecture file (`InputError` naming file and field)."""
    data, file = load_yaml(path, kind="architecture")
    f = Fields(data, file)
    f.check_keys(
        (
            "version",
            "name",
            "description",
            "wait_margin",
            "rate_step_hz",
            "probe_window",
            "categories",
        )
    )
    cats = f.sub("categories")
    cats.check_keys(CATEGORIES)
    models: dict[str, CategoryModel] = {}
    for cat in CATEGORIES:
        c = cats.sub(cat)
        if cat == "I":
            c.check_keys(("main_cpu", "sub_cpu"))
            models[cat] = CategoryModel(_times(c, "main_cpu"), _times(c, "sub_cpu"))
        else:
            c.check_keys(("main_cpu", "sub_cpu", "channel"))
            models[cat] = CategoryModel(
                _times(c, "main_cpu"), _times(c, "sub_cpu"), _times(c, "channel")
            )
    return Architecture(
        categories=models,
        wait_margin=f.float("wait_margin", min=0.0),
        rate_step_hz=f.float("rate_step_hz", min=0.0, strict_min=True),
        probe_window=f.float("probe_window", min=0.0, strict_min=True),
        name=f.str("name", Path(file).stem),
        file=file,
    )


def default_architecture() -> Architecture:
    """The packaged, calibrated architecture (``scenarios/refine/architecture.yaml``)."""
    from tamp.scenarios import path

    return load_architecture(path("refine/architecture.yaml"))
