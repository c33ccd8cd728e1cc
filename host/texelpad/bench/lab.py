"""Benchmark for texelpad lab: slider change -> the new scene playing on the
virtual board, through the lab's own board owner (texelpad.web.owner: the
host-side check, the push, the board's validation, build and swap, its status
back). Each step is what a pitch or irregularity slider of the free
exploration sends: the reference on the left half, the texel rendering
(format 2) on the right.

    .venv/bin/python -m texelpad.bench.lab [--steps N] [--json PATH]

Prints median, p95 and max in ms and writes the figures as JSON.
"""
from __future__ import annotations

import argparse
import json
import statistics
import time

from ..link.virtual import open_virtual, stop_on_signals
from ..study import scenes as S
from ..study.space import Point
from ..web.owner import BoardOwner


def run(steps: int = 200) -> dict:
    with stop_on_signals():
        vb = open_virtual(source=True)
        try:
            owner = BoardOwner(vb.port, "virtual", realtime=True)
            display = owner.display()
            times = []
            for k in range(steps):
                # a slider sweep: pitch back and forth, irregularity slowly
                u = 0.2 + 0.6 * abs((k % 40) - 20) / 20
                v = 0.3 + 0.4 * (k % 97) / 97
                scene = S.point_scene(S.DEFAULT_REFERENCE, Point(u, v), display)
                t0 = time.perf_counter()
                st, _ = owner.push(scene)
                times.append((time.perf_counter() - t0) * 1e3)
            last = owner.status()
            owner.close()
        finally:
            vb.stop()
    s = sorted(times)
    return {"steps": steps, "median_ms": statistics.median(times),
            "p95_ms": s[min(len(s) - 1, int(0.95 * (len(s) - 1) + 0.5))], "max_ms": s[-1],
            "overruns": last["overruns"], "refreshes": last["refreshes"],
            "board": "virtual (MicroPython unix port, real time)"}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m texelpad.bench.lab", description=__doc__)
    p.add_argument("--steps", type=int, default=200)
    p.add_argument("--json", metavar="PATH")
    a = p.parse_args(argv)
    res = run(a.steps)
    print("slider change -> new scene playing on the %s: median %.1f ms, p95 %.1f ms, "
          "max %.1f ms over %d changes; %d overruns in %d refreshes"
          % (res["board"], res["median_ms"], res["p95_ms"], res["max_ms"], res["steps"],
             res["overruns"], res["refreshes"]))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
