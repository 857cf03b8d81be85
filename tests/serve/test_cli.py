"""`tamp serve` as a newcomer runs it: bad options are one line (exit 2), and the server
started from the command line answers a rosbridge call and serves the page."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import urllib.request

import pytest
from websockets.sync.client import connect

from tamp.commands.main import main


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (["--port", "70000"], "--port"),
        (["--max-clients", "0"], "--max-clients"),
        (["--max-message", "10"], "--max-message"),
        (["--plan-timeout", "nan"], "--plan-timeout"),
        (["--token", "short"], "--token"),
        (["--origin", "evil.example"], "--origin"),
        (["--demo", "no_such_demo.yaml"], "no_such_demo.yaml"),
    ],
)
def test_bad_options_are_one_line_exit_2(capsys, argv, field):
    assert main(["serve", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("tamp: error:") and field in err[0]
    assert "Traceback" not in err[0]


def test_tamp_serve_from_the_command_line():
    env = {**os.environ, "TAMP_LOG": "INFO"}
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
        ],
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        line = proc.stderr.readline()
        m = re.search(r"ws://127\.0\.0\.1:(\d+)/", line)
        assert m, line
        port = int(m.group(1))
        with connect(f"ws://127.0.0.1:{port}/") as ws:
            ws.send(json.dumps({"op": "subscribe", "id": 1, "topic": "/tamp/scene"}))
            scene = json.loads(json.loads(ws.recv(timeout=10))["msg"]["data"])
            assert [o["id"] for o in scene["objects"]] == ["O0", "O1"]
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/") as r:
            assert b"tamp live demonstration" in r.read()
    finally:
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=10) == 0
