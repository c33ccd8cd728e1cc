"""What an import statement costs on the emulated Pico, and how many a push runs (issue 32:
docs/firmware.md, "An import statement runs at every call"). MicroPython runs an `import`
inside a function each time the function runs; this prints, on the board's own clock:

  per call     100 calls each of a relative import of a loaded module (`from ..compat
               import core` as texel's modules write it, via __import__ with their
               globals), a two-level name, an absolute `import texel.compat`, and an empty
               loop turn - on the texelpad firmware
  per push     every import statement the board runs while bench/firmware.py's scenes are
               pushed (counted and timed through builtins.__import__): name, level, the
               module that ran it, how many, their us - on the firmware and, with --stock,
               on stock MicroPython after `texelpad deploy`

    .venv/bin/python -m bench.import_cost [--uf2 PATH] [--stock] [--json PATH]

Figures only; never fails on them. ~1 wall minute (+ ~2 with --stock).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]

PER_CALL = r'''
import time
T, D = time.ticks_us, time.ticks_diff
g = {'__name__': 'texel.runtime.kinds.texel'}
def rel(n):
    for _ in range(n):
        __import__('compat', g, None, ('core',), 3)
def rel2(n):
    for _ in range(n):
        __import__('gen.plan_int_tables', g, None, ('table',), 3)
def absolute(n):
    for _ in range(n):
        __import__('texel.compat', None, None, ('core',), 0)
def empty(n):
    for _ in range(n):
        pass
import texel.gen.plan_int_tables
out = {}
for f in (empty, rel, rel2, absolute):
    t = T()
    f(100)
    out[f.__name__] = D(T(), t) / 100
print(repr(out))
'''

COUNTER = r'''
import builtins, time
_IC = {}
_orig_imp = builtins.__import__
def _imp(name, *a):
    g = a[0] if a else None
    k = (name, a[3] if len(a) > 3 else 0, g.get('__name__') if isinstance(g, dict) else None)
    t = time.ticks_us()
    try:
        return _orig_imp(name, *a)
    finally:
        c = _IC.get(k, (0, 0))
        _IC[k] = (c[0] + 1, c[1] + time.ticks_diff(time.ticks_us(), t))
def _icount():
    print(repr(sorted(_IC.items(), key=lambda x: -x[1][1])))
    _IC.clear()
'''

SCENES = ("shipped sine-vs-square", "shipped texel-sweep", "16 texel regions seed 0",
          "full-screen reference 2sin")


def _pushes(b: Any, say) -> list[dict[str, Any]]:
    """Push bench/firmware.py's first scenes (a realistic heap), then SCENES with every
    import statement counted; one row per scene."""
    from bench import firmware as F
    st = b.status()
    b.link.exec(F.DEVICE_CODE, timeout=60)
    allsc = F.scene_list(st["display"])
    for _cat, _name, sc in allsc[:4]:
        F._request(b, sc)
    b.link.exec(COUNTER, timeout=60)
    rows = []
    for name in SCENES:
        sc = next(s for _c, n, s in allsc if n == name)
        b.link.exec("builtins.__import__ = _imp")
        r = F._request(b, sc)
        b.link.exec("builtins.__import__ = _orig_imp")
        counts = b.link.eval("_icount()")
        rows.append({"scene": name, "playing_us": r.get("playing_us"),
                     "refused": r.get("refused"),
                     "imports": [[list(k), v[0], v[1]] for k, v in counts]})
        say(".. %s: %d import statements, %d us" % (
            name, sum(v[0] for _k, v in counts), sum(v[1] for _k, v in counts)))
    return rows


def on_firmware(uf2: Path, say) -> dict[str, Any]:
    from bench import firmware as F
    from texelpad.link.board import connect
    from texelpad.sim.emulated import EmulatedPico, finger_js
    with EmulatedPico(firmware=uf2, extra_args=("--adc-js", finger_js("sweep"))) as emu:
        emu.start()
        with connect(emu.port, timeout=120) as b:
            per_call = b.link.eval(PER_CALL, timeout=120)
            b.start(F.BOARD)
        with connect(emu.port, timeout=120) as b:
            return {"per_call_us": per_call, "pushes": _pushes(b, say)}


def on_stock(say) -> dict[str, Any]:
    from bench import firmware as F
    from texelpad.deploy.install import deploy
    from texelpad.link.board import connect
    from texelpad.sim.emulated import EmulatedPico, finger_js
    with EmulatedPico(firmware=None, extra_args=("--adc-js", finger_js("sweep"))) as emu:
        emu.start()
        with connect(emu.port, check=False, import_image=False, timeout=120) as b:
            deploy(b, progress=lambda m: None)
        with connect(emu.port, timeout=120) as b:
            b.start(F.BOARD)
        with connect(emu.port, timeout=120) as b:
            return {"pushes": _pushes(b, say)}


def report(res: dict[str, Any]) -> list[str]:
    out = ["import statements on the emulated Pico (board clock)"]
    pc = res["firmware"]["per_call_us"]
    out.append("per call, firmware: relative import of a loaded module %.1f us, a two-level "
               "name %.1f us, absolute %.1f us; an empty loop turn %.1f us"
               % (pc["rel"], pc["rel2"], pc["absolute"], pc["empty"]))
    for col in ("firmware", "stock"):
        if col not in res:
            continue
        for row in res[col]["pushes"]:
            imps = row["imports"]
            out.append("%s, %s: %s; %d import statements, %d us%s" % (
                col, row["scene"], "refused" if row["refused"] else "playing %.1f ms"
                % (row["playing_us"] / 1e3), sum(n for _k, n, _t in imps),
                sum(t for _k, _n, t in imps),
                "".join("\n    %s level %d from %s: %d, %d us" % (k[0] or "(package)", k[1],
                                                                  k[2], n, t)
                        for k, n, t in imps)))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--uf2", help="the texelpad firmware (.uf2; default: bench/firmware.py's)")
    ap.add_argument("--stock", action="store_true", help="also stock MicroPython + deploy")
    ap.add_argument("--json", metavar="PATH", help="also write the figures as JSON")
    a = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from bench.firmware import bench_uf2, print_and_save, stderr_say as say
    uf2 = bench_uf2(a.uf2)
    res = {"firmware": on_firmware(uf2, say)}
    if a.stock:
        res["stock"] = on_stock(say)
    return print_and_save(report(res), res, a.json)


if __name__ == "__main__":
    raise SystemExit(main())
