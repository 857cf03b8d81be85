"""`tamp serve` under load: 8 clients stream poses at 50 Hz while another plans and executes.

The server runs as ``tamp serve --port 0 --demo case2.yaml`` in its own process (so its CPU
time and memory are its own). On loopback, for ``--seconds``:

- 8 stream clients (raw WebSocket, as ROS# would): each advertises ``/mr/hand{i}``
  (geometry_msgs/PoseStamped) and publishes at 50 Hz with its send time in the stamp; each
  subscribes to the other seven streams (``queue_length`` 1), so the server fans out
  8 × 7 × 50 = 2,800 messages per second;
- 1 planner client (roslibpy-style calls over a raw socket): demonstrates Case 2 (begin, four
  steps), calls ``/tamp/plan``, ``/tamp/execute``, waits for ``done``, and repeats.

Reported: messages per second in (published) and out (received by the stream clients),
messages not delivered (expected deliveries minus received), split by the server's counters
into poses coalesced (a pose stream is latest-wins: a pose still waiting in a client's queue
is replaced by the newer one, so a client that falls behind gets the newest pose, not a
backlog) and messages dropped from a full queue, pose delivery latency p50 /
p99, plan-call latency p50 / p99, the server's CPU seconds (user + system, from /proc) and
peak resident memory (VmHWM), and the server's own counters (``/tamp/server/stats``).
Wall-clock figures come from a shared machine: read them as indicative.

``--out FILE`` writes the JSON (``benchmarks/results/serve.json`` is the committed run).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tamp.scenarios import path as packaged  # noqa: E402

CLIENTS = 8
RATE_HZ = 50.0


def proc_stats(pid: int) -> tuple[float, int]:
    """CPU seconds (user + system) and peak resident KiB of a process, from /proc."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    tick = os.sysconf("SC_CLK_TCK")
    cpu = (int(fields[11]) + int(fields[12])) / tick
    hwm = re.search(r"VmHWM:\s+(\d+)", Path(f"/proc/{pid}/status").read_text())
    return cpu, int(hwm.group(1)) if hwm else 0


def pct(values: list[float], q: float) -> float | None:
    if not values:
        return None
    values = sorted(values)
    return values[min(len(values) - 1, int(q * len(values)))]


def mr(p):
    x, y, z = p
    return {"x": z, "y": -x, "z": y}


async def stream_client(url: str, i: int, stop: float, stats: dict) -> None:
    from websockets.asyncio.client import connect

    async with connect(url, max_size=1 << 20) as ws:
        await ws.send(
            json.dumps(
                {"op": "advertise", "topic": f"/mr/hand{i}", "type": "geometry_msgs/PoseStamped"}
            )
        )
        for j in range(CLIENTS):
            if j != i:
                await ws.send(
                    json.dumps(
                        {
                            "op": "subscribe",
                            "id": f"s{j}",
                            "topic": f"/mr/hand{j}",
                            "type": "geometry_msgs/PoseStamped",
                            "queue_length": 1,
                        }
                    )
                )

        async def reader():
            async for text in ws:
                m = json.loads(text)
                if m.get("op") == "publish":
                    stats["received"] += 1
                    st = m["msg"]["header"]["stamp"]
                    stats["latency"].append(time.time() - (st["sec"] + st["nanosec"] * 1e-9))

        task = asyncio.create_task(reader())
        await stats["ready"].wait()
        period = 1.0 / RATE_HZ
        k = 0
        t0 = time.monotonic()
        while time.monotonic() < stop:
            now = time.time()
            sec = int(now)
            msg = {
                "header": {
                    "frame_id": "mr",
                    "stamp": {"sec": sec, "nanosec": int((now - sec) * 1e9)},
                },
                "pose": {
                    "position": {"x": 0.01 * k, "y": float(i), "z": 1.0},
                    "orientation": {"x": 0, "y": 0, "z": 0, "w": 1},
                },
            }
            await ws.send(json.dumps({"op": "publish", "topic": f"/mr/hand{i}", "msg": msg}))
            stats["published"] += 1
            k += 1
            await asyncio.sleep(max(0.0, t0 + k * period - time.monotonic()))
        await asyncio.sleep(0.5)  # let the last deliveries arrive
        task.cancel()


