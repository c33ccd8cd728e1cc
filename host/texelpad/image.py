"""The device image: which files `texelpad deploy` puts on a board, built offline.

Layout on the board's filesystem (root "/"), the same for `texelpad deploy`,
`mpremote mip install` (which installs under the first ``.../lib`` on
``sys.path``) and the unix-port virtual board (its "flash" directory as the
working directory, ``MICROPYPATH=<flash>:<flash>/lib:.frozen``)::

    /lib/texel/<module>.mpy              (.py for source images and mip)
    /lib/texel/{gen,runtime,hw}/<module>.mpy
    /lib/texel/gen/reference_noise.bin   package data (pyproject's package-data)
    /lib/texel/boards.d/<name>.json      the shipped boards
    /main.py                             power-up (texel/main.py; deploy decides)

The layout under /lib/texel is the texel package's own (device/texel in the
repository, site-packages/texel in a wheel): the image is read from the
installed package, so a pip-installed texelpad deploys as a checkout does.
A board's image carries only its own hardware backend (texel/hw/<port>.py)
and the shipped boards of its port; the mip package and --source images for
an unknown platform carry them all. ``texel.runtime.boards.load`` looks in
``<texel package>/boards.d`` last, so a user's ``/boards/<name>.json`` still
overrides a shipped board. No image - deploy's, mip's, the firmware's -
carries the host-only modules (HOST_ONLY: CPython's numpy plan), which stay in
the CPython package (a wheel, an editable install).

API:
    target_for(impl_name, mpy, version, platform=None, source=False) -> Target
    TARGETS                     named targets (rp2, pyboard, unix, circuitpython, source)
    build_image(target, include_main=True) -> list[ImageFile]
    image_bytes(files) -> int
    plan_upload(files, remote_hashes) -> files to (re)write
    plan_remove(files, remote_paths) -> stale package files to delete
    write_tree(files, root)     the image into a local directory (a virtual board's flash)
    package_json(base) / write_package_json(path)   mip's package.json (source .py files)
Errors are ImageError, one message saying what is wrong and what to do.
"""
from __future__ import annotations

import ast
import functools
import hashlib
import json
import os
import re
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Mapping, Sequence

from . import __version__
from .toolchain import mpy_cross_cmd

import texel
from texel.compat import PORT_TABLE, PORTS, UNIX_PLATFORMS, port_of

# The device package as installed beside this host package: device/texel in a
# checkout (editable install), site-packages/texel from a wheel.
PACKAGE_DIR = Path(texel.__file__).resolve().parent
BOARDS_DIR = PACKAGE_DIR / "boards.d"
MAIN_PY = PACKAGE_DIR / "main.py"            # the board's /main.py, not a module
HW_DIR = "hw"                                # texel/hw/<backend>.py
# The hardware backend module each board port runs (texel.compat.PORT_TABLE: texel.app's too).
PORT_BACKEND = {p: PORT_TABLE[p]["backend"][0] for p in PORTS}
# Hardware modules several ports share (texel/hw/<name>.py -> the ports that get
# it): the classroom kit's button and LED on machine.Pin (texel/kit.py)
HW_SHARED = {"pins": ("rp2", "stm32")}
# Host-only modules of the texel package (paths under it), the ONE list: every
# board image leaves them out - deploy's (.mpy and --source), mip's
# package.json, the firmware's frozen code and ROMFS (texelpad.firmware builds
# from package_modules/build_image) - while the CPython package (a wheel, an
# editable install) keeps them, since the host imports them. gen/plan_numpy.py
# is the plan on numpy arrays, which texel.make_plan runs only on CPython with
# numpy (docs/generator.md, "On CPython: the numpy engine and the plan on
# whole arrays"); no board has numpy (ulab boards have ulab.numpy and
# gen/engine_ulab.py). gen/engine_numpy.py, the numpy engine, likewise:
# texel._engine_module imports it only where numpy is.
HOST_ONLY = ("gen/plan_numpy.py", "gen/engine_numpy.py")

