"""Does a brush play under a moving finger while it is still being painted? (issue 32:
docs/firmware.md, "A brush plays under the finger first"). A full-screen brush push swaps
its scene in once the part around the finger is painted and paints the rest after the
answer, part by part on the side the finger is nearer (texel.app.PAINT_NEAR_FINGER,
texel/gen/brush_parts.py Painting). On the emulated Pico's texelpad firmware, for fingers
sweeping end to end and back at several speeds, each of PUSHES full-screen brush pushes
(bench/firmware.py's brush, seeds 1..) comes after a constant scene, with the board's
telemetry on (texel.app.stream: one refresh in 5 ms, position and amplitude); after the
push's answer and the painting, every sampled refresh on the brush is checked against the
finished map at its position: a refresh that read another value read a sample not yet
painted. Prints, per speed: the finger's speed (measured from the telemetry), the brush
pushes' -> playing and the painting after the answer (median, max), the sampled
refreshes on the brush (during the painting) and how many of them read an unpainted sample.

    .venv/bin/python -m bench.brush_chase [--uf2 PATH] [--periods 2,1,0.5] [--pushes 6]
                                          [--json PATH]

Figures only; never fails on them. ~1.5 wall minutes a speed.
"""
from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
RATE_HZ = 200           # telemetry samples a second: the 256-sample ring holds 1.28 s, more
                        # than a push, its painting and the commands around them take
CONST_U16 = 8061        # the constant scene's level 0.123 as the board plays it (u16)

CHECK = r'''
tel, lost = _tpf_A.telemetry()
_tpf_A.stream(0)
m = _tpf_A._rt.refresh.scene._bufs[0]
r0 = _tpf_W.replied_us
tu = _tpf_W.tidy_us
on = bad = during = bad_during = 0
for t, p, a in tel:
    if p < 0 or a == %d:
        continue
    on += 1
    # from the swap (the first sample on the brush) to the painting's end
    d = time.ticks_diff(t, r0) <= tu
    miss = m[p >> 9][p & 511] != a
    during += d
    bad += miss
    bad_during += d and miss
sp = [abs(tel[i + 1][1] - tel[i][1]) * 1000000 // max(1, time.ticks_diff(tel[i + 1][0], tel[i][0]))
      for i in range(len(tel) - 1) if tel[i][1] >= 0 and tel[i + 1][1] >= 0]
print(repr((len(tel), lost, on, during, bad, bad_during, max(sp) if sp else 0)))
''' % CONST_U16


def sweep_js(period_s: float) -> str:
    """bench/firmware.py's finger (texelpad.sim.emulated FINGERS "sweep") with
    period_s seconds end to end and back."""
    return ("(ch, t) => ch === 0 ? Math.round(125 + 3812 * (1 - Math.abs(((t / %g) %% 2) - 1)))"
            " : 0" % (period_s / 2))


