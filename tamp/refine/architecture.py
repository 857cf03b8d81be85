"""The communication architecture (Table 1, Fig. 2, Fig. 8) as a network of FIFO servers.

Per robot: sensors ``S`` (force, IMU, odometry) sample at their own rates (the file's
``sensor_rates_hz``; a sensor not named samples at the program's sensor rate); the main
CPU ``C1`` reads every sample and publishes one command message per control cycle (rate P)
with the setpoints of the robot's sections; sub-CPUs ``C2`` run the drivers; ``CC`` is the
communication channel between sub-CPUs and the main CPU. The categories differ in what is
shared (routes below; ``→`` is one hop, each a FIFO server):

- Category I (each S and each A has its own C): ``S_i → C2.S_i → C1`` and
  ``C1 → C2.A``. Sensors and commands meet only at the main CPU.
- Category II (sensors share a sub-CPU, actuators share another, one channel):
  ``S_i → C2.S → CC → C1`` and ``C1 → CC → C2.A``. They meet at the channel and at C1.
- Category III (sensors and actuators share one sub-CPU): ``S_i → C2 → CC → C1`` and
  ``C1 → CC → C2``. They meet at the sub-CPU, the channel and C1.

Each server has one service time per message kind (sensor sample, command). The load of a
command message may depend on the behavior that sends it (Figueroa Heredia et al. 2018
§3.3: the rate "can be calculated according to the event assigned for each behavior"): a
server's ``sections`` give the service of a command while that section moves, where it
differs from ``command`` (e.g. a base command carries both wheels' setpoints). Such a
command is its own stream, ``command.<section>`` (`command_stream`); a command that moves
several sections (parallel behaviors) is the stream of the heaviest. The numbers are
calibrated once per category (the packaged ``scenarios/refine/architecture.yaml``; their
derivation in docs/refinement.md) and never per task. The same file holds the rate-search
parameters of Fig. 5: the wait margin, the rate step and the probe window.

"Arrives without delay" (Fig. 5, Step 2) is read as: the sample waited no longer than an
unloaded network explains, i.e. at most one command message and one sample of each other
sensor ahead of it at each server on its route (`Architecture.wait_threshold`), plus a
small margin. Below the knee (every ρ < 1) the waits of periodic streams stay at that
level; past it the backlog grows every second and the threshold is crossed within the
probe window.

Architecture file (read with `tamp.schema`; `tamp.schema.describe(Architecture)` lists
every field with its default)::

    version: 1
    name: pioneer_pair
    wait_margin: 0.005          # s above the unloaded worst wait that counts as "delayed"
    rate_step_hz: 1.0           # Fig. 5: P grows by this step
    probe_window: 4.0           # s of sensor data judged at each rate
    sensor_rates_hz: {odometry: 50}   # optional: a sensor's own rate (Hz)
    max_command_rate_hz: 50     # optional: the main CPU's fastest loop (default 50 Hz)
    categories:
      I:   {main_cpu: {sensor: s, command: s}, sub_cpu: {sensor: s, command: s}}
      II:  {main_cpu: {...}, sub_cpu: {...}, channel: {sensor: s, command: s}}
      III: {main_cpu: {...}, sub_cpu: {...}, channel: {..., sections: {base: s}}}
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from tamp.fileio import Fields, load_yaml
from tamp.refine.program import CATEGORIES, SECTIONS, SENSORS, Program, event_id
from tamp.refine.queues import Hop, Network, max_wait, periodic_waits
from tamp.refine.steps import RateSearch, refine_rate
from tamp.schema import load_dataclass, spec

COMMAND = "command"  # the stream of command messages (one per control cycle)
MAIN = "C1"
CHANNEL = "CC"

#: A command's load: None (the plain ``command``) or the sections it moves.
Load = str | Sequence[str] | None


def _non_negative(f: Fields, key: str, values: Mapping[str, float], what: str) -> None:
    for k, v in values.items():
        if not v >= 0.0:
            raise f.sub(key).error(k, f"{what} must be >= 0, got {v!r}")


@dataclass(frozen=True)
class ServiceTimes:
    """Seconds a server spends on one sensor sample / one command message (``sections``:
    a command while that section moves, where it differs)."""

    sensor: float = spec(min=0.0, unit="s", help="one sensor sample")
    command: float = spec(min=0.0, unit="s", help="one command message")
    sections: Mapping[str, float] = spec(
        {},
        choices=SECTIONS,
        unit="s",
        help="one command message while this section moves, where it differs from command "
        "(the behavior's load)",
    )

    def check(self, f: Fields) -> None:
        _non_negative(f, "sections", self.sections, "a service time")

    def command_for(self, section: str | None) -> float:
        """The service of a command moving ``section`` (None: the plain command)."""
        return self.sections.get(section or "", self.command)


@dataclass(frozen=True)
class CategoryModel:
    """Service times of one category's servers (``channel`` is None in Category I)."""

    main_cpu: ServiceTimes = spec(help="the main CPU C1")
    sub_cpu: ServiceTimes = spec(help="the sub-CPUs C2 (drivers)")
    channel: ServiceTimes | None = spec(None, help="the channel CC (Categories II and III)")