# Where things go on the board.
LIB = "/lib"
REMOTE_PACKAGE = LIB + "/texel"
BOARDS_SUBDIR = "boards.d"          # = texel.runtime.boards.PACKAGE_BOARDS_DIR
REMOTE_MAIN = "/main.py"
# Package data shipped beside the modules: mirrors pyproject's
# [tool.setuptools.package-data] texel = [...] (a test keeps them equal).
DATA_PATTERNS = ("*.bin",)

# Ports whose deploy also writes reference maps (lib/texel/gen/ref/<name>.u16,
# 38,400 bytes each: texelpad.deploy.install with_reference_maps; the firmware's
# ROMFS holds the same files), read into a region's RAM instead of rendered
# (texel/gen/reference.py file_u16). A pyboard's /flash has 112 KB, too little
# beside the image, and CircuitPython's reading of them is not measured: they render.
MAP_PORTS = ("rp2",)
# Which: the study references whose full-screen render on a stock Pico takes a
# second or more (the emulated Pico's clock: square 0.96 s, sawtooth 1.18,
# triangle 1.59; reading a file ~12 ms). The sums of sines (C core: 57-81 ms) and
# the noise rows (25 ms) render: all nine files (94 of the filesystem's 352 4-KB
# blocks) left `mpremote mip install ./package.json` (179 blocks) no room beside
# the deployed image (docs/host.md's example; 242 blocks free without maps).
# The pyboard's firmware carries the same three in its ROMFS partition
# (firmware/build_stm32.py: 115 KB of its 256; the nine would not fit), where
# they play in place: 266-290 ms renders into 38.4 KB of its ~100 KB heap before.
MAP_NAMES = ("square", "triangle", "sawtooth")

# The rp2 backend runs the refresh as a hard machine.Timer IRQ, which rp2
# MicroPython supports from 1.26; older rp2 firmware is refused up front
# rather than failing at app.start().
MIN_MICROPYTHON_RP2 = (1, 26)

# sys.implementation._mpy >> 10 indexes this (MicroPython py/persistentcode.h
# MP_NATIVE_ARCH_*; the same order as mpy-cross -march and the table in
# docs/reference/mpyfiles.rst). None: the port has no native emitter.
ARCHS = (None, "x86", "x64", "armv6", "armv6m", "armv7m", "armv7em", "armv7emsp",
         "armv7emdp", "xtensa", "xtensawin", "rv32imc", "rv64imc")

# Decorators that make a function native code: such a module needs -march
# (and cannot be compiled for a port without a native emitter).
NATIVE_DECORATORS = frozenset({"viper", "native", "asm_thumb", "asm_xtensa", "asm_rv32"})

# Bump when the way a cached .mpy is made changes (flags, source naming):
# part of every cache key.
_RECIPE = "texelpad-mpy-1"


class ImageError(Exception):
    """The image cannot be made for this device: one line saying what to do."""


@dataclass(frozen=True)
class Target:
    """What a device loads. form "mpy": compiled with our mpy-cross, native
    (viper) modules with -march=arch (arch None: no native emitter, those
    modules are left out; the runtime has a pure-Python fallback); form
    "source": the .py files as they are (the device compiles them). port:
    the board port whose backend and boards the image carries (None: all)."""
    name: str
    form: str                        # "mpy" | "source"
    arch: str | None = None
    port: str | None = None

    @property
    def suffix(self) -> str:
        return ".mpy" if self.form == "mpy" else ".py"


TARGETS: dict[str, Target] = {
    # archs: the port table's (texel.compat.PORT_TABLE)
    "rp2": Target("rp2", "mpy", PORT_TABLE["rp2"]["arch"], "rp2"),              # RP2040, Cortex-M0+
    "pyboard": Target("pyboard", "mpy", PORT_TABLE["stm32"]["arch"], "stm32"),  # STM32F405, M4F
    "unix": Target("unix", "mpy", PORT_TABLE["virtual"]["arch"], "virtual"),    # the virtual board
    # CircuitPython's .mpy format is its own: it gets the sources
    "circuitpython": Target("circuitpython", "source", None, "circuitpython"),
    "source": Target("source", "source"),                        # deploy --source
}