async def planner_client(url: str, stop: float, stats: dict) -> None:
    from websockets.asyncio.client import connect

    data = yaml.safe_load(packaged("case2.yaml").read_text())

    def pose(p):
        return {"position": mr(p), "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}}

    begin = {
        "header": {"frame_id": "mr"},
        "robot": pose(data["frame"]["robot_position"]),
        "area_radius": data["area_radius"],
        "start": data["robot"]["start"],
        "objects": [{"id": o["id"], "pose": pose(o["position"])} for o in data["objects"]],
    }
    async with connect(url, max_size=1 << 22) as ws:
        pending: dict[str, asyncio.Future] = {}
        phases: asyncio.Queue = asyncio.Queue()

        async def reader():
            async for text in ws:
                m = json.loads(text)
                if m.get("op") == "service_response":
                    pending.pop(m["id"]).set_result(m)
                elif m.get("topic") == "/tamp/state":
                    await phases.put(json.loads(m["msg"]["data"])["phase"])

        task = asyncio.create_task(reader())
        n = 0

        async def call(service, args=None):
            nonlocal n
            n += 1
            mid = f"c{n}"
            fut = asyncio.get_running_loop().create_future()
            pending[mid] = fut
            await ws.send(
                json.dumps(
                    {"op": "call_service", "id": mid, "service": service, "args": args or {}}
                )
            )
            reply = await asyncio.wait_for(fut, 60)
            assert reply["result"], reply
            return reply["values"]

        await ws.send(json.dumps({"op": "subscribe", "topic": "/tamp/state", "id": "st"}))
        await ws.send(
            json.dumps(
                {"op": "advertise", "topic": "/tamp/demo/step", "type": "tamp_msgs/DemoStep"}
            )
        )
        stats["ready"].set()
        while time.monotonic() < stop:
            assert (await call("/tamp/demo/begin", begin))["success"]
            for s in data["steps"]:
                await ws.send(
                    json.dumps(
                        {
                            "op": "publish",
                            "topic": "/tamp/demo/step",
                            "msg": {
                                "header": {"frame_id": "mr"},
                                "object_id": s["object"],
                                "pose": pose(s["to"]),
                            },
                        }
                    )
                )
            while (await phases.get()) != "demonstrating":
                pass
            for _ in range(len(data["steps"])):  # one state message per accepted step
                await phases.get()
            t0 = time.perf_counter()
            values = await call("/tamp/plan", {"cost_model": "distance", "constraints": []})
            stats["plan_ms"].append((time.perf_counter() - t0) * 1000)
            assert values["success"], values
            await call("/tamp/execute")
            while (phase := await phases.get()) not in ("done", "failed"):
                pass
            stats["runs"][phase] += 1
        stats["server"] = json.loads((await call("/tamp/server/stats"))["message"])
        task.cancel()


async def run_load(url: str, seconds: float) -> dict:
    stats = {
        "published": 0,
        "received": 0,
        "latency": [],
        "plan_ms": [],
        "runs": {"done": 0, "failed": 0},
        "ready": asyncio.Event(),
    }
    stop = time.monotonic() + seconds + 1.0
    planner = asyncio.create_task(planner_client(url, stop, stats))
    streams = [asyncio.create_task(stream_client(url, i, stop, stats)) for i in range(CLIENTS)]
    await asyncio.gather(planner, *streams)
    return stats


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=20.0, help="streaming time (default 20)")
    ap.add_argument("--out", help="write the JSON here")
    args = ap.parse_args()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "tamp.commands.main",
            "serve",
            "--port",
            "0",
            "--demo",
            "case2.yaml",
            "--max-clients",
            "16",
        ],
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        env={**os.environ, "TAMP_LOG": "INFO"},
    )
    try:
        line = proc.stderr.readline()
        port = int(re.search(r"ws://127\.0\.0\.1:(\d+)/", line).group(1))
        cpu0, _ = proc_stats(proc.pid)
        t0 = time.perf_counter()
        stats = asyncio.run(run_load(f"ws://127.0.0.1:{port}/", args.seconds))
        wall = time.perf_counter() - t0
        cpu1, hwm = proc_stats(proc.pid)
    finally:
        proc.terminate()
        proc.wait(timeout=10)
    expected = stats["published"] * (CLIENTS - 1)
    lat = [v * 1000 for v in stats["latency"]]
    doc = {
        "benchmark": "serve",
        "command": f"python benchmarks/serve.py --seconds {args.seconds:g}",
        "machine": {"cpus": os.cpu_count(), "load_1min": os.getloadavg()[0]},
        "clients": {"stream": CLIENTS, "rate_hz": RATE_HZ, "planner": 1},
        "wall_s": round(wall, 2),
        "published": stats["published"],
        "published_per_s": round(stats["published"] / wall, 1),
        "delivered": stats["received"],
        "delivered_per_s": round(stats["received"] / wall, 1),
        "expected_deliveries": expected,
        "not_delivered": max(0, expected - stats["received"]),
        "coalesced_latest_wins": stats.get("server", {}).get("coalesced", 0),
        "dropped_queue_full": stats.get("server", {}).get("dropped", 0),
        "client_process_cpu_s": round(time.process_time(), 2),
        "pose_latency_ms": {"p50": pct(lat, 0.5), "p99": pct(lat, 0.99), "n": len(lat)},
        "plan_call_ms": {
            "p50": pct(stats["plan_ms"], 0.5),
            "p99": pct(stats["plan_ms"], 0.99),
            "n": len(stats["plan_ms"]),
            "mean": statistics.fmean(stats["plan_ms"]) if stats["plan_ms"] else None,
        },
        "runs": stats["runs"],
        "server_cpu_s": round(cpu1 - cpu0, 2),
        "server_cpu_share_of_one_core": round((cpu1 - cpu0) / wall, 3),
        "server_peak_rss_mib": round(hwm / 1024, 1),
        "server_counters": stats.get("server", {}),
    }
    for k in ("pose_latency_ms", "plan_call_ms"):
        doc[k] = {kk: (round(v, 2) if isinstance(v, float) else v) for kk, v in doc[k].items()}
    text = json.dumps(doc, indent=1)
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
