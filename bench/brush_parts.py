"""The brush painter's per-window parts on the emulated Pico's own clock
(issue 32: why a full-screen brush is not under 100 ms). A full screen is 403
windows of 192 samples; each has 97 Weibull draws and half of one inverse
192-point FFT (two windows a transform). Timed per call, N calls each, with
the brush of bench/firmware.py's full-screen brush scene:

  tb_frames      brush_core.c as it is: fill + the radix-2/radix-3 transform of two windows
  fft4           a radix-4 192-point transform of two windows, no fill (bench/brush_parts/
                 fft4.h: a prototype of other integers, not texelpad's)
  tb_draws       brush_core.c as it is: one window's 97 draws (log2, log2, exp2 each)
  table draws    one window's 97 draws from a per-shape table (fft4.h draws_tab: a
                 prototype of other integers, with stand-in tables: its cost, not its values)
  paint          texel.gen.brush.paint of 19,200 samples into 1 KB chunks, the C painter

They are built as a native module for armv6m (MicroPython's py/dynruntime.mk, the
mpfirmware kit) and run on the texelpad firmware.

    .venv/bin/python -m bench.brush_parts [--uf2 PATH] [--json PATH]

Figures only; never fails on them. ~1 wall minute with the firmware built.
"""
from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent / "brush_parts"
CORE = Path(__file__).resolve().parents[1] / "device" / "cmod" / "texelcore"
N = 40
WINDOWS = 403               # gen/brush.py windows(19200)

ON_BOARD = r'''
import sys, time, gc
sys.path.insert(0, '/')
import proto
from texel.gen import brush as B
from texel.runtime.upload import Chunks
_, ptab, tw, hann, log2t, pos = B._tables()
tab = B.table()
T, D = time.ticks_us, time.ticks_diff
def per(f, n):
    gc.collect()
    t0 = T()
    f()
    return D(T(), t0) / n
v = B.validate(%(brush)r)
invk, ll, sign, off = B.compensated(v)
res = {
    "tb_frames_us": per(lambda: proto.time_frames(%(n)d, tab, log2t, ptab, tw, hann, pos), %(n)d),
    "fft4_us": per(lambda: proto.time_fft4(%(n)d, tw), %(n)d),
    "tb_draws_us": per(lambda: proto.time_draws(%(n)d, invk, ll, tab, log2t, ptab, tw, hann,
                                                pos), %(n)d),
    "table_draws_us": per(lambda: proto.time_draws_tab(%(n)d), %(n)d),
}
ch = Chunks(19200)
res["paint_us"] = per(lambda: B.paint(v, 0, 19200, ch), 1)
print(repr(res))
'''


def build() -> bytes:
    """proto.mpy for armv6m, built now in a temporary folder."""
    from texelpad import toolchain
    from texelpad.firmware.natmod import _kit_micropython
    kit = _kit_micropython()
    if kit is None:
        raise SystemExit("brush_parts: no MicroPython kit (../shared/instruments/mpfirmware)")
    with tempfile.TemporaryDirectory(prefix="brush-parts-") as tmp:
        src = Path(tmp) / "src"
        shutil.copytree(HERE, src)
        for name in ("brush_core.c", "brush_core.h"):
            shutil.copy2(CORE / name, src / name)
        args = ["make", "-s", "MPY_DIR=%s" % kit, "ARCH=armv6m",
                "BUILD=%s" % (Path(tmp) / "build"), "PYTHON=%s" % sys.executable]
        mc = toolchain.mpy_cross_cmd()
        if len(mc) == 1:
            args.append("MPY_CROSS=%s" % mc[0])
        p = subprocess.run(args, cwd=src, capture_output=True, text=True)
        if p.returncode:
            raise SystemExit("brush_parts: the build failed:\n" + (p.stdout + p.stderr)[-2000:])
        return (src / "proto.mpy").read_bytes()


def measure(uf2: str) -> dict[str, Any]:
    from bench.firmware import brush_scene, literal_on_firmware
    mpy = build()
    display = {"positions": 19200, "dx_um": 5.3}     # the study display's
    brush = brush_scene(display, 0)["regions"][0]["texture"]["brush"]
    res = literal_on_firmware("brush_parts", uf2, [
        "f = open('/proto.mpy', 'wb')\nf.close()"] + [
        "f = open('/proto.mpy', 'ab')\nf.write(%r)\nf.close()" % mpy[i:i + 1024]
        for i in range(0, len(mpy), 1024)] + [ON_BOARD % {"brush": brush, "n": N}])
    res["calls"] = N
    return res


def table(res: dict[str, Any]) -> str:
    fr, f4 = res["tb_frames_us"] / 2, res["fft4_us"] / 2      # per window
    dr, dt = res["tb_draws_us"], res["table_draws_us"]
    lines = ["the brush painter's parts per window, the emulated Pico's clock (%d calls each), %s"
             % (res["calls"], res["uf2"]), "",
             "  %-62s %8.1f us" % ("tb_frames (fill + transform), per window", fr),
             "  %-62s %8.1f us" % ("radix-4 prototype transform, no fill, per window", f4),
             "  %-62s %8.1f us" % ("tb_draws, 97 draws", dr),
             "  %-62s %8.1f us" % ("table-driven draws prototype, 97 draws", dt),
             "  %-62s %8.1f ms" % ("paint, 19,200 samples (C)", res["paint_us"] / 1000.0),
             "",
             "  per window from paint: %.1f us; the transform alone over %d windows: %.1f ms"
             % (res["paint_us"] / WINDOWS, WINDOWS, fr * WINDOWS / 1000.0),
             "  with table draws and this transform: >= %.1f ms of painting"
             % ((res["paint_us"] / WINDOWS - dr + dt) * WINDOWS / 1000.0)]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    from bench.firmware import parts_main
    return parts_main(argv, "python -m bench.brush_parts", __doc__, measure, table)


if __name__ == "__main__":
    sys.exit(main())