@dataclass(frozen=True)
class ImageFile:
    remote: str                      # absolute path on the board, "/lib/texel/app.mpy"
    data: bytes
    sha256: str                      # hex of data (what the board's hashlib reports)
    source: Path                     # the checkout file it was made from

    @property
    def size(self) -> int:
        return len(self.data)


# --- mpy-cross -------------------------------------------------------------------

@dataclass(frozen=True)
class MpyCross:
    cmd: tuple[str, ...]
    banner: str                      # `mpy-cross --version`, part of every cache key
    release: str                     # "1.28.0"
    mpy: tuple[int, int]             # (.mpy version, sub-version) it writes: (6, 3)

    @property
    def mpy_text(self) -> str:
        return "v%d.%d" % self.mpy




@functools.lru_cache(maxsize=None)
def _mpy_cross_for(cmd: tuple[str, ...]) -> MpyCross:
    try:
        p = subprocess.run(list(cmd) + ["--version"], capture_output=True, text=True, timeout=30)
    except OSError as e:
        raise ImageError("mpy-cross not found (%s): reinstall texelpad (it pins mpy-cross), or "
                         "deploy --source" % e) from None
    banner = (p.stdout + p.stderr).strip()
    # "MicroPython v1.28.0 on 2026-08-11; mpy-cross emitting mpy v6.3"
    m = re.search(r"MicroPython v(\d+\.\d+(?:\.\d+)?)\S*.*mpy v(\d+)\.(\d+)", banner)
    if p.returncode != 0 or not m:
        raise ImageError("mpy-cross (%s) did not report its version: %r" % (" ".join(cmd), banner))
    return MpyCross(tuple(cmd), banner, m.group(1), (int(m.group(2)), int(m.group(3))))


def mpy_cross() -> MpyCross:
    """The mpy-cross deploy compiles with, and the .mpy format it writes."""
    return _mpy_cross_for(tuple(mpy_cross_cmd()))


# --- which device is it ---------------------------------------------------------------

def _version3(version: Sequence) -> tuple[int, ...]:
    """(1, 26, 0, '') / (1, 26, 0) / [1, 26] -> the leading ints."""
    out = []
    for v in version:
        if not isinstance(v, int):
            break
        out.append(v)
    return tuple(out)


def _vtext(version: Sequence) -> str:
    return ".".join(str(v) for v in _version3(version)) or repr(version)


def decode_mpy(mpy: int) -> tuple[int, int, str | None]:
    """sys.implementation._mpy -> (.mpy version, sub-version, native arch).
    MicroPython packs it as version | sub_version << 8 | arch << 10 (the .mpy
    header's bytes 1 and 2)."""
    index = mpy >> 10
    if index >= len(ARCHS):
        raise ImageError("sys.implementation._mpy = %#x names native architecture #%d, unknown "
                         "to texelpad; deploy --source" % (mpy, index))
    return mpy & 0xFF, (mpy >> 8) & 3, ARCHS[index]


def _platform_port(platform: str | None) -> str | None:
    """sys.platform -> the board port whose backend the image carries (the
    port table's; the unix port's platforms the virtual board's; unknown
    platforms None: every backend)."""
    if not platform:
        return None
    if platform in UNIX_PLATFORMS:
        return "virtual"
    return port_of("micropython", platform)


