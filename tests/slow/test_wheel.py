"""The quick start from a built wheel in a fresh venv, run outside the checkout:
what a user gets from `pip install texelpad`. The wheel must carry the device
package whole (subpackages, boards.d, main.py, the noise data) and the
device-side bench scripts, and nothing of the tests; deploy (inside the demo)
must read the image from the installed package, not from a checkout."""
from __future__ import annotations

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

pytestmark = [pytest.mark.slow, pytest.mark.vboard]

ROOT = Path(__file__).resolve().parents[2]


def _env() -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"
    return env


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    p = subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(out),
                        str(ROOT)], capture_output=True, text=True, timeout=600, env=_env())
    assert p.returncode == 0, p.stdout + p.stderr
    (whl,) = out.glob("texelpad-*.whl")
    return whl


def test_wheel_carries_the_device_package_and_no_tests(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    device = {p.relative_to(ROOT / "device").as_posix()
              for p in (ROOT / "device" / "texel").rglob("*")
              if p.is_file() and "__pycache__" not in p.parts}
    assert device <= names, sorted(device - names)          # every module, board, data file
    for must in ("texel/main.py", "texel/boards.d/pico.json", "texel/gen/reference_noise.bin",
                 "texel/hw/rp2.py", "texelpad/bench/device/mpbench.py",
                 "texelpad/bench/device/mp_refresh_bench.py", "texelpad/toolchain.py"):
        assert must in names, must
    assert not [n for n in names if n.startswith("tests/") or "ulab_standin" in n or "/fakes/" in n]


def test_quick_start_from_the_wheel_in_a_fresh_venv(wheel, tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=300)
    py = venv / "bin" / "python"
    p = subprocess.run([str(py), "-m", "pip", "install", "-q", str(wheel)], capture_output=True,
                       text=True, timeout=900, env=_env())
    assert p.returncode == 0, p.stdout + p.stderr
    run = tmp_path / "elsewhere"                 # not the checkout: nothing to find there
    run.mkdir()
    where = subprocess.run([str(py), "-c", "import texel, texelpad; print(texel.__file__); "
                            "print(texelpad.__file__)"], capture_output=True, text=True,
                           cwd=run, env=_env(), timeout=120)
    assert where.returncode == 0, where.stderr
    assert all(str(venv) in line for line in where.stdout.split()), where.stdout
    png = run / "texture.png"
    demo = subprocess.run([str(venv / "bin" / "texelpad"), "demo", "--out", str(png)],
                          capture_output=True, text=True, cwd=run, env=_env(), timeout=300)
    assert demo.returncode == 0, demo.stdout + demo.stderr
    assert "the board played exactly the map (0 of" in demo.stdout, demo.stdout
    assert "deploy: unix image" in demo.stderr       # the image came from the installed package
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the shipped example scenes are package data of the wheel
    scenes = subprocess.run([str(venv / "bin" / "texelpad"), "scenes"], capture_output=True,
                            text=True, cwd=run, env=_env(), timeout=60)
    assert scenes.returncode == 0 and "split-4sin" in scenes.stdout, scenes.stdout + scenes.stderr
