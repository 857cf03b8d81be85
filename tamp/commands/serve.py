"""`tamp serve`: a rosbridge v2 server for live demonstrations from MR, Python and a browser.

``tamp serve [--host 127.0.0.1] [--port 9090] [--token T] [--origin URL]... [--sim]
[--rate R] [--demo DEMO.yaml] [--max-clients N] [--max-message BYTES] [--plan-timeout S]``

ROS# (the HoloLens apps of SMP-MRO), roslibpy and roslibjs connect to
``ws://HOST:PORT/`` (``?token=T`` when a token is set); ``http://HOST:PORT/`` serves the
browser demonstration page. A live demonstration is planned by the same pipeline as
``tamp plan`` (goals and constraints, RG, A*, the verification gate) and executed like
``tamp plan --execute`` in the symbolic world, or with ``--sim`` in the Drake youBot cell
of ``tamp simulate smp-mro``. Binds to localhost unless ``--host`` says otherwise.
"""

from __future__ import annotations

import argparse
import functools
import math
import tempfile
import time
from pathlib import Path
from typing import Any

from tamp.errors import InputError

DEFAULT_WORKSPACE = {"x": [-1.0, 4.5], "y": [-2.2, 2.8]}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "serve",
        help="serve live demonstrations over rosbridge (ROS#, roslibpy, roslibjs, a web page)",
        description=__doc__.splitlines()[0],
    )
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    p.add_argument("--port", type=int, default=9090, help="port (default 9090; 0: any free)")
    p.add_argument("--token", help="require ?token=T in the URL (browsers cannot set headers)")
    p.add_argument(
        "--origin",
        action="append",
        default=[],
        metavar="URL",
        help="a browser origin allowed besides this server's own page (repeatable; '*': any)",
    )
    p.add_argument(
        "--sim", action="store_true", help="execute in the Drake youBot cell (tamp simulate)"
    )
    p.add_argument(
        "--rate",
        type=float,
        default=1.0,
        metavar="R",
        help="with --sim: the simulation's pace, R x real time (default 1: a person watches; "
        "0: as fast as possible)",
    )
    p.add_argument(
        "--demo",
        metavar="DEMO.yaml",
        help="start with this demonstration's scene (objects, areas; its steps are not used)",
    )
    p.add_argument("--max-clients", type=int, default=8, metavar="N", help="default 8")
    p.add_argument(
        "--max-message", type=int, default=1 << 20, metavar="BYTES", help="default 1 MiB"
    )
    p.add_argument("--plan-timeout", type=float, default=120.0, metavar="S", help="default 120 s")
    p.set_defaults(func=run)


def check_arguments(args: argparse.Namespace) -> None:
    """Bad options are one line naming the option (exit 2)."""
    if not 0 <= args.port <= 65535:
        raise InputError(f"must be 0 to 65535, got {args.port}", field="--port")
    if not 1 <= args.max_clients <= 1000:
        raise InputError(f"must be 1 to 1000, got {args.max_clients}", field="--max-clients")
    if not 1024 <= args.max_message <= 64 << 20:
        raise InputError(
            f"must be 1024 to {64 << 20} bytes, got {args.max_message}", field="--max-message"
        )
    if not (math.isfinite(args.plan_timeout) and 0 < args.plan_timeout <= 3600):
        raise InputError(f"must be 0 to 3600 s, got {args.plan_timeout}", field="--plan-timeout")
    if not (math.isfinite(args.rate) and 0 <= args.rate <= 100):
        raise InputError(f"must be 0 to 100, got {args.rate}", field="--rate")
    if args.token is not None and not (8 <= len(args.token) <= 256 and args.token.isprintable()):
        raise InputError("must be 8 to 256 printable characters", field="--token")
    for o in args.origin:
        if o != "*" and not o.startswith(("http://", "https://")):
            raise InputError(f"{o[:60]!r}: expected http(s)://HOST[:PORT] or *", field="--origin")


def plan_demo(demo: Any, cost: str) -> Any:
    """What ``tamp plan`` does to a demonstration: RG, A*, the order's verification gate."""
    from tamp.rg import plan
    from tamp.verification.gate import gate_order

    result = plan(demo, cost)
    gate_order(result)
    return result


def execute_symbolic(
    demo: Any, result: Any, mapping: dict[str, Any], channel: Any
) -> dict[str, Any]:
    """What ``tamp plan --execute --json`` prints for this plan (its defaults, gate on).
    A symbolic run takes milliseconds: its events are published when it ends."""
    from tamp.commands.execute_args import execution_payload

    args = argparse.Namespace(
        appear=[],
        fail=[],
        skill_ticks=1,
        max_ticks=None,
        max_expansions=None,
        verify_budget=None,
        bt_xml=None,
        bt_dot=None,
    )
    _, doc, _ = execution_payload(args, demo, result, verify=True)
    return doc