@dataclass(frozen=True)
class Architecture:
    """Calibrated service times per category, the sensors' own rates and the parameters
    of the rate search (module docstring)."""

    categories: Mapping[str, CategoryModel] = spec(choices=CATEGORIES, help="I, II and III")
    wait_margin: float = spec(min=0.0, unit="s", help="queueing above the unloaded worst wait")
    rate_step_hz: float = spec(min=0.0, strict_min=True, unit="Hz", help="Fig. 5's step of P")
    probe_window: float = spec(
        min=0.0, strict_min=True, unit="s", help="sensor data judged at each rate"
    )
    sensor_rates_hz: Mapping[str, float] = spec(
        {},
        choices=SENSORS,
        unit="Hz",
        help="a sensor's own sample rate; a sensor not named samples at the program's sensor rate",
    )
    max_command_rate_hz: float = spec(
        50.0,
        min=0.0,
        strict_min=True,
        unit="Hz",
        help="the fastest the main CPU's loop sends commands: P never exceeds it (the "
        "workcell sends at most one command per tick, 20 ms at the coarsest)",
    )
    name: str | None = spec(None, help="default: the file's stem")
    description: str = spec("")
    file: str | None = None

    def check(self, f: Fields) -> None:
        cats = f.sub("categories")
        for cat in CATEGORIES:
            if cat not in self.categories:
                raise cats.error(cat, "missing field")
            has = self.categories[cat].channel is not None
            if has != (cat != "I"):
                what = "has no channel (own links)" if cat == "I" else "needs a channel"
                raise cats.sub(cat).error("channel", f"Category {cat} {what}")
        for k, v in self.sensor_rates_hz.items():
            if not v > 0.0:
                raise f.sub("sensor_rates_hz").error(k, f"a rate must be > 0, got {v!r}")

    # ------------------------------------------------------------------ the network

    def sensor_rate(self, sensor: str, default: float) -> float:
        """The rate ``sensor`` samples at: its own, else the program's ``default``."""
        return self.sensor_rates_hz.get(sensor, default)

    def command_stream(self, category: str, load: Load = None) -> str:
        """The stream of a command moving the sections ``load``: ``command.<section>`` of
        the section whose command costs most along the route (ties: the first), or
        ``command`` when no server gives the sections a service of their own."""
        sections = (load,) if isinstance(load, str) else tuple(load or ())
        m = self.categories[category]
        servers = [x for x in (m.main_cpu, m.sub_cpu, m.channel) if x is not None]
        best, cost = COMMAND, sum(x.command for x in servers)
        for sec in sections:
            c = sum(x.command_for(sec) for x in servers)
            if c > cost + 1e-15:
                best, cost = f"{COMMAND}.{sec}", c
        return best

    def network(self, category: str, sensors: Sequence[str] = SENSORS) -> Network:
        """The FIFO network of one robot in ``category`` (routes in the module docstring),
        with a ``command.<section>`` stream per section besides ``command``."""
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
        for section in (None, *SECTIONS):
            stream = COMMAND if section is None else f"{COMMAND}.{section}"
            cmd = Hop(MAIN, m.main_cpu.command_for(section))
            if category == "I":
                routes[stream] = (cmd, Hop("C2.A", m.sub_cpu.command_for(section)))
            else:
                sub = "C2.A" if category == "II" else "C2"
                assert m.channel is not None
                routes[stream] = (
                    cmd,
                    Hop(CHANNEL, m.channel.command_for(section)),
                    Hop(sub, m.sub_cpu.command_for(section)),
                )
        return Network(routes)

    def wait_threshold(
        self,
        category: str,
        sensor: str,
        sensors: Sequence[str] = SENSORS,
        load: Load = None,
    ) -> float:
        """Longest wait of a ``sensor`` sample that is not "delayed": at each server of its
        route one command (of ``load``) and one sample of every other sensor ahead of it,
        plus the margin."""
        net = self.network(category, sensors)
        command = net.routes[self.command_stream(category, load)]
        total = self.wait_margin
        for hop in net.routes[sensor]:
            ahead = [h.service for h in command if h.server == hop.server]
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
        load: Load = None,
    ) -> RateSearch:
        """Fig. 5's search from the current rate, judging the ``watched`` sensors (the
        triggers of the behavior) against their thresholds under the behavior's ``load``;
        P never exceeds the rate of the slowest watched sensor (``sensor_rate``: the
        program's, for sensors without one of their own) nor ``max_command_rate_hz``."""
        threshold = min(self.wait_threshold(category, s, sensors, load) for s in watched)
        limit = min(self.sensor_rate(s, sensor_rate) for s in watched)
        limit = min(limit, self.max_command_rate_hz)
        return RateSearch(current, self.rate_step_hz, threshold, limit=limit)

    def probe_wait(
        self,
        category: str,
        sensor_rate: float,
        rate: float,
        watched: Sequence[str] = SENSORS,
        sensors: Sequence[str] = SENSORS,
        load: Load = None,
    ) -> float:
        """The queue model's measurement of one probe: the longest wait of the ``watched``
        sensors' samples during ``probe_window`` at command rate ``rate`` (commands of
        ``load``), every stream starting together on an empty network."""
        net = self.network(category, sensors)
        rates = self.rates(sensor_rate, rate, sensors, self.command_stream(category, load))
        waits = periodic_waits(net, rates, self.probe_window)
        return max_wait(waits, watched)

    def rates(
        self,
        sensor_rate: float,
        command_rate: float,
        sensors: Sequence[str] = SENSORS,
        command: str = COMMAND,
    ) -> dict[str, float]:
        """Message rates of every stream (for `Network.utilisation` and `periodic_waits`):
        each sensor at its own rate (else ``sensor_rate``), the ``command`` stream at
        ``command_rate``."""
        out = {s: self.sensor_rate(s, sensor_rate) for s in sensors}
        out[command] = command_rate
        return out


