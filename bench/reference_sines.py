"""The sums of sines (2sin, 3sin, 4sin) on a stock Pico, speed against error: the float path
(gen/reference.py, float32 sines and heap floats) and the integer one (gen/reference_viper.py,
which reference_u16 takes on a float32 board with viper), each timed on the emulated RP2040's
own clock (time.ticks_us: emulated us) over a half screen (9,600 samples), and each map compared
at every sample with CPython's binary64 map (texel.reference_u16 here). Then main.py's power-up
on a fresh heap (a raw soft reset first), the work a friendly Ctrl-D waits for (issue 30: the
REPL answers within 1 s of board time).

    .venv/bin/python -m bench.reference_sines [--json FILE]

Needs the emulated Pico (../shared/instruments/rp2emu, node); stock MicroPython v1.28 with
`texelpad deploy`. Prints a table; never fails on a time."""
from __future__ import annotations

import argparse
import base64
import json
import sys
from typing import Any

import numpy as np

import texel
from bench import deployed_pico

NAMES = ("2sin", "3sin", "4sin")
N = 9600

# defines _trs(name, path): emulated us of reference_u16 by one path (None: no such path here),
# the map left in _U, which _trs_piece(a, b) hands back as base64 (small pieces: a 38 KB
# answer at once needs as much of the heap again)
BOARD_CODE = """
import gc, time, binascii, texel
from texel.gen import reference as _R
_U = None
def _trs(name, path):
    global _U
    _U = None
    gc.collect()
    _U = texel.reference_u16(name, %d)           # imports and buffer outside the timing
    _R._INT_SINES = None if path == 'int' else False
    if path == 'int' and not _R._int_sines():
        return None
    t0 = time.ticks_us()
    texel.reference_u16(name, %d, _U)
    dt = time.ticks_diff(time.ticks_us(), t0)
    _R._INT_SINES = None
    return dt
def _trs_piece(a, b):
    return binascii.b2a_base64(memoryview(_U)[a:b]).decode().strip()
""" % (N, N)
PIECE = 1200            # samples a piece (1,600 base64 characters)

MAIN_PY = ("import time\nt0 = time.ticks_us()\nexec(open('/main.py').read())\n"
           "print(repr(time.ticks_diff(time.ticks_us(), t0)))")


def run(say) -> dict[str, Any]:
    from texelpad.link.board import connect
    res: dict[str, Any] = {"chip": "rp2040 (rp2emu)", "samples": N, "rows": []}
    with deployed_pico(say, res) as port:
        with connect(port, timeout=120) as b:
            b.link.exec(BOARD_CODE, timeout=60)
            res["firmware"] = b.status().get("firmware")
            for name in NAMES:
                want = np.asarray(texel.reference_u16(name, N), dtype=np.int64)
                for path in ("int", "float"):
                    us = b.link.eval("print(repr(_trs(%r, %r)))" % (name, path), timeout=600)
                    row: dict[str, Any] = {"name": name, "path": path, "us": us}
                    if us is not None:
                        raw = b"".join(base64.b64decode(b.link.eval(
                            "print(repr(_trs_piece(%d, %d)))" % (a, a + PIECE)))
                            for a in range(0, N, PIECE))
                        got = np.frombuffer(raw, dtype="<u2").astype(np.int64)
                        d = np.abs(got - want)
                        row.update(worst_u16=int(d.max()), off=int((d > 0).sum()))
                    res["rows"].append(row)
                    say("%s %s: %s us" % (name, path, us))
        with connect(port, timeout=120) as b:
            b.link.soft_reset()
            res["main_py_us"] = b.link.eval(MAIN_PY, timeout=600)
            say("main.py: %d us" % res["main_py_us"])
    return res


def table(res: dict[str, Any]) -> str:
    lines = ["sums of sines as uint16 maps on the emulated RP2040 (%s), %d samples, the board's "
             "clock; error against CPython's binary64 map at every sample"
             % (res.get("firmware"), res["samples"]),
             "%-6s %-6s %10s %10s %14s" % ("name", "path", "ms", "worst u16", "samples off")]
    for r in res["rows"]:
        if r["us"] is None:
            lines.append("%-6s %-6s %10s" % (r["name"], r["path"], "(no viper)"))
            continue
        lines.append("%-6s %-6s %10.1f %10d %14d" % (r["name"], r["path"], r["us"] / 1e3,
                                                     r["worst_u16"], r["off"]))
    lines.append("")
    lines.append("main.py (import texel.app, the power-up split screen) on a fresh heap: %.0f ms"
                 % (res["main_py_us"] / 1e3))
    lines.append("wall %.1f s; emulator: %s" % (res["wall_s"], res["emulator_summary"]))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", help="write the figures here as JSON")
    a = ap.parse_args(argv)
    res = run(lambda m: print(m, file=sys.stderr, flush=True))
    print(table(res))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
