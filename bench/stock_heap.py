"""Where a stock Pico's heap goes (issue 32, the stock path): stock
MicroPython 1.28 on the emulated Pico (../shared/instruments/rp2emu), this
checkout deployed with `texelpad deploy` (.mpy files in its flash filesystem,
the armv6m native module where it can be built), then the heap after a
collection (gc.mem_free) at the prompt, after importing texelpad's modules
one at a time in the order texel.app.start() brings them in, and playing the
power-up scene. Each module's figure is what importing it took beyond the
modules above it (its bytecode and objects: a stock board has no frozen code
and no ROMFS, so all of it is RAM).

    .venv/bin/python -m bench.stock_heap [--json PATH]

Figures only; never fails on them. ~2 wall minutes (the deploy takes most).
"""
from __future__ import annotations

import argparse
import json
import sys
from typing import Any

# texel.app.start("pico")'s imports, each after the ones it needs
MODULES = ("texel.compat", "texel.gen.params", "texel.gen.check", "texel.protocol",
           "texel.runtime.duty", "texel.runtime.sensor", "texel.runtime.boards",
           "texel.runtime.refresh", "texel.runtime.kinds", "texel.runtime.scene", "texel.app",
           "texel.wire", "texel.hw.rp2", "_texelcore", "texel.gen.rng", "texel.gen.grid",
           "texel.gen.sine_table", "texel.gen.plan_int_tables", "texel.gen.plan_int",
           "texel.gen.engine_int", "texel.gen.reference", "texel.gen.reference_viper",
           "texel.runtime.kinds.reference", "texel.runtime.kinds.texel",
           "texel.runtime.refresh_fast")
_FREE = "import gc\ngc.collect()\nprint(gc.mem_free())"


def measure(say=print) -> dict[str, Any]:
    import texelpad
    from texelpad.deploy.install import deploy
    from texelpad.sim.emulated import EmulatedPico, why_not
    why = why_not()
    if why:
        raise SystemExit("stock_heap: %s" % why)
    emu = EmulatedPico()
    emu.start()
    try:
        say(".. deploying this checkout to the emulated stock Pico")
        with texelpad.connect(emu.port, check=False, timeout=120) as b:
            deploy(b)
        with texelpad.connect(emu.port, check=False, timeout=120) as b:
            link = b.link
            link.exec("import texel.app\ntexel.app.stop()", timeout=60)
            link.soft_reset(timeout=120)
            prompt = int(link.eval(_FREE, timeout=60))
            rows = []
            last = prompt
            for m in MODULES:
                free = int(link.eval("import %s\n%s" % (m, _FREE), timeout=120))
                rows.append({"module": m, "bytes": last - free, "free": free})
                last = free
            free_start = int(link.eval("import texel.app\ntexel.app.start('pico')\n%s" % _FREE,
                                       timeout=300))
            loaded = link.eval("import sys\nprint(repr(sorted(k for k in sys.modules)))",
                               timeout=60)
    finally:
        emu.stop()
    return {"prompt_free": prompt, "modules": rows, "modules_bytes": prompt - last,
            "start_bytes": last - free_start, "playing_free": free_start,
            "loaded_after_start": loaded}


def report(r: dict[str, Any]) -> str:
    lines = ["stock MicroPython 1.28 on the emulated Pico, this checkout deployed "
             "(texelpad deploy): heap free after a collection",
             "  at the prompt (after a soft reset)          %8d B" % r["prompt_free"]]
    for row in sorted(r["modules"], key=lambda x: -x["bytes"]):
        lines.append("  import %-38s %8d B" % (row["module"], row["bytes"]))
    lines += ["  all of them                                 %8d B" % r["modules_bytes"],
              "  texel.app.start('pico') on top (power-up scene, refresh, sensor) %d B"
              % r["start_bytes"],
              "  free playing the power-up scene             %8d B" % r["playing_free"]]
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", help="write the figures here")
    a = ap.parse_args()
    r = measure(lambda m: print(m, file=sys.stderr))
    print(report(r))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(r, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
