"""The wheel works on its own: built, installed into a fresh environment, run from elsewhere.

`pip wheel .` of a copy of the project; a new virtual environment whose own site-packages
holds only the installed wheel and, through a ``.pth`` file, sees the packages of the
environment running the tests (Drake, torch: nothing is downloaded, and ``.pth`` files of
that environment, such as an editable install of tamp, are not processed). Then ``tamp
simulate`` and ``tamp grasp predict`` run from an empty temporary directory with
``PYTHONPATH`` cleared, so neither the source tree nor the working directory can help.
"""

from __future__ import annotations

import json
import os
import shutil
import site
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parent.parent
SOURCES = ("pyproject.toml", "README.md", "LICENSE", "tamp")


def _run(cmd: list[str], cwd: Path, env: dict[str, str], timeout: float = 300):
    proc = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, f"{cmd}: exit {proc.returncode}\n{proc.stdout}\n{proc.stderr}"
    return proc


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> tuple[Path, dict[str, str], Path]:
    """(the new environment's bin folder, its environment variables, the wheel)."""
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"  # a copy: building writes build/ and *.egg-info beside the sources
    src.mkdir()
    for name in SOURCES:
        path = ROOT / name
        if path.is_dir():
            shutil.copytree(path, src / name, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy2(path, src / name)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["DRAKE_ALLOW_NETWORK"] = "meshcat"
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "--no-input"]
    _run([*pip, "wheel", ".", "--no-deps", "--no-build-isolation", "-q", "-w", str(tmp)], src, env)
    (wheel,) = tmp.glob("tamp_hrc-*.whl")

    venv = tmp / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", str(venv)], tmp, env)
    python = venv / "bin" / "python"
    purelib = _run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], tmp, env
    ).stdout.strip()
    ours = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    ours.update(site.getsitepackages())
    (Path(purelib) / "project_env.pth").write_text("\n".join(sorted(ours)) + "\n")
    _run([*pip, "--python", str(python), "install", "--no-deps", "-q", str(wheel)], tmp, env)
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    return venv / "bin", env, wheel


def test_wheel_holds_the_models_and_the_license(installed):
    _, _, wheel = installed
    names = set(zipfile.ZipFile(wheel).namelist())
    for name in ("youbot", "bottle", "obstacle", "floor", "area_marker"):
        assert f"tamp/models/sdf/{name}.sdf" in names
    assert {"tamp/models/package.xml", "tamp/models/weights/hrgnet_synth_rgbd.pt"} <= names
    # the three grasp networks of `tamp simulate lots --grasp`; the weights stay small
    weights = [f"tamp/models/weights/{n}_synth_rgbd.pt" for n in ("grconvnet", "ggcnn")]
    assert set(weights) <= names
    sizes = [
        i.compress_size for i in zipfile.ZipFile(wheel).infolist() if i.filename.endswith(".pt")
    ]
    assert sum(sizes) < 8_000_000, sizes
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names)
    sources = {p.relative_to(ROOT).as_posix() for p in (ROOT / "tamp").rglob("*.py")}
    assert sources <= names, sorted(sources - names)[:5]
    metadata = next(n for n in names if n.endswith(".dist-info/METADATA"))
    text = zipfile.ZipFile(wheel).read(metadata).decode()
    assert "License-Expression: BSD-3-Clause" in text
    assert "Requires-Dist: drake<2,>=1.40" in text  # a range: a user's own Drake is kept


def test_imports_come_from_the_wheel(installed, tmp_path):
    bin_dir, env, _ = installed
    code = "import tamp, tamp.models; print(tamp.__file__); print(tamp.models.__file__)"
    out = _run([str(bin_dir / "python"), "-c", code], tmp_path, env).stdout.split()
    venv = bin_dir.parent.resolve()
    for path in out:
        assert Path(path).resolve().is_relative_to(venv), out


def test_simulate_runs_from_any_directory(installed, tmp_path):
    bin_dir, env, _ = installed
    proc = _run(
        [str(bin_dir / "tamp"), "simulate", "smp-mro", "--case", "1", "--json"], tmp_path, env
    )
    data = json.loads(proc.stdout)
    assert data["ok"] and data["status"] == "SUCCESS"
    assert data["verified"] == {"order": True, "tree": True}
    assert all(data["goals"].values()) and len(data["goals"]) == 3
    assert list(tmp_path.iterdir()) == []  # nothing written to the working directory


def test_grasp_predict_with_the_shipped_weights(installed, tmp_path):
    """A red bar 5 cm above a table, seen from 0.6 m: the grasp closes across the bar."""
    import tifffile
    from PIL import Image

    bin_dir, env, _ = installed
    n = 96
    depth = np.full((n, n), 0.60, np.float32)
    rgb = np.full((n, n, 3), 150, np.uint8)
    depth[40:56, 30:66] = 0.55  # 36 x 16 px, long along u
    rgb[40:56, 30:66] = (200, 40, 40)
    Image.fromarray(rgb).save(tmp_path / "rgb.png")
    tifffile.imwrite(tmp_path / "depth.tiff", depth)
    down = "1 0 0 0  0 -1 0 0  0 0 -1 0.6  0 0 0 1".split()  # camera 0.6 m up, looking down
    cmd = [str(bin_dir / "tamp"), "grasp", "predict", "rgb.png", "--depth", "depth.tiff"]
    cmd += ["--intrinsics", "100", "100", "47.5", "47.5", "--pose", *down, "--top", "2", "--json"]
    grasps = json.loads(_run(cmd, tmp_path, env).stdout)
    assert len(grasps) == 2
    for g in grasps:
        assert 30 <= g["u"] <= 66 and 40 <= g["v"] <= 56, g  # on the bar
        assert abs(abs(g["angle"]) - np.pi / 2) < 0.4, g  # fingers close across its width
        assert g["position"][2] == pytest.approx(0.05, abs=0.01)  # the bar's top
        # the quality map is a regression trained towards 1 at grasp centres (MSE), not a
        # probability: a confident peak may read a little above 1 (the mats weights: 1.02)
        assert 0.0 < g["quality"] < 2.0
    assert grasps[0]["quality"] >= grasps[1]["quality"]
