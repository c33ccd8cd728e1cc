"""The C core (device/cmod/texelcore: brush_core.c, texel_core.c), its
CPython build: compiled for this machine with gcc as one shared library and
called through ctypes - the same integers as texel.gen.brush's and
texel.gen.plan_int's / engine_int's Python loops, checked on the host in
seconds. Its other builds: the firmware's user C module (tests/firmware) and
the native .mpy (tests/gen/test_texel_core.py, on the unix port and the
emulated Pico)."""
from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from array import array
from pathlib import Path

from texel.gen import brush as B
from texel.gen.plan_int_tables import table
from texel.gen.rng import Rng

from . import mpy

CORE = mpy.ROOT / "device" / "cmod" / "texelcore"
SRCS = (CORE / "brush_core.c", CORE / "texel_core.c", CORE / "refresh_core.c",
        CORE / "check_core.c")
_LIB = None


def available() -> bool:
    return shutil.which("gcc") is not None


def lib() -> ctypes.CDLL:
    global _LIB
    if _LIB is None:
        h = hashlib.sha256()
        for f in SRCS + (CORE / "brush_core.h", CORE / "texel_core.h", CORE / "refresh_core.h",
                         CORE / "check_core.h"):
            h.update(f.read_bytes())
        out = Path(tempfile.gettempdir()) / ("texelpad-core-%s.so" % h.hexdigest()[:16])
        if not out.exists():
            tmp = out.with_suffix(".so.tmp%d" % os.getpid())
            # -fwrapv: none of the core's values overflows int32 (texel_core.h),
            # and if one did, wrap as the ARM builds do rather than let gcc assume
            subprocess.run(["gcc", "-O2", "-std=c99", "-Wall", "-Wextra", "-Werror", "-shared",
                            "-fPIC", "-fwrapv", "-o", str(tmp)] + [str(s) for s in SRCS],
                           check=True)
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


class PaintParts:
    """_texelcore's paint_part and skip (texelcore_api.h) over this library:
    what texel.gen.brush_parts.Painting calls, for tests that run that class on
    CPython against the C loops (its other builds: tests/gen/test_texel_core.py)."""

    def __init__(self) -> None:
        self.calls: list[tuple[int, int, int]] = []     # (w_from, w_to, lo_emit)

    def leak(self, q: array, a: array, n: int, sweeps: int, c: array) -> None:
        leak(q, a, n, sweeps, c)

    def zero(self, a: array) -> None:
        a[:] = array(a.typecode, bytes(a.itemsize * len(a)))

    def skip(self, st: array, steps: int) -> None:
        lib().tb_skip(ctypes.c_void_p(_ptr(st)), ctypes.c_int32(steps))

    def paint_part(self, st, invk, ll, sign, off, n, chunks, bits, tab, log2t, phase, tw,
                   hann, pos, ring, w_from, w_to, lo_emit, work) -> None:
        assert len(ring) >= B.WINDOW and len(work) >= 4 * B.K + 3 * B.WINDOW
        assert 0 <= w_from <= w_to <= B.windows(n) and not (w_from | w_to) & 1
        keep = (tab, log2t, phase, tw, hann, pos)
        t = Tables(*(_ptr(a) for a in keep))
        ptrs = (ctypes.c_void_p * len(chunks))(*(_ptr(c) for c in chunks))
        self.calls.append((w_from, w_to, lo_emit))
        lib().tb_paint_range(ctypes.c_void_p(_ptr(st)), ctypes.c_void_p(_ptr(invk)),
                             ctypes.c_void_p(_ptr(ll)), ctypes.c_int32(sign),
                             ctypes.c_int32(off), ctypes.byref(t), ctypes.c_int32(n), ptrs,
                             ctypes.c_int32(bits), ctypes.c_void_p(_ptr(work)),
                             ctypes.c_void_p(_ptr(ring)), ctypes.c_int32(w_from),
                             ctypes.c_int32(w_to), ctypes.c_int32(lo_emit))
        del keep


def leak(q: array, a: array, n: int, sweeps: int, c: array) -> None:
    lib().tb_leak(ctypes.c_void_p(_ptr(q)), ctypes.c_void_p(_ptr(a)), ctypes.c_int32(n),
                  ctypes.c_int32(sweeps), ctypes.c_void_p(_ptr(c)))


def log2_q24(v: int, log2t: array) -> int:
    """brush_core.c tb_log2_q24: brush.log2_q24."""
    f = lib().tb_log2_q24
    f.restype = ctypes.c_int32
    return f(ctypes.c_int32(v), ctypes.c_void_p(_ptr(log2t)))


