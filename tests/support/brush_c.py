"""The firmware's C painter (device/cmod/texelbrush/brush_core.c) compiled
for this machine with gcc and called through ctypes: the same integers as
texel.gen.brush's Python loops, checked on the host in seconds (the firmware
build runs it on the emulated Pico: tests/firmware)."""
from __future__ import annotations

import ctypes
import hashlib
import shutil
import subprocess
import tempfile
from array import array
from pathlib import Path

from texel.gen import brush as B
from texel.gen.plan_int_tables import table
from texel.gen.rng import Rng

from . import mpy

SRC = mpy.ROOT / "device" / "cmod" / "texelbrush" / "brush_core.c"
_LIB = None


def available() -> bool:
    return shutil.which("gcc") is not None


def lib() -> ctypes.CDLL:
    global _LIB
    if _LIB is None:
        digest = hashlib.sha256(SRC.read_bytes()).hexdigest()[:16]
        out = Path(tempfile.gettempdir()) / ("texelpad-brush-core-%s.so" % digest)
        if not out.exists():
            tmp = out.with_suffix(".so.tmp")
            subprocess.run(["gcc", "-O2", "-std=c99", "-Wall", "-Wextra", "-Werror", "-shared",
                            "-fPIC", "-o", str(tmp), str(SRC)], check=True)
            tmp.replace(out)
        _LIB = ctypes.CDLL(str(out))
    return _LIB


class Tables(ctypes.Structure):
    _fields_ = [(n, ctypes.c_void_p) for n in ("exp_tab", "log2t", "phase", "tw", "hann", "pos")]


def _ptr(a: array) -> int:
    return a.buffer_info()[0]


def paint(brush: dict, seed: int, n: int, chunk_bits: int = 9) -> list[int]:
    """texel.gen.brush.paint(brush, seed, n) by the C loop, into chunks of
    2^chunk_bits values as a board's upload Chunks."""
    _, ptab, tw, hann, log2t, pos = B._tables()
    tab = array("i", table())
    keep = (ptab, tw, hann, log2t, pos, tab)
    t = Tables(*(_ptr(a) for a in (tab, log2t, ptab, tw, hann, pos)))
    rng = Rng(seed)
    invk, ll, sign, off = B.compensated(brush)
    st = B.state(rng)
    size = 1 << chunk_bits
    chunks = [array("H", bytes(2 * min(size, n - o))) for o in range(0, n, size)]
    ptrs = (ctypes.c_void_p * len(chunks))(*(_ptr(c) for c in chunks))
    work = array("i", bytes(4 * (4 * B.K + 3 * B.WINDOW)))
    lib().tb_paint(ctypes.c_void_p(_ptr(st)), ctypes.c_void_p(_ptr(invk)),
                   ctypes.c_void_p(_ptr(ll)), ctypes.c_int32(sign), ctypes.c_int32(off),
                   ctypes.byref(t), ctypes.c_int32(n), ptrs, ctypes.c_int32(chunk_bits),
                   ctypes.c_void_p(_ptr(work)))
    del keep
    return [v for c in chunks for v in c]


def leak(q: array, a: array, n: int, sweeps: int, c: array) -> None:
    lib().tb_leak(ctypes.c_void_p(_ptr(q)), ctypes.c_void_p(_ptr(a)), ctypes.c_int32(n),
                  ctypes.c_int32(sweeps), ctypes.c_void_p(_ptr(c)))