def execute_sim(
    demo: Any, result: Any, mapping: dict[str, Any], channel: Any, *, rate: float = 0.0
) -> dict[str, Any]:
    """The Drake youBot cell of ``tamp simulate smp-mro`` on the live demonstration (the
    exported demonstration beside a scenario file with the packaged cases' settings), run at
    ``rate`` × real time (0: as fast as possible). While it runs, the channel gets each
    action's start and end, appearances, the running action, the robot's pose and its
    joints; a cancelled channel stops the simulation between two chunks."""
    import yaml

    from tamp.serve import RunCancelled
    from tamp.sim.smp.robot import ROBOT
    from tamp.sim.smp.simulate import WORKCELL, simulate

    live = mapping
    seen: set[tuple[int, str | None]] = set()
    appeared: set[str] = set()
    last = [-1.0]

    def progress(t: float, runner: Any) -> None:
        if channel.cancelled:
            raise RunCancelled
        s = runner.system
        ex = s.executor.state(s.executor.GetMyContextFromRoot(runner.root))
        running = None
        for rec in ex.log:
            if rec.status is None:
                running = rec.action
            if (rec.id, rec.status) in seen:
                continue
            seen.add((rec.id, rec.status))
            if rec.status is None:
                channel.event("start", what=rec.action, t=round(rec.start, 3))
            else:
                kind = "success" if rec.status in ("SUCCESS", "HALTED") else "failure"
                channel.event(kind, what=rec.action, t=round(rec.end or t, 3))
        for obj in sorted(set(runner.appeared) - appeared):
            appeared.add(obj)
            channel.event("appear", what=obj, t=round(runner.appeared[obj], 3))
        now = time.monotonic()
        if now - last[0] >= 0.1:  # at most 10 updates a second of the streams
            last[0] = now
            x, y, yaw = runner.robot_pose()
            channel.robot(x, y, yaw)
            channel.bt(t=round(t, 3), running=running)
            q = s.plant.GetPositions(runner.plant_context, s.robot)
            channel.joints(list(ROBOT.joints)[: len(q)], list(q))

    with tempfile.TemporaryDirectory(prefix="tamp-serve-") as tmp:
        Path(tmp, "demo.yaml").write_text(yaml.safe_dump(live, sort_keys=False))
        scenario = {
            "version": 1,
            "name": str(live.get("name", "live")),
            "demonstration": "demo.yaml",
            "planner": {"cost": result.cost_model},
            "plant": {"time_step": 0.01},
            "executor": {"bt_period": 0.1, "controller_period": 0.02, "max_sim_time": 300},
            "base": {"max_speed": 0.5, "max_accel": 0.6, "max_yaw_rate": 1.2, "max_yaw_accel": 2.0},
            "workspace": DEFAULT_WORKSPACE,
        }
        extra = sorted({a.obj for a in demo.appear} - set(demo.objects))
        if extra:  # the cell stages appearances from its own list (robot frame)
            scenario["objects"] = [{"id": o, "model": "obstacle"} for o in extra]
            scenario["appear"] = [str(a) for a in demo.appear if a.obj in extra]
        Path(tmp, "scenario.yaml").write_text(yaml.safe_dump(scenario, sort_keys=False))
        loaded = WORKCELL.load(str(Path(tmp, "scenario.yaml")))
    run = simulate(loaded, realtime_rate=rate, progress=progress)
    doc = run.to_json()
    doc["executed"] = [a["action"] for a in doc.get("actions", []) if a["status"] == "SUCCESS"]
    doc["reached"] = bool(doc.get("ok"))
    doc["live"] = True
    if run.base_path:
        doc["final_world"] = {
            "robot": list(run.base_path[-1]),
            "objects": {k: [p.x, p.y, 0.0] for k, p in sorted(run.final_poses.items())},
        }
    return doc


def make_app(args: argparse.Namespace) -> Any:
    """The server and its app for these options (tests build theirs the same way)."""
    from tamp.serve import Limits, Pipeline, RosbridgeServer, TampApp

    web = Path(__file__).resolve().parents[1] / "serve" / "web"
    server = RosbridgeServer(
        limits=Limits(max_clients=args.max_clients, max_message=args.max_message),
        token=args.token,
        origins=args.origin,
        web_root=web,
    )
    pipeline = Pipeline(
        plan=plan_demo,
        execute=functools.partial(execute_sim, rate=args.rate) if args.sim else execute_symbolic,
        name="drake youBot cell" if args.sim else "symbolic",
    )
    app = TampApp(server, pipeline, plan_timeout=args.plan_timeout)
    if args.demo:
        from tamp.fileio import load_yaml
        from tamp.scenarios import resolve

        data, _ = load_yaml(resolve(args.demo), kind="demonstration")
        app.open_file(data, args.demo)
    return server, app


def run(args: argparse.Namespace) -> int:
    import asyncio
    import logging

    check_arguments(args)
    server, _ = make_app(args)
    log = logging.getLogger("tamp")

    async def main() -> None:
        try:
            port = await server.start(args.host, args.port)
        except OSError as exc:
            raise InputError(
                f"cannot listen on {args.host}:{args.port}: {exc.strerror}", field="--port"
            ) from None
        query = f"?token={args.token}" if args.token else ""
        log.info(
            "rosbridge: ws://%s:%d/%s  page: http://%s:%d/%s",
            args.host,
            port,
            query,
            args.host,
            port,
            query,
        )
        if args.host not in ("127.0.0.1", "localhost", "::1"):
            log.warning(
                "listening on %s: reachable from the network%s",
                args.host,
                "" if args.token else " without a token (--token)",
            )
        await asyncio.Event().wait()

    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        log.info("stopped")
    return 0