def target_for(impl_name: str, mpy: int | None, version: Sequence,
               platform: str | None = None, source: bool = False) -> Target:
    """The Target for a device, from its sys.implementation.name, ._mpy (None
    when the firmware has no such attribute) and .version, and optionally
    sys.platform. source=True (deploy --source) skips the .mpy format check
    but still refuses firmware too old to run the display.

    Without a platform the rp2 minimum is applied to armv6m devices (the only
    armv6m board texelpad supports is the RP2040)."""
    if impl_name == "circuitpython":
        return TARGETS["circuitpython"]
    if impl_name != "micropython":
        raise ImageError("the device runs %r, not MicroPython or CircuitPython: nothing to deploy"
                         % (impl_name,))
    fmt = decode_mpy(mpy) if mpy is not None else None
    arch = fmt[2] if fmt else None
    if _platform_port(platform) == "rp2" or (platform is None and arch == "armv6m"):
        if _version3(version)[:2] < MIN_MICROPYTHON_RP2:
            raise ImageError(
                "MicroPython %s on rp2 is too old: texelpad needs %s or later (the refresh is a "
                "hard machine.Timer IRQ); update the firmware (https://micropython.org/download/)"
                % (_vtext(version), ".".join(map(str, MIN_MICROPYTHON_RP2))))
    if source:
        return Target("source", "source", None, _platform_port(platform))
    mc = mpy_cross()
    if fmt is None:
        raise ImageError(
            "MicroPython %s does not report its .mpy format (no sys.implementation._mpy): update "
            "the firmware to MicroPython %s, or deploy --source" % (_vtext(version), mc.release))
    if (fmt[0], fmt[1]) != mc.mpy:
        # Bytecode needs the same version; native (viper) code also the same
        # sub-version (docs/reference/mpyfiles.rst). The image holds viper
        # modules, so both must match.
        raise ImageError(
            "this firmware (MicroPython %s) loads .mpy v%d.%d, but the pinned mpy-cross %s writes "
            "%s: update the firmware to MicroPython %s, or deploy --source (plain .py files, "
            "compiled by the board)" % (_vtext(version), fmt[0], fmt[1], mc.release, mc.mpy_text,
                                         mc.release))
    port = _platform_port(platform)
    for t in TARGETS.values():
        if t.form == "mpy" and t.arch == arch and (platform is None or t.port == port):
            return t
    return Target(arch or "bytecode", "mpy", arch, port)


# --- the files -------------------------------------------------------------------------

def _is_native_decorator(node: ast.expr) -> bool:
    if isinstance(node, ast.Call):
        node = node.func
    if isinstance(node, ast.Attribute):
        return (node.attr in NATIVE_DECORATORS and isinstance(node.value, ast.Name)
                and node.value.id == "micropython")
    return isinstance(node, ast.Name) and node.id in NATIVE_DECORATORS


