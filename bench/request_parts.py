"""The pieces of a request on the texelpad firmware (issue 32, the request path),
each timed on the emulated Pico's own clock (time.ticks_us; rp2emu: rp2040js @
125 MHz) while the power-up scene plays: what docs/firmware.md's account of the
request path quotes.

  compile      the push request as texelpad.link.protocol.staged_call writes it now
               (one statement, reply's defaults left out) and as it wrote it before
               (three lines, every argument), the same scene text
  import       `import json` inside a function: MicroPython never caches a built-in
               in sys.modules and looks for an extensible one on every sys.path
               filesystem first (tests/runtime/test_imports.py)
  answer       texel.app.status() (what push answered before) and changes() (what
               pushed answers now), their repr(), and printing the repr
  status trip  the request Board.push sent before every push until it remembered
               the status (Board._known_status): compile + status() + repr + print
  first use    importing texel.gen.options (seed 001's options) the first time

    .venv/bin/python -m bench.request_parts [--uf2 PATH] [--json PATH]

Figures only; never fails on them. ~1 wall minute with the firmware built.
"""
from __future__ import annotations

import sys
from typing import Any

SCENE = ('{"regions":[{"start_mm":0,"end_mm":50.88,"texture":{"kind":"reference","name":"2sin"}},'
         '{"start_mm":50.88,"end_mm":101.76,"texture":{"pitch_db":5.0,"irregularity_db":-3.01,'
         '"texel_samples":50,"seed":173254587,"v":2,"kind":"texel"}}]}')
REPS = 5

# run on the board (one exec); prints one repr() line
ON_BOARD = r'''
import time, gc, sys
T = time.ticks_us
D = time.ticks_diff
txt = %(scene)r
now = "__import__('texel.wire').wire.reply('pushed', %%r)" %% txt
before = "import texel.wire as _m\n_m.reply('push', %%r, (), (), 0, None)\n_m = None" %% txt
trip = "import texel.app as _a\nprint(repr(_a.status()))\n_a = None"
def timed(f, n=%(reps)d):
    out = []
    for _ in range(n):
        gc.collect()
        t0 = T()
        f()
        out.append(D(T(), t0))
    return out
def imp():
    import json
import texel.app as app
st = app.status(collect=False)
ch = app.changes()
r_st = repr(("ok", st))
r_ch = repr(("ok", ch))
res = {
    "compile_now_us": timed(lambda: compile(now, "<r>", "exec")),
    "compile_before_us": timed(lambda: compile(before, "<r>", "exec")),
    "import_json_in_function_us": timed(imp),
    "status_us": timed(lambda: app.status(collect=False)),
    "changes_us": timed(lambda: app.changes()),
    "repr_status_us": timed(lambda: repr(("ok", st))),
    "repr_changes_us": timed(lambda: repr(("ok", ch))),
    "status_chars": len(r_st), "changes_chars": len(r_ch),
}
c = compile(trip, "<s>", "exec")
t0 = T()
exec(c, {})
res["status_trip_run_us"] = D(T(), t0)
t0 = T()
compile(trip, "<s>", "exec")
res["status_trip_compile_us"] = D(T(), t0)
fresh = "texel.gen.options" not in sys.modules
gc.collect()
f0 = gc.mem_free()
t0 = T()
import texel.gen.options
res["first_import_options_us"] = D(T(), t0) if fresh else None
gc.collect()
res["first_import_options_heap_bytes"] = f0 - gc.mem_free() if fresh else None
print(repr(res))
'''


def measure(uf2: str) -> dict[str, Any]:
    from bench.firmware import literal_on_firmware
    return literal_on_firmware("request_parts", uf2, [ON_BOARD % {"scene": SCENE, "reps": REPS}])


def table(res: dict[str, Any]) -> str:
    def med(xs: list[int]) -> float:
        return sorted(xs)[len(xs) // 2] / 1000.0
    rows = [
        ("compile, the push request now (one statement)", med(res["compile_now_us"])),
        ("compile, the push request before (three lines)", med(res["compile_before_us"])),
        ("`import json` inside a function", med(res["import_json_in_function_us"])),
        ("status(collect=False) (push's answer before)", med(res["status_us"])),
        ("changes() (pushed's answer now)", med(res["changes_us"])),
        ("repr of status()'s answer (%d chars)" % res["status_chars"],
         med(res["repr_status_us"])),
        ("repr of changes()' answer (%d chars)" % res["changes_chars"],
         med(res["repr_changes_us"])),
        ("Board.push's status() request before every push: compile",
         res["status_trip_compile_us"] / 1000.0),
        ("  ... and run (status with its collection, repr, print)",
         res["status_trip_run_us"] / 1000.0)]
    if res.get("first_import_options_us") is not None:
        rows.append(("first import of texel.gen.options (seed 001's options; %d bytes of heap)"
                     % res["first_import_options_heap_bytes"], res["first_import_options_us"] / 1000.0))
    lines = ["the pieces of a request on the texelpad firmware, the emulated Pico's clock "
             "(median of %d where repeated), %s" % (REPS, res["uf2"]), ""]
    lines += ["  %-76s %8.2f ms" % r for r in rows]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    from bench.firmware import parts_main
    return parts_main(argv, "python -m bench.request_parts", __doc__, measure, table)


if __name__ == "__main__":
    sys.exit(main())
