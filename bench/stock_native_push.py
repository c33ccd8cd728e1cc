"""app.push of a full-screen format-2 texel texture (no "v", as a user writes
it) on the emulated stock Pico after `texelpad deploy`: first with the C
core's native module (/lib/_texelcore.mpy, armv6m), then with it removed and
a soft reset (the viper twins), on the board's own clock (ticks_us).

    python bench/stock_native_push.py > bench/results/stock_native_push.json
"""
from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.firmware import BOARD, USER_SCRIPT, _total  # noqa: E402
from texelpad.deploy.install import deploy  # noqa: E402
from texelpad.link.board import connect  # noqa: E402
from texelpad.sim.emulated import EmulatedPico  # noqa: E402

ENGINES = ("from texel.gen import plan_int as P, engine_int as E\nimport gc\ngc.collect()\n"
           "print(repr((P.ENGINE, E.ENGINE, gc.mem_free())))")


def main() -> int:
    out: dict[str, Any] = {}
    with EmulatedPico() as emu:
        emu.start()
        with connect(emu.port, check=False, import_image=False, timeout=120) as b:
            deploy(b, progress=lambda m: print("..", m, file=sys.stderr))
        for label in ("native", "viper"):
            with connect(emu.port, timeout=120) as b:
                b.start(BOARD)
                tot = _total(b.status()["display"])
                eng = b.link.eval(ENGINES)
                us = []
                for k in range(5):
                    tex = {"kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9,
                           "seed": 100 + k}
                    us.append(int(b.link.eval(USER_SCRIPT % (tot, tex), timeout=120)))
                st = b.status()
                out[label] = {"engines": eng, "push_us": us, "mem_free_playing": st["mem_free"],
                              "last_push": st["last_push"]}
                print("..", label, out[label], file=sys.stderr)
                if label == "native":
                    b.stop()
                    b.link.exec("import os\nos.remove('/lib/_texelcore.mpy')", timeout=30)
                    b.link.soft_reset()
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