def wave_ll(a: array, invk: array, ll: array, base: int, s: tuple, ll_none: int, ll_max: int,
            log2t: array) -> None:
    """brush_core.c tb_wave_ll: brush._waves_ll for a brush of one shape s."""
    i64 = ctypes.c_int64
    lib().tb_wave_ll(ctypes.c_void_p(_ptr(a)), ctypes.c_int32(len(invk)),
                     ctypes.c_void_p(_ptr(invk)), ctypes.c_void_p(_ptr(ll)), i64(base),
                     ctypes.c_int32(s[0]), i64(s[1]), i64(s[2]), ctypes.c_int32(ll_none),
                     ctypes.c_int32(ll_max), ctypes.c_void_p(_ptr(log2t)))


def _p(a) -> ctypes.c_void_p:
    return ctypes.c_void_p(_ptr(a))


def texels(st: array, count: int, L: int, mu: int, sigma: int, q: int, dcap: int, tab: array,
           t28: array, d28: array, ys: array, zs: array, keep: int) -> int:
    """texel.gen.plan_int.texels_py by tc_texels: the same arguments (arrays:
    st 'H' of 10, the rest 'i'), the same results."""
    i32 = ctypes.c_int32
    return lib().tc_texels(_p(st), i32(count), i32(L), i32(mu), i32(sigma), i32(q), i32(dcap),
                           _p(tab), _p(t28), _p(d28), _p(ys), _p(zs), i32(keep))


def fill(out: array, a: int, b: int, t: int, d: int, tab: array, g: int) -> int:
    """texel.gen.engine_int._fill_py by tc_fill."""
    i32 = ctypes.c_int32
    return lib().tc_fill(_p(out), i32(a), i32(b), i32(t), i32(d), _p(tab), i32(g))


def render(out: array, n: int, L: int, count: int, t28: array, d28: array, tab: array,
           g: int) -> None:
    """texel.gen.engine_int.render_u16's loop by tc_render."""
    i32 = ctypes.c_int32
    lib().tc_render(_p(out), i32(n), i32(L), i32(count), _p(t28), _p(d28), _p(tab), i32(g))


def samples(vals: list[int], fit: str, n: int, chunk_bits: int = 9) -> list[int]:
    """kinds/samples.py fill_chunks by the C loop (tc_samples), into chunks
    of 2^chunk_bits values."""
    size = 1 << chunk_bits
    chunks = [array("H", bytes(2 * min(size, n - o))) for o in range(0, n, size)]
    ptrs = (ctypes.c_void_p * len(chunks))(*(_ptr(c) for c in chunks))
    v = array("H", vals)
    lib().tc_samples(ptrs, ctypes.c_int32(chunk_bits), ctypes.c_int32(n),
                     ctypes.c_void_p(_ptr(v)), ctypes.c_int32(len(vals)),
                     ctypes.c_int32(0 if fit == "tile" else 1))
    return [x for c in chunks for x in c]