def holds_native_code(path: Path) -> bool:
    """A function in the file is decorated @micropython.viper/native/asm_*
    (found with ast: mentions in comments and strings do not count)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    return any(_is_native_decorator(d)
               for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
               for d in n.decorator_list)


def _wanted_module(p: Path, port: str | None) -> bool:
    """Every module but main.py (the board's /main.py), the host-only ones
    (HOST_ONLY) and, for a port, the other ports' backends."""
    rel = p.relative_to(PACKAGE_DIR)
    if rel == Path("main.py") or rel.as_posix() in HOST_ONLY:
        return False
    if port is not None and rel.parts[0] == HW_DIR and rel.name != "__init__.py":
        # the port's backend, its own helpers (hw/stm32_irq.py goes with hw/stm32.py)
        # and what it shares (HW_SHARED)
        return (rel.stem == PORT_BACKEND[port] or rel.stem.startswith(PORT_BACKEND[port] + "_")
                or port in HW_SHARED.get(rel.stem, ()))
    return True


def package_modules(port: str | None = None) -> list[Path]:
    """The texel package's modules a board gets (subpackages included, not
    main.py nor HOST_ONLY), sorted; with a port only that port's hardware
    backend."""
    mods = sorted(p for p in PACKAGE_DIR.rglob("*.py")
                  if "__pycache__" not in p.parts and _wanted_module(p, port))
    if not mods:
        raise ImageError("no device package at %s: reinstall texelpad" % PACKAGE_DIR)
    return mods


def package_data() -> list[Path]:
    """The package's data files (DATA_PATTERNS, in any subpackage), sorted."""
    return sorted({p for pat in DATA_PATTERNS for p in PACKAGE_DIR.rglob(pat) if p.is_file()})


def board_files(port: str | None = None) -> list[Path]:
    """The shipped boards (texel/boards.d); with a port only its boards."""
    files = sorted(BOARDS_DIR.glob("*.json"))
    if port is None:
        return files
    return [p for p in files if json.loads(p.read_text(encoding="utf-8")).get("port") == port]


def _lib_layout(port: str | None = None) -> list[tuple[str, Path]]:
    """(path under /lib, package file) of the package for a board port
    (None: all of it, as mip installs it)."""
    return [("texel/" + p.relative_to(PACKAGE_DIR).as_posix(), p)
            for p in package_modules(port) + package_data() + board_files(port)]


def cache_root() -> Path:
    """$TEXELPAD_CACHE, else $XDG_CACHE_HOME/texelpad, else ~/.cache/texelpad."""
    if os.environ.get("TEXELPAD_CACHE"):
        return Path(os.environ["TEXELPAD_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "texelpad"


def _compile(mc: MpyCross, src: Path, name: str, march: str | None, cache: Path) -> bytes:
    """src compiled to .mpy, from the cache when the same source, name, flags
    and mpy-cross made it before. name ("texel/app.py") is embedded as the
    source name: tracebacks read well and the bytes do not depend on where the
    checkout is."""
    text = src.read_bytes()
    key = hashlib.sha256(b"\0".join([_RECIPE.encode(), mc.banner.encode(),
                                     (march or "").encode(), name.encode(), text])).hexdigest()
    path = cache / key[:2] / (key + ".mpy")
    try:
        data = path.read_bytes()
        if data[:1] == b"M":
            return data
    except OSError:
        pass
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".mpy", dir=path.parent)
    os.close(fd)
    try:
        args = list(mc.cmd) + (["-march=" + march] if march else []) + ["-s", name, "-o", tmp, str(src)]
        p = subprocess.run(args, capture_output=True, text=True, timeout=120)
        if p.returncode != 0:
            # its traceback: 'File "texel/x.py", line 3' then 'SyntaxError: ...'
            lines = [ln.strip() for ln in (p.stderr + p.stdout).splitlines()
                     if ln.strip() and not ln.startswith("Traceback")]
            raise ImageError("mpy-cross%s failed on %s: %s" % (
                " -march=" + march if march else "",
                src.relative_to(PACKAGE_DIR.parent) if src.is_relative_to(PACKAGE_DIR.parent)
                else src,
                "; ".join(lines[-2:]) or "exit %d" % p.returncode))
        data = Path(tmp).read_bytes()
        os.replace(tmp, path)            # atomic: a concurrent build sees all or nothing
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return data


def _file(remote: str, data: bytes, source: Path) -> ImageFile:
    return ImageFile(remote, data, hashlib.sha256(data).hexdigest(), source)


def build_image(target: Target, include_main: bool = True,
                cache_dir: Path | None = None) -> list[ImageFile]:
    """Every file of the image for target, in upload order: the package
    (modules, data, boards), then /main.py last, so an interrupted upload
    never leaves a power-up script without the modules it imports.

    mpy targets: modules without native code are compiled without -march
    (plain bytecode, the same bytes for every architecture, so they are cached
    once); modules with viper code get -march=target.arch, or are left out
    when the port has no native emitter. Compiled files are cached under
    cache_dir (default cache_root()/mpy/<mpy-cross release>/<arch|bytecode>),
    keyed by content, so a rebuild runs no mpy-cross at all."""
    # (remote, source, name, compile?, march), in layout order
    plan: list[tuple[str, Path, str, bool, str | None]] = []
    for rel, src in _lib_layout(target.port):
        remote = LIB + "/" + rel
        if target.form != "mpy" or src.suffix != ".py":
            plan.append((remote, src, rel, False, None))
            continue
        try:
            native = holds_native_code(src)
        except SyntaxError:
            # not CPython syntax: give mpy-cross the -march, it compiles
            # either kind of module with it (or names the file and line)
            native = None
        if native and target.arch is None:
            continue                     # no native emitter: the pure fallback runs
        plan.append((remote[:-3] + ".mpy", src, rel, True,
                     target.arch if native is not False else None))
    datas: dict[int, bytes] = {}
    jobs = [i for i, e in enumerate(plan) if e[3]]
    if jobs:
        mc = mpy_cross()
        base = Path(cache_dir) if cache_dir is not None else cache_root() / "mpy"
        base = base / ("%s-%s" % (mc.release, mc.mpy_text))

        def one(i: int) -> bytes:
            _, src, name, _, march = plan[i]
            return _compile(mc, src, name, march, base / (march or "bytecode"))

        # one mpy-cross process per module: run them side by side
        with ThreadPoolExecutor(max_workers=min(8, os.cpu_count() or 1)) as ex:
            datas = dict(zip(jobs, ex.map(one, jobs)))
    files = [_file(remote, datas[i] if comp else src.read_bytes(), src)
             for i, (remote, src, _, comp, _) in enumerate(plan)]
    if include_main:
        files.append(_file(REMOTE_MAIN, MAIN_PY.read_bytes(), MAIN_PY))
    return files


def compile_module(src: Path, name: str, march: str | None = None,
                   cache_dir: Path | None = None) -> bytes:
    """One file compiled to .mpy by the pinned mpy-cross (cached as
    build_image's modules are): the firmware's ROMFS carries texel/main.py
    as a module this way (texelpad.firmware.romfs)."""
    mc = mpy_cross()
    base = Path(cache_dir) if cache_dir is not None else cache_root() / "mpy"
    base = base / ("%s-%s" % (mc.release, mc.mpy_text))
    return _compile(mc, src, name, march, base / (march or "bytecode"))


def image_bytes(files: Iterable[ImageFile]) -> int:
    """Total size of the files, bytes (what the board's filesystem must hold,
    before block rounding)."""
    return sum(f.size for f in files)


def plan_upload(files: Sequence[ImageFile],
                remote_hashes: Mapping[str, str | None]) -> list[ImageFile]:
    """The files to write: those whose sha256 on the board (remote_hashes:
    remote path -> hex digest, None or absent when the file is missing)
    differs. Keeps the image's order."""
    out = []
    for f in files:
        have = remote_hashes.get(f.remote)
        if not have or have.lower() != f.sha256:
            out.append(f)
    return out


def plan_remove(files: Sequence[ImageFile], remote_paths: Iterable[str]) -> list[str]:
    """Files on the board under /lib/texel that the image does not have, to
    delete: a leftover app.py (from mip or a --source deploy) would shadow
    the new app.mpy, since MicroPython imports .py before .mpy."""
    keep = {f.remote for f in files}
    prefix = REMOTE_PACKAGE + "/"
    return sorted(p for p in remote_paths if p.startswith(prefix) and p not in keep)


def write_tree(files: Iterable[ImageFile], root: Path | str) -> None:
    """Write the image under a local directory standing for the board's "/"
    (the virtual board's flash)."""
    root = Path(root)
    for f in files:
        dst = root / f.remote.lstrip("/")
        dst.parent.mkdir(parents=True, exist_ok=True)
        dst.write_bytes(f.data)


# --- mip ---------------------------------------------------------------------------------

def package_json(base: Path | str) -> dict:
    """mip's package.json for the device package as source .py files: every
    module a board gets (mip installs onto boards: no HOST_ONLY module), the
    package data and the shipped boards, targets relative to the
    device's lib directory, URLs relative to `base` (the directory the
    package.json lives in; mip resolves relative URLs against it, locally and
    on github:/gitlab:). main.py is not in it: mip installs under /lib only."""
    base = Path(base).resolve()
    urls = [[rel, Path(os.path.relpath(src, base)).as_posix()]
            for rel, src in _lib_layout()]
    return {"urls": urls, "deps": [], "version": __version__}


def package_json_text(base: Path | str) -> str:
    """package_json(base) as the committed file: one [target, url] pair a
    line, so a new device file is a one-line diff."""
    d = package_json(base)
    pairs = ",\n".join("    " + json.dumps(u) for u in d["urls"])
    return ('{\n  "urls": [\n%s\n  ],\n  "deps": %s,\n  "version": %s\n}\n'
            % (pairs, json.dumps(d["deps"]), json.dumps(d["version"])))


def write_package_json(path: Path | str) -> dict:
    """Write package.json at path (URLs relative to its directory); return it."""
    path = Path(path)
    text = package_json_text(path.parent)
    path.write_text(text, encoding="utf-8")
    return json.loads(text)
