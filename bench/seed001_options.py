"""What seed 001's texture options cost on the chip: `python -m bench.seed001_options
[--json OUT]`.

The options (texel.gen.params OPTION_SPEC: `min_cpmm`, a lower pitch bound
redrawn from a second stream; `phase: "reset"`; docs/generator.md, "Seed 001's
stimulus") run as a pass after the per-texel loop (texel/gen/options.py), in
Python on every runtime. This measures it on the emulated Raspberry Pi Pico
(../shared/instruments/rp2emu: the real MicroPython v1.28 firmware on
rp2040js, time from cycle counts - texelpad.sim.emulated, stock firmware +
`texelpad deploy`), on the board's own clock (time.ticks_us: emulated us):

- the plan alone (texel.make_plan of a validated format-2 texture) with and
  without the options, for the textures the studies play: the staircase's at
  its start (26 mm texels) and its floor (1.25 mm) on the whole display, the
  mapping's (1 mm texels, half the display) at a low and a mid slider
  setting, and a 50-sample texture (the free exploration's texel) on the
  whole display - the most texels a study plays;
- a whole push of the staircase's scene and of the mapping's (validate,
  build, swap: texel.app's last_push), as the lab pushes them.

Error: none to report - the options are integer arithmetic in format 2, the
same bits on every runtime (tests/gen/test_seed001_options.py proves it on
the unix port, ulab f32/f64 and CircuitPython); this bench reads the board's
counts of redrawn texels beside the times.
"""
from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from texel.gen.lognormal import to_db

from bench import deployed_pico
from texelpad.study import scenes as S
from texelpad.study.mapping import slider_values

DISPLAY = {"positions": 19200, "dx_um": 5.3}
STAIR = dict(zip(("pitch_db", "irregularity_db"), to_db(4.0, 4.3)))      # the wide condition
OPTS = {"min_cpmm": 1.0, "phase": "reset"}
BOARD_CODE = '''
import gc, time, texel
def _tpo_plan(p, reps):
    p = texel.validate(p)
    best = None
    for _ in range(reps):
        gc.collect()
        t0 = time.ticks_us()
        pl = texel.make_plan(p)
        dt = time.ticks_diff(time.ticks_us(), t0)
        best = dt if best is None or dt < best else best
    return (best, pl.count, getattr(pl, "redrawn", 0), getattr(pl, "at_min", 0))
'''


def cases() -> list[tuple[str, dict[str, Any]]]:
    zero = dict(zip(("pitch_db", "irregularity_db"), to_db(*slider_values(0.0, 0.0))))
    lo = dict(zip(("pitch_db", "irregularity_db"), to_db(*slider_values(0.0, 10.0))))
    mid = dict(zip(("pitch_db", "irregularity_db"), to_db(*slider_values(50.0, 50.0))))
    out = []
    for name, base, n, length in (
            ("staircase 26 mm, whole display", STAIR, 4906, 19200),
            ("staircase 1.25 mm (floor), whole display", STAIR, 236, 19200),
            ("mapping P=0 I=0 (no draw reaches 1 c/mm)", zero, 189, 9600),
            ("mapping P=0 I=10 (mean 0.75 c/mm), half display", lo, 189, 9600),
            ("mapping P=50 I=50, half display", mid, 189, 9600),
            ("50-sample texels, whole display (384 texels)", STAIR, 50, 19200)):
        p = dict(base, texel_samples=n, length_samples=length, seed=12345, v=2)
        out.append((name, p))
    return out


def run(reps: int, say) -> dict[str, Any]:
    from texelpad.link.board import connect
    res: dict[str, Any] = {"chip": "rp2040 (rp2emu)", "reps": reps, "plans": [], "pushes": []}
    with deployed_pico(say, res) as port:
        with connect(port, timeout=120) as b:
            st = b.start("pico")
            res["firmware"] = st.get("firmware")
            b.link.exec(BOARD_CODE, timeout=60)
            for name, p in cases():
                row: dict[str, Any] = {"case": name, "texture": p}
                for key, extra in (("without", {}), ("with", OPTS)):
                    us, count, redrawn, at_min = b.link.eval(
                        "print(repr(_tpo_plan(%r, %d)))" % (dict(p, **extra), reps), timeout=600)
                    row[key] = {"plan_us": us, "texels": count, "redrawn": redrawn,
                                "at_min": at_min}
                    say("%s %s options: %d us" % (name, key, us))
                res["plans"].append(row)
            for name, scene in _scenes():
                b.push(scene)
                lp = b.link.eval("print(repr(texel.app.status()['last_push']))")
                res["pushes"].append({"case": name, "last_push": lp})
                say("push %s: %r" % (name, lp))
    return res


def _scenes() -> list[tuple[str, dict[str, Any]]]:
    stair = dict(STAIR, **OPTS)
    out = []
    for mm in (26.0, 1.25):
        sc, _ = S.staircase_scenes(int(round(mm / 0.0053)), 0, 7, DISPLAY, stair)
        out.append(("staircase %g mm (seed 001)" % mm, sc[0]))
    tex = dict(zip(("pitch_db", "irregularity_db"), to_db(*slider_values(50.0, 50.0))),
               texel_samples=189, seed=99, v=2, **OPTS)
    out.append(("mapping P=50 I=50, reference as the board's bp-4-0.5",
                S.split({"kind": "reference", "name": "bp-4-0.5"}, tex, DISPLAY)))
    return out


def table(res: dict[str, Any]) -> str:
    lines = ["seed 001's texture options on the emulated RP2040 (%s), plan build, best of %d, "
             "emulated us" % (res.get("firmware"), res["reps"]),
             "%-50s %7s %10s %10s %8s %7s" % ("texture", "texels", "without", "with", "ratio",
                                             "redrawn")]
    for r in res["plans"]:
        a, b = r["without"], r["with"]
        lines.append("%-50s %7d %10d %10d %8.2f %7d" % (r["case"], a["texels"], a["plan_us"],
                                                         b["plan_us"], b["plan_us"] / a["plan_us"],
                                                         b["redrawn"]))
    lines.append("")
    lines.append("whole pushes (texel.app last_push, emulated us):")
    for r in res["pushes"]:
        lp = r["last_push"] or {}
        lines.append("  %-52s validate %7s  build %8s  swap %6s" % (
            r["case"], lp.get("validate_us"), lp.get("build_us"), lp.get("swap_us")))
    lines.append("wall %.1f s" % res["wall_s"])
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reps", type=int, default=3, help="plans per case; the best is kept")
    ap.add_argument("--json", metavar="OUT", help="write the figures as JSON")
    args = ap.parse_args(argv)
    res = run(args.reps, lambda m: print(m, file=sys.stderr, flush=True))
    print(table(res))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