def one_speed(uf2: Path, period_s: float, pushes: int, say) -> dict[str, Any]:
    import ast
    from bench import firmware as F
    from texelpad.link.board import connect
    from texelpad.sim.emulated import EmulatedPico
    rows = []
    with EmulatedPico(firmware=uf2, extra_args=("--adc-js", sweep_js(period_s))) as emu:
        emu.start()
        with connect(emu.port, timeout=120) as b:
            b.start(F.BOARD)
        with connect(emu.port, timeout=120) as b:
            display = b.status()["display"]
            b.link.exec(F.DEVICE_CODE + "\nimport texel.app as _tpf_A\nimport texel.wire as _tpf_W\n", timeout=60)
            const = {"regions": [{"start_mm": 0, "end_mm": F._total(display),
                                  "texture": {"kind": "constant", "level": 0.123}}]}
            for k in range(pushes):
                F._request(b, const)
                b.link.exec("_tpf_A.stream(%d)\n_tpf_A.telemetry()" % RATE_HZ, timeout=60)
                r = F._request(b, F.brush_scene(display, k + 1))
                n, lost, on, during, bad, bad_during, speed = ast.literal_eval(
                    b.link.exec(CHECK, timeout=60).strip().splitlines()[-1])
                row = {"seed": k + 1, "refused": r.get("refused"),
                       "playing_ms": (r.get("playing_us") or 0) / 1e3,
                       "after_answer_ms": (r.get("tidy_us") or 0) / 1e3,
                       "samples": n, "lost": lost, "on_brush": on, "during_painting": during,
                       "unpainted": bad, "unpainted_during_painting": bad_during,
                       "finger_samples_per_s": speed}
                say(".. period %g s, brush %d: %s" % (period_s, k + 1, row))
                rows.append(row)
    ok = [r for r in rows if not r["refused"]]
    mm = [r["finger_samples_per_s"] * display["dx_um"] / 1000.0 for r in ok]
    return {"period_s": period_s, "finger_mm_per_s": [min(mm, default=0), max(mm, default=0)],
            "playing_ms_median": statistics.median(r["playing_ms"] for r in ok) if ok else None,
            "playing_ms_max": max((r["playing_ms"] for r in ok), default=None),
            "after_answer_ms_median": (statistics.median(r["after_answer_ms"] for r in ok)
                                       if ok else None),
            "on_brush": sum(r["on_brush"] for r in ok),
            "during_painting": sum(r["during_painting"] for r in ok),
            "unpainted": sum(r["unpainted"] for r in ok),
            "unpainted_during_painting": sum(r["unpainted_during_painting"] for r in ok),
            "lost": sum(r["lost"] for r in ok), "refused": len(rows) - len(ok), "rows": rows}


def report(res: dict[str, Any]) -> list[str]:
    out = ["a brush under a moving finger while it is painted (issue 32): the emulated Pico's "
           "texelpad firmware, %s" % res["uf2"],
           "%d full-screen brush pushes a speed; telemetry: one refresh in %d ms"
           % (res["pushes"], 1000 // RATE_HZ), "",
           "%-9s %15s %22s %18s %26s %20s" % ("sweep", "finger", "-> playing med/max",
                                              "after the answer", "sampled on brush (painting)",
                                              "unpainted (painting)")]
    for s in res["speeds"]:
        out.append("%-9s %4.0f-%4.0f mm/s %11.1f / %5.1f ms %12.1f ms %16d (%4d) %13d (%4d)" % (
            "%g s" % s["period_s"], s["finger_mm_per_s"][0], s["finger_mm_per_s"][1],
            s["playing_ms_median"] or 0, s["playing_ms_max"] or 0,
            s["after_answer_ms_median"] or 0, s["on_brush"], s["during_painting"],
            s["unpainted"], s["unpainted_during_painting"]))
    out += ["", "finger: the fastest move between two samples (telemetry), the least and the "
            "most over the pushes; after the answer: the rest of the painting and the "
            "collection (texel.wire.tidy_us); (painting): from the swap to the painting's end; "
            "unpainted: sampled refreshes whose amplitude is not the finished map's at their "
            "position"]
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--uf2", help="the texelpad firmware (.uf2; default: bench/firmware.py's)")
    ap.add_argument("--periods", default="2,1,0.5",
                    help="seconds a sweep takes end to end and back, comma-separated")
    ap.add_argument("--pushes", type=int, default=6, help="brush pushes a speed")
    ap.add_argument("--json", metavar="PATH", help="also write the figures as JSON")
    a = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from bench.firmware import bench_uf2, print_and_save, stderr_say as say
    uf2 = bench_uf2(a.uf2)
    periods = [float(x) for x in a.periods.split(",") if x.strip()]
    res = {"uf2": str(uf2), "pushes": a.pushes,
           "speeds": [one_speed(uf2, p, a.pushes, say) for p in periods]}
    return print_and_save(report(res), res, a.json)


if __name__ == "__main__":
    raise SystemExit(main())