def sines(steps: tuple, consts: tuple, n: int, parts: int = 1) -> list[int]:
    """gen/reference_viper.py fill by the C loop (tc_sines): the first n values of the sum
    of sines of these phase steps (gen/reference.py _SINES) with fill's constants (a0, ws,
    rq) as uint16, in `parts` calls (the phases carry from one to the next)."""
    from texel.gen import sine_table
    st = array("i", [x for s in steps for x in divmod(s * 1024, 100000)])   # steps_of
    ph = array("i", bytes(8 * len(steps)))
    tab = sine_table.table()
    a0, ws, rq = consts
    out = array("H", bytes(2 * n))
    cuts = [n * k // parts for k in range(parts + 1)]
    i32 = ctypes.c_int32
    for a, b in zip(cuts, cuts[1:]):
        lib().tc_sines(ctypes.c_void_p(_ptr(out) + 2 * a), i32(b - a), ctypes.c_void_p(_ptr(st)),
                       ctypes.c_void_p(_ptr(ph)), i32(len(steps)), ctypes.c_void_p(_ptr(tab)),
                       i32(a0), i32(ws), i32(rq))
    return list(out)


def options(plan, ys: array, dmin: int, flags: int, tries: int) -> tuple[int, int, int]:
    """tc_options on a plan the loop made (plan_int.PlanInt without its
    options; t28, d28 and ys changed in place): (redrawn, at_min, above)."""
    from texel.gen.options import REDRAW_CONSTS
    r = Rng(plan.params["seed"], consts=REDRAW_CONSTS)
    st = array("H", (r.a_hi, r.a_lo, r.b_hi, r.b_lo, r.c_hi, r.c_lo, r.d_hi, r.d_lo))
    tab = array("i", table())
    t28, d28 = array("i", plan.t28), array("i", plan.d28)
    out = array("i", (0, 0, plan.above_nyquist))
    i32 = ctypes.c_int32
    lib().tc_options(ctypes.c_void_p(_ptr(st)), i32(plan.count), i32(plan.L), i32(plan.mu),
                     i32(plan.sigma), i32(plan.q), i32(plan.dcap), i32(dmin), i32(flags),
                     i32(tries), ctypes.c_void_p(_ptr(tab)), ctypes.c_void_p(_ptr(ys)),
                     ctypes.c_void_p(_ptr(t28)), ctypes.c_void_p(_ptr(d28)),
                     ctypes.c_void_p(_ptr(out)))
    plan.t28[:] = t28
    plan.d28[:] = d28
    return out[0], out[1], out[2]


def plan_with_options(p: dict) -> tuple[list[int], list[int], tuple[int, int, int]]:
    """What texelcore_api.h plan computes for a validated format-2 set p with
    options: tc_plan_consts, tc_seeded, tc_texels keeping the log pitches,
    then tc_plan_options (its redraw stream, d_min, hopeless test and
    MIN_TRIES): (t28, d28, (redrawn, at_min, above))."""
    from texel.gen.grid import mdb as grid_mdb
    from texel.gen.params import texel_count
    k = plan_consts(mdb(p["pitch_db"]), mdb(p["irregularity_db"]), mdb(p["quant_db"]),
                    mdb(p["band_limit_cpmm"]) if p["band_limit_cpmm"] is not None else 0)
    st = array("H", seeded(p["seed"]))
    count, L = texel_count(p), p["texel_samples"]
    tab = array("i", table())
    t28, d28, ys = (array("i", bytes(4 * count)) for _ in range(3))
    one = array("i", [0])
    above = texels(st, count, L, k[0], k[1], k[2], k[3], tab, t28, d28, ys, one, 2)
    lo = p.get("min_cpmm")
    out = (ctypes.c_int32 * 3)()
    kk = (ctypes.c_int32 * 4)(*k)
    i32 = ctypes.c_int32
    lib().tc_plan_options(ctypes.c_uint32(p["seed"]), i32(grid_mdb(lo) if lo is not None else -1),
                          i32(1 if p.get("phase") == "reset" else 0), i32(count), i32(L), kk,
                          ctypes.c_void_p(_ptr(tab)), ctypes.c_void_p(_ptr(ys)),
                          ctypes.c_void_p(_ptr(t28)), ctypes.c_void_p(_ptr(d28)), i32(above), out)
    return list(t28), list(d28), (out[0], out[1], out[2])


def grid(value: float, tie: float, lo: float, hi: float) -> float | None:
    """check_core.h tc_grid (CPython's double): the grid point, or None where
    it leaves the value to gen/grid.py."""
    out = ctypes.c_double()
    f = lib().tc_grid_c
    f.argtypes = [ctypes.c_double] * 4 + [ctypes.POINTER(ctypes.c_double)]
    return out.value if f(value, tie, lo, hi, ctypes.byref(out)) else None


def plan_consts(pitch_mdb: int, irreg_mdb: int, quant_mdb: int, cap_mc: int) -> list[int]:
    """texel_core.c tc_plan_consts: PlanInt's mu, sigma, q, dcap."""
    out = (ctypes.c_int32 * 4)()
    tab = array("i", table())
    lib().tc_plan_consts(ctypes.c_int32(pitch_mdb), ctypes.c_int32(irreg_mdb),
                         ctypes.c_int32(quant_mdb), ctypes.c_int32(cap_mc),
                         ctypes.c_void_p(_ptr(tab)), out)
    return list(out)


def seeded(seed: int) -> list[int]:
    """texel_core.c tc_seeded: plan_int.seeded's 10 halves."""
    st = (ctypes.c_uint16 * 10)()
    lib().tc_seeded(ctypes.c_uint32(seed), st)
    return list(st)


def mdb(value: float) -> int:
    """check_core.h tc_mdb (double): gen/grid.py mdb."""
    f = lib().tc_mdb_c
    f.argtypes = [ctypes.c_double]
    f.restype = ctypes.c_int32
    return f(value)
