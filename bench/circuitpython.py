"""texelpad on a CircuitPython Pico (issue 35 item 3): stock CircuitPython
10.2.1 on the emulated Pico (../shared/instruments/cpyemu), this checkout on
its CIRCUITPY drive as `texelpad deploy` lays it out (sources: CircuitPython
compiles them at import), a finger sweeping the softpot (--adc-js). On the
board's own clock (time.monotonic_ns, 30.5 us steps): importing texel.app,
start("pico_cpy") with a full-screen format-2 texel, pushes (validate, build,
swap), the heap free while playing, and the refresh rate the paced loop
reaches at several asked rates - alone (app.run_loop) and while serving the
host (texel.app.serve(): the loop also polls the console) - with its
overruns (refreshes whose body took longer than the period) and late
refreshes (started more than a period after they were due).

    .venv/bin/python -m bench.circuitpython [--json PATH]

Figures only; never fails on them. ~3 wall minutes.
"""
from __future__ import annotations

import argparse
import ast
import json
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
RATES = (2000, 1500, 1250, 1000)
SECONDS = 1.0                     # emulated s per rate and loop
FINGER_JS = "(ch, t) => ch === 0 ? 600 + Math.floor((t * 700) % 3000) : 0"

BOARD_CODE = r"""
import gc
from texel import compat
T, D = compat.ticks_us, compat.ticks_diff
res = {}
gc.collect()
res["free_prompt"] = gc.mem_free()
t = T()
import texel.app as a
res["import_us"] = D(T(), t)
gc.collect()
res["free_imported"] = gc.mem_free()

def texel(seed):
    return a.full_screen({"kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9,
                          "seed": seed, "v": 2})

t = T()
a.start("pico_cpy", texel(7), report=False)
res["start_us"] = D(T(), t)
res["start_push"] = a._rt.last_push
gc.collect()
res["free_playing"] = gc.mem_free()
pushes = []
for seed in range(8, 13):
    t = T()
    st = a.push(texel(seed))
    pushes.append([D(T(), t), st["last_push"]])
    a.tidy()
res["pushes"] = pushes
for name, tex in (("constant", {"kind": "constant", "level": 0.5}),
                  ("reference 4sin", {"kind": "reference", "name": "4sin"})):
    t = T()
    try:
        st = a.push(a.full_screen(tex))
        res[name] = [D(T(), t), st["last_push"]]
    except ValueError as e:
        res[name] = str(e)
    a.tidy()
a.push(texel(7))
a.tidy()
gc.collect()
res["free_playing_again"] = gc.mem_free()

def rate(hz, serving):
    rt = a._rt
    rt.hz = hz
    rt.period_us = 1000000 // hz
    r = rt.refresh
    r.period_us = rt.period_us
    r.overruns = 0
    r.worst_us = 0
    n0 = r.count
    t0 = T()
    if not serving:
        lp = a.run_loop(SECONDS)
        return [hz, "loop", r.count - n0, D(T(), t0), r.overruns, r.worst_us, lp["late"]]
    from texel import serve
    real = compat.console_reader()
    end = [None]
    def read():
        if D(T(), t0) >= int(SECONDS * 1000000):
            end[0] = [hz, "serve", r.count - n0, D(T(), t0), r.overruns, r.worst_us, None]
            raise SystemExit
        return real()
    try:
        serve.serve(lambda: rt, lambda: None, read)
    except SystemExit:
        pass
    return end[0]

rows = []
for hz in RATES:
    rows.append(rate(hz, False))
    rows.append(rate(hz, True))
res["rates"] = rows
a.stop()
print("RESULT " + repr(res))
"""


def measure(say=print) -> dict[str, Any]:
    from texelpad import toolchain
    d = toolchain.instruments_dir()
    k = d / "cpyemu" if d is not None else None
    if k is None or not (k / "run.sh").is_file():
        raise SystemExit("circuitpython: no cpyemu in the instruments")
    with tempfile.TemporaryDirectory() as tmp:
        img = Path(tmp) / "circuitpy.img"
        say(".. laying out the CIRCUITPY drive (cpyemu/make-texel-fs.sh)")
        subprocess.run([str(k / "make-texel-fs.sh"), str(img), str(ROOT)], check=True,
                       capture_output=True, timeout=300)
        script = Path(tmp) / "bench.py"
        script.write_text(BOARD_CODE.replace("RATES", repr(RATES))
                          .replace("SECONDS", repr(SECONDS)))
        say(".. running on the emulated CircuitPython Pico (~3 wall minutes)")
        p = subprocess.run([str(k / "run.sh"), "--timeout", "900", "--fs-image", str(img),
                            "--adc-js", FINGER_JS, str(script)],
                           capture_output=True, text=True, timeout=1800)
    line = [ln for ln in p.stdout.splitlines() if ln.startswith("RESULT ")]
    if not line:
        raise SystemExit("circuitpython: the board printed no result:\n%s\n%s"
                         % (p.stdout[-2000:], p.stderr[-2000:]))
    res = ast.literal_eval(line[-1][len("RESULT "):])
    res["emulated"] = [ln for ln in p.stdout.splitlines() if "emulated_seconds" in ln]
    return res


def _ms(us: int) -> str:
    return "%.1f" % (us / 1000)


def _push(lp: Any) -> str:
    if not isinstance(lp, list):
        return "refused: %s" % lp
    us, p = lp
    return ("%s ms (validate %s + build %s + swap %s, scene %d B)"
            % (_ms(us), _ms(p["validate_us"]), _ms(p["build_us"]), _ms(p["swap_us"]),
               p["scene_bytes"]))


def report(res: dict[str, Any]) -> str:
    out = ["texelpad on the emulated CircuitPython 10.2.1 Pico (board clock; sources on "
           "CIRCUITPY, compiled at import)", ""]
    out.append("heap free: at the prompt %d B; after import texel.app %d B; playing a "
               "full-screen format-2 texel %d B (after 7 pushes: %d B)"
               % (res["free_prompt"], res["free_imported"], res["free_playing"],
                  res["free_playing_again"]))
    out.append("import texel.app: %s ms" % _ms(res["import_us"]))
    out.append("start('pico_cpy', full-screen texel): %s ms; its scene: %s"
               % (_ms(res["start_us"]), _push([0, res["start_push"]]).split(" (", 1)[1][:-1]))
    for us, lp in res["pushes"]:
        out.append("push, format-2 texel: %s" % _push([us, lp]))
    for name in ("constant", "reference 4sin"):
        out.append("push, %s: %s" % (name, _push(res[name])))
    out.append("")
    out.append("paced refresh with a moving finger, %g emulated s each:" % SECONDS)
    out.append("%8s %6s %10s %9s %9s %9s %6s" % ("asked", "loop", "reached", "overruns",
                                                 "worst us", "late", ""))
    for hz, how, n, us, over, worst, late in res["rates"]:
        out.append("%8d %6s %8.0f Hz %9d %9d %9s" % (hz, how, n * 1e6 / us, over, worst,
                                                     "-" if late is None else late))
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", help="also write the figures as JSON here")
    args = ap.parse_args(argv)
    res = measure(lambda m: print(m, file=sys.stderr))
    print(report(res))
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1, sort_keys=True) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