# ----------------------------------------------------------------- Fig. 5 offline


def behavior_loads(program: Program, robot: str) -> dict[str, tuple[str, ...]]:
    """Behavior name -> the sections its commands move: its own, or, in a parallel group
    (one command stream), every section of the group."""
    r = program.robot(robot)
    out: dict[str, tuple[str, ...]] = {}
    for group in r.groups():
        sections = tuple(dict.fromkeys(r.behaviors[i].section for i in group))
        for i in group:
            out[r.behaviors[i].name] = sections
    return out


def trigger_sensors(program: Program, robot: str) -> tuple[str, ...]:
    """The sensors that trigger robot ``robot``'s events (Fig. 5, Step 2)."""
    r = program.robot(robot)
    return tuple(sorted({b.event.sensor for b in r.behaviors if b.event.sensor}))


def behavior_searches(program: Program, architecture: Architecture) -> dict[str, RateSearch]:
    """Fig. 5 run on the architecture's queue model, behavior by behavior (Step 4), keyed by
    event id ``ROBOT.BEHAVIOR``: from the behavior's current rate, P rises while the sensor
    that triggers its event (one triggered by another robot's event: every trigger sensor
    of its robot; a robot with none: force) delivers without delay under the behavior's
    command load. The same model runs in the simulation's Channel, which confirms the rates
    in the run of the refined program."""
    c = program.communication
    out: dict[str, RateSearch] = {}
    for r in program.robots:
        loads = behavior_loads(program, r.name)
        own = trigger_sensors(program, r.name) or ("force",)
        for b in r.behaviors:
            watched = (b.event.sensor,) if b.event.sensor else own
            stream = architecture.command_stream(c.category, loads[b.name])
            # the search is a function of these alone (deterministic queues): done once
            key = (repr(architecture), c.category, c.sensor_rate_hz, program.rate(b))
            key += (watched, stream)
            if key not in _SEARCHES:
                search = architecture.search(
                    c.category, program.rate(b), c.sensor_rate_hz, watched, load=loads[b.name]
                )
                _SEARCHES[key] = refine_rate(
                    search,
                    lambda rate, w=watched, ld=loads[b.name]: architecture.probe_wait(
                        c.category, c.sensor_rate_hz, rate, w, load=ld
                    ),
                )
            out[event_id(r.name, b.name)] = _SEARCHES[key]
    return out


#: searches `behavior_searches` has run in this process, by everything they depend on
_SEARCHES: dict[tuple, RateSearch] = {}


def load_architecture(path: str | Path) -> Architecture:
    """Read and validate an architecture file (`InputError` naming file and field)."""
    data, file = load_yaml(path, kind="architecture")
    arch = load_dataclass(Architecture, Fields(data, file), extra_keys=("version",))
    return dataclasses.replace(
        arch, name=arch.name or Path(file).stem, description=arch.description.strip(), file=file
    )


def default_architecture() -> Architecture:
    """The packaged, calibrated architecture (``scenarios/refine/architecture.yaml``)."""
    from tamp.scenarios import path

    return load_architecture(path("refine/architecture.yaml"))
