"""Issue 19's and issue 32's goals measured on the emulated Pico running the texelpad firmware:
`python -m bench.firmware [--uf2 PATH] [--json OUT] [--stock] [--quick]`.

The board is rp2emu (../shared/instruments: rp2040js, time from cycle counts)
booting the .uf2 as if dragged onto a Pico (texelpad.sim.emulated,
EmulatedPico(firmware=...)): MicroPython 1.28 + ulab with texelpad in the
ROMFS partition, playing its power-up scene. Every figure is on the board's
own clock (time.ticks_us: emulated microseconds); the host's clock measures
nothing but the wall time of the run. With --stock the same sequence also
runs on the stock path (today: stock MicroPython + `texelpad deploy`,
open_emulated's way) and its figures go beside the firmware's.

A push is timed as the host sends it (texel's own request,
protocol.staged_call: the scene as JSON text parsed by the board's json
module, then texel.app.pushed - push answered with what it changed, which
Board.push merges into the status it read before - then the reply printed),
wrapped on the board: _tpf_req(code) takes the request's code as text, notes
ticks_us, compiles and runs it exactly as the raw REPL would, and notes ticks_us
again after the reply is printed. texel.app._push (push's and pushed's work) is
wrapped to note when it is entered, and
its own last_push (validate_us, build_us, swap_us: contiguous from its entry)
ends at the swap. So:

    to playing = compile + JSON parse (up to push's entry) + validate + build + swap
    answers    = everything until the reply's line is printed (status() and its
                 repr; texel.wire.reply notes the time): the host has its answer.
                 The collection of the old scene comes after it (app.tidy), while
                 the host reads the line; the next request's compile waits for it

(The bytes' transfer over USB before the compile is not counted: "from the
host's last byte".) The goal verdicts use these figures.

On an RP2040 the link sends a push as a frame to the board's standing reader
(texel.wire.stand, Board.stands): nothing is compiled, and a push is timed from
when the reader has read the frame's last byte (texel.wire.read_us): compile 0,
parse = to push's entry (the scene's JSON read). _tpf_pre / _tpf_post, two
commands around the frame, note and read the figures (each ends the reader;
the next frame starts it again, before the figures' clock starts).

The sequence (one emulator, one boot):
  1. boot; connect; the first push after boot is a free-exploration scene;
  2. PUSHES pushes in a row cycling through the scene list: every shipped
     scene (host/texelpad/scenes), every study config's scenes (the nine
     free-exploration trials: each reference left + a texel texture right;
     the first question of every other config), 16 texel regions, every
     reference full-screen, a full-screen brush (texelpad.brush.document.
     design): each push's figures, refusals, the refresh's overruns over the
     run and free memory after each push (gc.collect(); gc.mem_free()):
     its least-squares slope per push;
  3. refresh cost (texelpad/bench/device/rp2_chip_bench.py's method: a viper busy
     loop timed with the refresh interrupt on and off; the finger sweeps)
     with a full-screen scene of each region kind the refresh tells apart
     (constant, reference from flash, texel plan, brush map, uploaded
     samples) and 16 texel regions;
  4. heap free while playing the power-up scene; then stop, soft reset from
     the raw REPL (main.py does not run): the heap before texelpad starts.
For the worst push (and the goals not met) a second, script-mode run of
rp2emu with --profile replays that scene and the PC histogram is mapped to
the firmware's .elf symbols (arm-none-eabi-nm): where the cycles go.
"""
from __future__ import annotations

import argparse
import ast
import bisect
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Callable

from texelpad.bench.link import slope_per_push

Progress = Callable[[str], None]

BOARD = "pico"
PUSHES = 100
QUICK_SCENES = 3
QUICK_PUSHES = 5
IRQ_SPIN = 300_000          # as texelpad/bench/chip.py: ~29 ms per window on the chip
IRQ_REPS = 3

# the goals (ms unless said): issue 32's table where it sets one (scenes, 16 regions,
# the brush, the refresh on the firmware, the heap, the user's push), issue 19's elsewhere
GOALS = {
    "scene_to_playing_ms": 10.0, "scene_answers_ms": 15.0, "regions16_to_playing_ms": 20.0,
    "reference_to_playing_ms": 20.0, "brush_to_playing_ms": 100.0,
    "first_push_answers_ms": 30.0, "refresh_us": 3.0, "overruns": 0,
    "heap_free_playing_bytes": 180 * 1024, "refused": 0,
    "user_push_ms": 20.0,       # app.push of a full-screen texel without "v"
}
USER_PUSHES = 5                 # the user's script below, each a new seed

# what the board runs (sent once after connecting): the request wrapper
DEVICE_CODE = r'''
import time, gc, sys
import texel.app as _tpf_app
import texel.wire as _tpf_wire
_tpf_t = [None]
_tpf_orig = _tpf_app._push
def _tpf_push(scene):
    _tpf_t[0] = time.ticks_us()
    return _tpf_orig(scene)
_tpf_app._push = _tpf_push
def _tpf_req(code):
    rt = _tpf_app._rt
    ov0 = rt.refresh.overruns
    n0 = rt.pushes
    _tpf_t[0] = None
    _tpf_wire.replied_us = None
    err = None
    t0 = time.ticks_us()
    t1 = t0
    try:
        c = compile(code, '<request>', 'exec')
        t1 = time.ticks_us()
        exec(c, {})
    except Exception as e:
        err = '%s: %s' % (type(e).__name__, e)
    t2 = time.ticks_us()
    if _tpf_wire.replied_us is not None:     # the answer's line, before the collection
        t2 = _tpf_wire.replied_us
    c = None
    code = None
    tp = _tpf_t[0]
    gc.collect()
    print(repr((time.ticks_diff(t1, t0), None if tp is None else time.ticks_diff(tp, t0),
                time.ticks_diff(t2, t0), rt.last_push if rt.pushes != n0 else None, err,
                gc.mem_free(), rt.refresh.overruns - ov0, rt.refresh.worst_us, rt.pushes,
                _tpf_wire.tidy_us)))
_tpf_s = [None]
def _tpf_pre():
    rt = _tpf_app._rt
    _tpf_s[0] = (rt.refresh.overruns, rt.pushes)
    _tpf_t[0] = None
    _tpf_wire.replied_us = None
    _tpf_wire.read_us = None
def _tpf_post():
    rt = _tpf_app._rt
    ov0, n0 = _tpf_s[0]
    t0 = _tpf_wire.read_us
    tp = _tpf_t[0]
    t2 = _tpf_wire.replied_us
    gc.collect()
    print(repr((0, None if tp is None or t0 is None else time.ticks_diff(tp, t0),
                None if t2 is None or t0 is None else time.ticks_diff(t2, t0),
                rt.last_push if rt.pushes != n0 else None, None,
                gc.mem_free(), rt.refresh.overruns - ov0, rt.refresh.worst_us, rt.pushes,
                _tpf_wire.tidy_us)))
def _tpf_heap():
    gc.collect()
    return gc.mem_free()
'''


def say_nothing(m: str) -> None:
    pass


# --- the scenes ---------------------------------------------------------------------------

def _total(display: dict[str, Any]) -> float:
    return round(display["positions"] * display["dx_um"] / 1000.0, 6)


def shipped_scenes() -> list[tuple[str, dict[str, Any]]]:
    from texelpad import scenes
    d = Path(scenes.__file__).resolve().parent       # texelpad/scenes/*.json
    out = []
    for p in sorted(d.glob("*.json")):
        sc = json.loads(p.read_text())
        out.append(("shipped " + p.stem, {"regions": sc["regions"]}))
    return out


def study_scenes(display: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """What the lab pushes: the nine free-exploration trials (each reference
    left, the sliders' start texture right), then the first question's
    scenes of every other shipped study config (the mapping's: its sliders'
    start; the paper's quantization test, which takes the participant's own
    matches, with the trained rater's standing in for them)."""
    from texel.gen.params import PITCH_DB_MAX
    from texelpad.study import configs, protocols, questions, rater, scenes as S
    out = []
    every = configs.available()
    for name, c in sorted(every.items()):
        if "error" in c:
            continue
        config = dict(c["config"])
        if c["protocol"] == "quant" and not config.get("matches"):
            config["matches"] = {r: dict(m, pitch_db=min(PITCH_DB_MAX, m["pitch_db"]))
                                 for r, m in rater.data()["matches"].items()}   # (white: 20 dB)
        header = {"protocol": c["protocol"], "config": config, "seed": 1}
        st = protocols.start(c["protocol"], config, 1)
        if c["protocol"] == "mapping":
            sc, _ = questions.slider_scene(st, header, display, *st.config.start, 0)
            out.append(("%s trial 1 sliders' start" % name, sc))
            continue
        if c["protocol"] == "free":
            v = S.texture_format(c["config"])
            p0, s0 = c["config"]["start"]
            for k, ref in enumerate(c["config"]["references"]):
                tex = st.texture(p0, s0, k, v)
                out.append(("%s trial %s" % (name, ref),
                            S.split({"kind": "reference", "name": ref}, tex, display)))
            continue
        q = questions.ask(c["protocol"], st, header, display)
        for k, sc in enumerate(q.options):
            out.append(("%s option %d" % (name, k + 1), sc))
    return out


def regions16(display: dict[str, Any], seed: int) -> dict[str, Any]:
    from texelpad.bench.link import regions16 as r16
    return r16(display, 2, seed)


def reference_scenes(display: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    from texel.gen import reference
    names = list(reference.STUDY_NAMES)
    return [("full-screen reference %s" % n,
             {"regions": [{"start_mm": 0, "end_mm": _total(display),
                           "texture": {"kind": "reference", "name": n}}]}) for n in names]


def brush_scene(display: dict[str, Any], seed: int = 1) -> dict[str, Any]:
    from texelpad.brush import document
    return {"regions": [document.region(document.design("pink", 0.05), seed, 0,
                                         _total(display))]}


def scene_list(display: dict[str, Any]) -> list[tuple[str, str, dict[str, Any]]]:
    """(category, name, scene): the mixed scenes the run cycles through."""
    out = [("scene", n, s) for n, s in shipped_scenes() + study_scenes(display)]
    out += [("regions16", "16 texel regions seed %d" % k, regions16(display, 200 + k))
            for k in range(2)]
    out += [("reference", n, s) for n, s in reference_scenes(display)]
    out += [("brush", "full-screen brush seed %d" % k, brush_scene(display, k + 1))
            for k in range(2)]
    # interleaved so that a quick run and the first pushes see every category
    # (the first push after boot: a free-exploration trial, what the lab pushes first)
    free = [x for x in out if x[1].startswith("free")]
    first = free[:1] + [next(x for x in out if x[0] == c) for c in ("regions16", "reference",
                                                                    "brush")]
    return first + [x for x in out if x not in first]


# --- on the board -------------------------------------------------------------------------

def _request(b: Any, scene: dict[str, Any]) -> dict[str, Any]:
    """One push through the wrapper: the board's figures (module docstring)."""
    from texelpad.link import protocol
    from texelpad.link.board import host_check
    from texelpad.link.transport import LinkError
    scene = host_check(scene)
    plain, uploads = protocol.split_uploads(scene)
    if uploads:                          # the data goes first, as Board.push sends it
        try:
            b._upload([u for _, u in uploads], None)
        except (LinkError, ValueError) as e:
            return {"refused": "upload: %s" % (str(e)[:300],)}
    slots = {i: k for k, (i, _) in enumerate(uploads)}
    try:
        if b.stands:
            # as Board.push sends it on an RP2040: a frame to texel.wire.stand(), timed
            # from when the board has read its last byte (texel.wire.read_us); the
            # figures are read by a command after it (which ends the reader: the next
            # push starts it again before its frame, outside the figures)
            head, data = protocol.staged_frame("pushed", [plain], 0, slots)
            b.link.exec("_tpf_pre()")
            try:
                reply = b.link.eval_frame(head, data, timeout=600)
            except LinkError as e:
                reply = ("err", "link: %s" % e)
            out = b.link.exec("_tpf_post()", timeout=600).strip().splitlines()
            request_bytes = len(head) + len(data)
        else:
            code = protocol.staged_call(protocol.WIRE, "pushed", [plain], 0, slots)
            out = b.link.exec("_tpf_req(%r)" % code, timeout=600).strip().splitlines()
            reply = ast.literal_eval(out[-2]) if len(out) > 1 else None
            request_bytes = len(code)
        (compile_us, entry_us, answer_us, lp, err, free, overruns, worst_us,
         pushes, tidy_us) = ast.literal_eval(out[-1])
    except (LinkError, ValueError, SyntaxError, IndexError) as e:
        return {"refused": "link: %s" % (str(e)[:300],)}
    r: dict[str, Any] = {"compile_us": compile_us, "answer_us": answer_us, "mem_free": free,
                         "tidy_us": tidy_us,
                         "overruns": overruns, "worst_us": worst_us, "pushes": pushes,
                         "request_bytes": request_bytes}
    if err or not (isinstance(reply, tuple) and reply and reply[0] == "ok") or lp is None:
        r["refused"] = err or (reply[1] if isinstance(reply, tuple) else repr(out[-2:]))[:300]
        return r
    r.update({"entry_us": entry_us, "validate_us": lp["validate_us"], "build_us": lp["build_us"],
              "swap_us": lp["swap_us"], "scene_bytes": lp.get("scene_bytes"),
              "playing_us": entry_us + lp["validate_us"] + lp["build_us"] + lp["swap_us"]})
    r["parse_us"] = entry_us - compile_us
    return r


# A user's script, as docs/device-api.md writes one: the texture without "v"
# (format 2 since 0.2; "v": 1 is the lab's float generator, timed for contrast).
# The board's clock around the call; the script is compiled by the raw REPL
# before it runs, as mpremote exec does.
USER_SCRIPT = """import time, texel.app
t0 = time.ticks_us()
texel.app.push({"regions": [{"start_mm": 0, "end_mm": %r, "texture": %r}]})
print(time.ticks_diff(time.ticks_us(), t0))"""


def _user_pushes(b: Any, display: dict[str, Any], say: Progress) -> dict[str, Any]:
    """texel.app.push of a full-screen texel texture written as a user writes
    it (no "v"), USER_PUSHES seeds; and with "v": 1 (twice) for contrast.
    Microseconds from the call to its return on the board's clock."""
    out: dict[str, Any] = {}
    for label, extra, n in (("no_v", {}, USER_PUSHES), ("v1", {"v": 1}, 2)):
        us = []
        for k in range(n):
            tex = dict({"kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9,
                        "seed": 100 + k}, **extra)
            us.append(int(b.link.eval(USER_SCRIPT % (_total(display), tex), timeout=120)))
        out[label] = us
        say("user's push, full-screen texel %s: %s us" % (
            "without \"v\"" if not extra else "with \"v\": 1", us))
    st = b.status()
    out["format_played"] = [r.get("v") for r in st["scene"]["regions"]]
    return out


def _irq_costs(b: Any, display: dict[str, Any], reps: int, say: Progress) -> dict[str, Any]:
    """Refresh cost incl. IRQ entry/exit for a full-screen scene of each
    region kind (and 16 texel regions), texelpad/bench/chip.py's method."""
    from texelpad.bench.chip import CPU_HZ, EXCEPTION_CYCLES
    from texelpad.link.transport import BoardError
    total = _total(display)
    kinds = [
        ("constant", {"regions": [{"start_mm": 0, "end_mm": total,
                                   "texture": {"kind": "constant", "level": 0.5}}]}),
        ("reference (flash map)", reference_scenes(display)[2][1]),
        ("texel plan (format 2)", {"regions": [{"start_mm": 0, "end_mm": total, "texture": {
            "kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "v": 2}}]}),
        ("brush (RAM map)", brush_scene(display, 3)),
        # a few samples the refresh plays where they are (kinds/samples.py SMALL):
        # 4 values tiled (K_TILE), and the shipped gradient's 2 stretched (K_STRETCH)
        ("samples (4 tiled, in place)", {"regions": [{"start_mm": 0, "end_mm": total,
                                                      "texture": {
            "kind": "samples", "fit": "tile", "u16": [0, 65535, 30000, 9000]}}]}),
        ("samples (2 stretched, in place)", {"regions": [{"start_mm": 0, "end_mm": total,
                                                          "texture": {
            "kind": "samples", "fit": "stretch", "u16": [0, 65535]}}]}),
        # 1,024 values tiled (more than SMALL): a 38,400-byte map built in RAM (as a brush's)
        ("samples (1,024 tiled, RAM map)", {"regions": [{"start_mm": 0, "end_mm": total,
                                                         "texture": {
            "kind": "samples", "fit": "tile",
            "u16": [(i * 2654435761) & 0xFFFF for i in range(1024)]}}]}),
        # a full-screen upload: played from its 1 KB chunks (scene.K_CHUNK)
        ("samples (19,200 uploaded, chunks)", {"regions": [{"start_mm": 0, "end_mm": total,
                                                            "texture": {
            "kind": "samples", "fit": "tile",
            "u16": [(i * 2654435761) & 0xFFFF for i in range(display["positions"])]}}]}),
        ("16 texel regions", regions16(display, 300)),
    ]
    out = {}
    for name, sc in kinds:
        r = _request(b, sc)
        if "refused" in r:
            out[name] = {"refused": r["refused"]}
            say("refresh, %s: refused (%s)" % (name, r["refused"][:120]))
            continue
        try:
            rows = b.link.eval("print(repr(_tpb_irq_cost(%d, %d, %d)))" % (IRQ_SPIN, reps, 40),
                               timeout=600)
        except BoardError as e:
            # (a stock Pico's heap: a MemoryError in the measuring loop's own
            # allocations) recorded as that kind's refusal; the other kinds go on. A
            # link that times out or is lost ends the run as before
            out[name] = {"refused": "measuring: %s" % (str(e)[:300],)}
            say("refresh, %s: not measured (%s)" % (name, str(e)[:120]))
            continue
        us = [(on - off) / n for on, off, n, _pos in rows if n > 0]
        out[name] = {"median_us": statistics.median(us), "max_us": max(us),
                     "cycles": statistics.median(us) * CPU_HZ / 1e6,
                     "positions": [pos for *_x, pos in rows], "windows": len(us)}
        say("refresh, %s: median %.2f us (max %.2f)" % (name, out[name]["median_us"],
                                                        out[name]["max_us"]))
    worst = max((v["max_us"] for v in out.values() if "max_us" in v), default=None)
    return {"kinds": out, "worst_us": worst, "exception_cycles_not_counted": EXCEPTION_CYCLES,
            "worst_us_with_exception": None if worst is None
            else worst + EXCEPTION_CYCLES / (CPU_HZ / 1e6)}


def run_board(firmware: str | None, pushes: int, scenes: int | None, irq_reps: int,
              say: Progress) -> dict[str, Any]:
    """The sequence of the module docstring on one emulated Pico: booted from
    `firmware` (a .uf2), or with None the stock path (stock MicroPython +
    texelpad deploy + start, as open_emulated)."""
    from texelpad.link.board import connect
    from texelpad.sim.emulated import EmulatedPico, finger_js, why_not
    from texelpad.sim.virtual import stop_on_signals
    from texelpad.bench.engines import DEVICE_SCRIPTS
    why = why_not()
    if why:
        raise RuntimeError(why)
    label = "firmware" if firmware else "stock"
    res: dict[str, Any] = {"path": label}
    t_wall = time.monotonic()
    with stop_on_signals(), EmulatedPico(firmware=firmware,
                                         extra_args=("--adc-js", finger_js("sweep"))) as emu:
        say("%s: booting the emulated Pico" % label)
        emu.start()
        if not firmware:
            from texelpad.deploy.install import deploy
            with connect(emu.port, check=False, import_image=False, timeout=120) as b:
                deploy(b, progress=lambda m: None)
            with connect(emu.port, timeout=120) as b:
                b.start(BOARD)
        with connect(emu.port, timeout=120) as b:
            st = b.status()
            if not st.get("running"):
                raise RuntimeError("%s: texelpad is not playing after boot: %r" % (label, st))
            display = st["display"]
            res["firmware"] = st["firmware"]
            res["boot_scene"] = st.get("scene")
            res["boot_last_push"] = st.get("last_push")
            b.link.exec(DEVICE_CODE, timeout=60)
            b.link.exec((DEVICE_SCRIPTS / "rp2_chip_bench.py").read_text(), timeout=60)
            b.link.eval("print(repr(_tpb_snap(True)))")
            allsc = scene_list(display)
            if scenes is not None:
                allsc = allsc[:scenes]
            res["scenes"] = len(allsc)
            # 1 + 2: the first push after boot, then the mixed run
            rows = []
            for i in range(pushes):
                cat, name, sc = allsc[i % len(allsc)]
                r = _request(b, sc)
                r.update({"i": i, "category": cat, "name": name})
                rows.append(r)
                if "refused" in r:
                    say("%s push %d (%s): REFUSED %s" % (label, i + 1, name, r["refused"]))
                elif (i + 1) % 10 == 0 or i < 1:
                    say("%s push %d/%d (%s): playing %.1f ms, answers %.1f ms, free %d"
                        % (label, i + 1, pushes, name, r["playing_us"] / 1e3,
                           r["answer_us"] / 1e3, r["mem_free"]))
            res["rows"] = rows
            snap = b.link.eval("print(repr(_tpb_snap()))")
            res["run_overruns"] = snap[2]
            res["run_worst_refresh_us"] = snap[3]
            res["run_faults"] = snap[4]
            # 2b: a push as a user scripts it (mpremote exec / Thonny): one
            # texel.app.push of a full-screen texel without "v", call -> return
            res["user_push"] = _user_pushes(b, display, say)
            # 3: the refresh per region kind
            res["refresh"] = _irq_costs(b, display, irq_reps, say)
            # 4: the heap, playing the power-up scene, then before texelpad starts
            res.update(_heap_figures(b, label, say))
    res["wall_s"] = time.monotonic() - t_wall
    return res


def _heap_figures(b: Any, label: str, say: Progress) -> dict[str, Any]:
    """run_board's step 4: the heap playing the power-up scene (started
    again), then after a soft reset, bare and with texel.app imported."""
    res: dict[str, Any] = {}
    try:
        b.start(BOARD)
    except Exception as e:      # (LinkError, DeviceError: the board's words)
        # a stock Pico after the run: every kind's code and the bench's
        # helpers (their refresh IRQ holds the last scene) in its heap. The
        # error is a figure; the heap one then comes after a soft reset
        res["start_error"] = "%s: %s" % (type(e).__name__, str(e)[:300])
        say("%s: start after the run failed: %s" % (label, res["start_error"]))
        b.link.soft_reset(timeout=120)
        b.start(BOARD)
        b.link.exec(DEVICE_CODE, timeout=60)
    res["heap_free_playing_default"] = b.link.eval("print(_tpf_heap())")
    b.stop()
    b.link.soft_reset(timeout=120)
    res["heap_free_bare"] = b.link.eval("import gc\ngc.collect()\nprint(gc.mem_free())")
    res["heap_free_after_import"] = b.link.eval(
        "import texel.app, gc\ngc.collect()\nprint(gc.mem_free())")
    return res


# --- the profile of a push ----------------------------------------------------------------

def profile_push(uf2: str, scene: dict[str, Any], elf: str | None,
                 say: Progress) -> dict[str, Any] | None:
    """rp2emu's script mode with --profile: the board pushes `scene` (texel.app
    playing since boot) and the PC histogram is folded onto the .elf's
    function symbols. None when it cannot run."""
    from texelpad.link import protocol
    from texelpad.sim.emulated import rp2emu_dir
    from texelpad.firmware import romfs
    nm = shutil.which("arm-none-eabi-nm")
    d = rp2emu_dir()
    if not (nm and elf and os.path.isfile(elf) and d):
        return None
    text = protocol.scene_text(scene)
    script = ("import json, texel.app\n_s = json.loads(%r)\ntexel.app.push(_s)\n" % text)
    with tempfile.TemporaryDirectory(prefix="texelpad-prof-") as tmp:
        sp, pp = Path(tmp) / "push.py", Path(tmp) / "prof.json"
        sp.write_text(script)
        # warm-up: the script mode counts from the script's start (the compile
        # of this script is in the histogram too; the push dominates it)
        p = subprocess.run([str(d / "run.sh"), "--firmware", uf2, "--profile", str(pp),
                            "--timeout", "600", str(sp)], capture_output=True, text=True,
                           timeout=900)
        if p.returncode != 0 or not pp.is_file():
            say("profile: rp2emu exited %d: %s" % (p.returncode, (p.stdout + p.stderr)[-300:]))
            return None
        hist = json.loads(pp.read_text())
    syms = []
    out = subprocess.run([nm, "-n", "-S", "--defined-only", elf], capture_output=True,
                         text=True).stdout
    for line in out.splitlines():
        f = line.split()
        if len(f) >= 4 and f[2] in "tTwW":
            syms.append((int(f[0], 16), int(f[1], 16), f[3]))
    syms.sort()
    starts = [s[0] for s in syms]
    by: dict[str, float] = {}
    total = 0.0
    for pc, cyc in hist:
        total += cyc
        if pc < 0:
            by["(asleep: WFI/WFE)"] = by.get("(asleep: WFI/WFE)", 0) + cyc
            continue
        k = bisect.bisect_right(starts, pc & ~1) - 1
        if k >= 0 and pc < syms[k][0] + max(syms[k][1], 2):
            name = syms[k][2]
        elif pc >= 0x20000000:
            name = "(RAM: native/viper code of texelpad)"
        elif pc >= romfs.XIP_BASE + 0xA0000:
            name = "(flash: ROMFS)"
        else:
            name = "(unknown)"
        by[name] = by.get(name, 0) + cyc
    top = sorted(by.items(), key=lambda kv: -kv[1])[:15]
    return {"total_cycles": total, "total_ms": total / 125e3,
            "top": [{"symbol": s, "cycles": c, "pct": 100.0 * c / total if total else 0.0}
                    for s, c in top]}


# --- figures ------------------------------------------------------------------------------

def _ms(us: float | None) -> float | None:
    return None if us is None else us / 1e3


def summarize(res: dict[str, Any]) -> dict[str, Any]:
    rows = res["rows"]
    ok = [r for r in rows if "refused" not in r]

    def cat(c: str, key: str, fn: Callable = max) -> float | None:
        v = [r[key] for r in ok if r["category"] == c]
        return _ms(fn(v)) if v else None

    def worst(c: str) -> str | None:
        v = [r for r in ok if r["category"] == c]
        return max(v, key=lambda r: r["playing_us"])["name"] if v else None

    mem = [r["mem_free"] for r in rows if r.get("mem_free") is not None]
    first = rows[0] if rows else {}
    f = {
        "scene_to_playing_ms": cat("scene", "playing_us"),
        "scene_to_playing_ms_median": cat("scene", "playing_us", statistics.median),
        "scene_to_playing_worst": worst("scene"),
        "scene_answers_ms": cat("scene", "answer_us"),
        "scene_answers_ms_median": cat("scene", "answer_us", statistics.median),
        "tidy_after_answer_ms": _ms(max((r.get("tidy_us") or 0) for r in ok)) if ok else None,
        "tidy_after_answer_ms_median": (_ms(statistics.median(r.get("tidy_us") or 0 for r in ok))
                                        if ok else None),
        "regions16_to_playing_ms": cat("regions16", "playing_us"),
        "regions16_answers_ms": cat("regions16", "answer_us"),
        "reference_to_playing_ms": cat("reference", "playing_us"),
        "reference_to_playing_worst": worst("reference"),
        "reference_answers_ms": cat("reference", "answer_us"),
        "brush_to_playing_ms": cat("brush", "playing_us"),
        "brush_answers_ms": cat("brush", "answer_us"),
        # its scene plays once the part under the finger is painted (texel.app
        # PAINT_NEAR_FINGER); the rest is painted after the answer (tidy_us, with the
        # collection): the map whole by then
        "brush_painted_ms": _ms(max(r["playing_us"] + (r.get("tidy_us") or 0) for r in ok
                                    if r["category"] == "brush"))
        if any(r["category"] == "brush" for r in ok) else None,
        "first_push_to_playing_ms": _ms(first.get("playing_us")),
        "first_push_answers_ms": _ms(first.get("answer_us")),
        "first_push_scene": first.get("name"),
        "refresh_us": res["refresh"]["worst_us"],
        "refresh_us_with_exception": res["refresh"]["worst_us_with_exception"],
        "overruns": res["run_overruns"],
        "worst_refresh_body_us": res["run_worst_refresh_us"],
        "heap_free_playing_bytes": min(mem) if mem else None,
        "heap_free_playing_default_bytes": res.get("heap_free_playing_default"),
        "start_after_run_error": res.get("start_error"),
        "heap_free_bare_bytes": res["heap_free_bare"],
        "heap_free_after_import_bytes": res["heap_free_after_import"],
        "pushes": len(rows), "refused": len(rows) - len(ok),
        "refusals": [(r["name"], r["refused"]) for r in rows if "refused" in r],
        "mem_free_slope_per_push": slope_per_push(mem),
        "user_push_ms": _ms(max(res["user_push"]["no_v"])) if res.get("user_push") else None,
        "user_push_ms_median": _ms(statistics.median(res["user_push"]["no_v"]))
        if res.get("user_push") else None,
        "user_push_v1_ms": _ms(max(res["user_push"]["v1"])) if res.get("user_push") else None,
        "mem_free_first": mem[0] if mem else None, "mem_free_last": mem[-1] if mem else None,
    }
    return f


def _met(key: str, v: Any) -> str:
    g = GOALS.get(key)
    if g is None or v is None:
        return ""
    good = v >= g if key == "heap_free_playing_bytes" else v <= g
    return "met" if good else "NOT met"


ROWS = [  # (key, label, unit); the goal and its verdict from GOALS
    ("scene_to_playing_ms", "shipped + study scenes: last byte -> playing (max)", "ms"),
    ("scene_answers_ms", "shipped + study scenes: board answers (max)", "ms"),
    ("regions16_to_playing_ms", "16 texel regions: -> playing (max)", "ms"),
    ("reference_to_playing_ms", "full-screen reference: -> playing (max of 9)", "ms"),
    ("brush_to_playing_ms", "full-screen brush: -> playing under the finger (max)", "ms"),
    ("first_push_answers_ms", "first push after boot: answers", "ms"),
    ("refresh_us", "one refresh incl. IRQ, worst region kind (stock: <= 10)", "us"),
    ("overruns", "refresh overruns while pushing", ""),
    ("heap_free_playing_bytes", "heap free while playing (min over the pushes)", "B"),
    ("refused", "pushes refused", ""),
    ("mem_free_slope_per_push", "free memory trend", "B/push"),
    ("user_push_ms", "app.push, full-screen texel without \"v\" (max of %d)" % USER_PUSHES, "ms"),
]


def _goal(key: str) -> str:
    g = GOALS.get(key)
    if g is None:
        return "flat" if key == "mem_free_slope_per_push" else ""
    if key == "heap_free_playing_bytes":
        return ">= " + format(int(g), ",")
    return "<= %g" % g if g else "0"


def _fmt(v: Any, unit: str) -> str:
    if v is None:
        return "-"
    if unit == "B":
        return format(int(v), ",")
    if unit in ("ms", "us"):
        return "%.2f" % v
    if unit == "B/push":
        return "%+.1f" % v
    return str(v)


# the table's rows below the goals: (key, label, unit)
EXTRA_ROWS = [("scene_to_playing_ms_median", "  scenes: -> playing, median", "ms"),
              ("scene_answers_ms_median", "  scenes: answers, median", "ms"),
              ("tidy_after_answer_ms", "  after the answer: the old scene's collection (a brush:"
               " its painting's rest too), max", "ms"),
              ("tidy_after_answer_ms_median", "  after the answer: the collection, median", "ms"),
              ("regions16_answers_ms", "  16 texel regions: answers (max)", "ms"),
              ("reference_answers_ms", "  full-screen reference: answers (max)", "ms"),
              ("brush_answers_ms", "  full-screen brush: answers (max)", "ms"),
              ("brush_painted_ms", "  full-screen brush: painted whole (+ the collection), max",
               "ms"),
              ("first_push_to_playing_ms", "  first push after boot: -> playing", "ms"),
              ("refresh_us_with_exception", "  refresh + 30 exception cycles not emulated", "us"),
              ("worst_refresh_body_us", "  refresh body worst (its own clock) while pushing",
               "us"),
              ("user_push_ms_median", "  app.push without \"v\": call -> return, median", "ms"),
              ("user_push_v1_ms", "  app.push with \"v\": 1 (the lab's float plan), max of 2",
               "ms"),
              ("heap_free_playing_default_bytes", "heap free playing the power-up scene", "B"),
              ("heap_free_after_import_bytes", "heap free, texel.app imported, not playing", "B"),
              ("heap_free_bare_bytes", "heap free at boot before texelpad starts", "B")]


def table(out: dict[str, Any]) -> str:
    fw, stock = out["firmware"]["figures"], (out.get("stock") or {}).get("figures")
    lines = ["texelpad firmware bench (issues 19 and 32): the emulated Pico (rp2040js @ 125 MHz), every "
             "figure on the board's own clock (ticks_us)",
             "uf2 %s: firmware %s bytes, ROMFS %s bytes of %s" % (
                 out["uf2"], format(out["firmware_bytes"], ","), format(out["romfs_bytes"], ","),
                 format(out["romfs_capacity"], ",")),
             "%d pushes in a row of %d mixed scenes (first: %s)" % (
                 fw["pushes"], out["firmware"]["scenes"], fw["first_push_scene"]), ""]
    w = 58
    head = "%-*s %12s %12s %12s  %s" % (w, "", "firmware", "today*", "goal", "")
    lines.append(head)
    for key, label, unit in ROWS:
        goal = _goal(key)
        v = fw.get(key)
        t = stock.get(key) if stock else None
        verdict = _met(key, v) if key in GOALS else ""
        lines.append("%-*s %12s %12s %12s  %s" % (w, label + (" [%s]" % unit if unit else ""),
                                                  _fmt(v, unit), _fmt(t, unit), goal, verdict))
    for key, label, unit in EXTRA_ROWS:
        v = fw.get(key)
        t = stock.get(key) if stock else None
        lines.append("%-*s %12s %12s" % (w, label + " [%s]" % unit, _fmt(v, unit), _fmt(t, unit)))
    if out.get("stock_error"):
        lines.append("today's path failed: %s" % out["stock_error"][:300])
    for path, figs in (("firmware", fw), ("today's path", stock)):
        if figs and figs.get("start_after_run_error"):
            lines.append("%s: texelpad start after the run failed (the power-up scene's heap is"
                         " after a soft reset): %s" % (path, figs["start_after_run_error"]))
    lines.append("* today = stock MicroPython 1.28 + ulab + `texelpad deploy`, the same scenes on the "
                 "same emulator (--stock)%s" % (
                     "" if stock else ": failed (above)" if out.get("stock_error")
                     else ": not run (pass --stock)"))
    lines.append("")
    lines.append("refresh cost per region kind (median / max us over %d windows, finger sweeping):"
                 % IRQ_REPS)
    for path in ("firmware", "stock"):
        if not out.get(path):
            continue
        ks = out[path]["refresh"]["kinds"]
        lines.append("  %-8s " % path + "; ".join(
            "%s %s" % (k, "REFUSED" if "refused" in v else "%.2f/%.2f" % (v["median_us"],
                                                                        v["max_us"]))
            for k, v in ks.items()))
    lines.append("")
    lines.append("per category (firmware), ms: to playing = compile + parse + validate + build + "
                 "swap (max-playing push)")
    for c in ("scene", "regions16", "reference", "brush"):
        rs = [r for r in out["firmware"]["rows"] if r["category"] == c and "refused" not in r]
        if not rs:
            continue
        r = max(rs, key=lambda r: r["playing_us"])
        lines.append("  %-10s %-40s %6.2f = %.2f + %.2f + %.2f + %.2f + %.2f; answers %.2f; "
                     "JSON request %d B" % (
                         c, r["name"][:40], r["playing_us"] / 1e3, r["compile_us"] / 1e3,
                         r["parse_us"] / 1e3, r["validate_us"] / 1e3, r["build_us"] / 1e3,
                         r["swap_us"] / 1e3, r["answer_us"] / 1e3, r["request_bytes"]))
    if fw["refusals"]:
        lines.append("REFUSED: " + "; ".join("%s: %s" % x for x in fw["refusals"][:10]))
    if out.get("profile"):
        p = out["profile"]
        lines.append("")
        lines.append("where the cycles go, %s (rp2emu --profile, script mode, %.1f ms incl. the "
                     "script's compile; symbols of %s):" % (p["scene"], p["total_ms"],
                                                            os.path.basename(out["elf"] or "")))
        for t in p["top"][:12]:
            lines.append("  %5.1f %%  %s" % (t["pct"], t["symbol"]))
    if out.get("notes"):
        lines.append("")
        lines += ["note: " + n for n in out["notes"]]
    lines.append("wall time %.0f s" % out["wall_s"])
    return "\n".join(lines)


def notes(out: dict[str, Any]) -> list[str]:
    fw = out["firmware"]["figures"]
    n = []
    for key, label, unit in ROWS:
        if key in GOALS and _met(key, fw.get(key)) == "NOT met":
            n.append("%s: %s %s (goal %s)" % (label, _fmt(fw.get(key), unit), unit, _goal(key)))
    return n


# --- the run ------------------------------------------------------------------------------

def uf2_sizes(uf2: str) -> dict[str, int]:
    from texelpad.firmware import romfs
    from texelpad.sim.emulated import FS_OFFSET
    blocks = romfs.read_uf2(Path(uf2).read_bytes())
    low = sum(len(p) for a, p, _ in blocks if a - romfs.XIP_BASE < FS_OFFSET)
    high = b"".join(p for a, p, _ in sorted(blocks) if a - romfs.XIP_BASE >= FS_OFFSET)
    rom = 0
    if high.startswith(romfs.ROMFS_HEADER):
        i, v = len(romfs.ROMFS_HEADER), 0
        while True:
            c = high[i]
            i += 1
            v = (v << 7) | (c & 0x7F)
            if not c & 0x80:
                break
        rom = i + v
    return {"firmware_bytes": low, "romfs_bytes": rom}


def default_uf2(say: Progress) -> str:
    """$TEXELPAD_FIRMWARE_UF2, or the firmware built for boards/pico into
    ~/.cache/texelpad/firmware-pico (built once: 2-3 min)."""
    env = os.environ.get("TEXELPAD_FIRMWARE_UF2")
    if env:
        return env
    out = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "texelpad" / \
        "firmware-pico"
    uf2 = out / "texelpad-pico.uf2"
    if not uf2.is_file():
        from texelpad.firmware.build import build_firmware, repo_boards_dir
        boards = repo_boards_dir()
        if boards is None:
            raise RuntimeError("no boards/ folder (a wheel): give --uf2")
        say("building the firmware into %s (2-3 min)" % out)
        build_firmware(boards / BOARD, out, progress=lambda m: say("firmware: " + m))
    return str(uf2)


# --- the smaller benches that run a script on the texelpad firmware -----------------------
# (bench/request_parts.py, bench/brush_parts.py)

def literal_on_firmware(name: str, uf2: str, codes: list[str]) -> dict[str, Any]:
    """Boot the emulated Pico on `uf2`, run each of `codes` in turn through
    the raw REPL, and return the literal the last one printed on its last
    line (a dict of figures). SystemExit, named `name`, where the emulator
    cannot run."""
    from texelpad.link.transport import Link
    from texelpad.sim.emulated import EmulatedPico, why_not
    why = why_not()
    if why:
        raise SystemExit("%s: %s" % (name, why))
    emu = EmulatedPico(firmware=uf2)
    emu.start()
    try:
        link = Link(emu.port, timeout=120)
        try:
            out = ""
            for code in codes:
                out = link.exec(code, timeout=600)
        finally:
            link.close()
    finally:
        emu.stop()
    res: dict[str, Any] = ast.literal_eval(out.strip().splitlines()[-1])
    res["uf2"] = uf2
    return res


def stderr_say(m: str) -> None:
    print(m, file=sys.stderr, flush=True)


def bench_uf2(arg: str | None) -> Path:
    """A bench's --uf2, or default_uf2 (its progress on stderr)."""
    return Path(arg or default_uf2(lambda m: stderr_say(".. " + m)))


def print_and_save(lines: list[str], res: dict[str, Any], json_path: str | None) -> int:
    """A bench's figures printed, and written as JSON where --json says."""
    print("\n".join(lines))
    if json_path:
        Path(json_path).write_text(json.dumps(res, indent=1) + "\n")
    return 0


def parts_main(argv: list[str] | None, prog: str, doc: str | None,
               measure: Callable[[str], dict[str, Any]],
               table: Callable[[dict[str, Any]], str]) -> int:
    """main() of such a bench: --uf2 (default: default_uf2) and --json; the
    figures measured on it, printed as `table` writes them."""
    ap = argparse.ArgumentParser(prog=prog, description=doc,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--uf2", help="the texelpad firmware (default: built once into ~/.cache, "
                    "as bench.firmware does)")
    ap.add_argument("--json", help="write the figures as JSON here")
    a = ap.parse_args(argv)
    uf2 = a.uf2 or default_uf2(lambda m: print(".. " + m, file=sys.stderr, flush=True))
    res = measure(uf2)
    print(table(res))
    if a.json:
        Path(a.json).write_text(json.dumps(res, indent=1))
    return 0


def run(uf2: str, stock: bool = False, quick: bool = False, pushes: int | None = None,
        profile: bool = True, progress: Progress | None = None) -> dict[str, Any]:
    say = progress or say_nothing
    t0 = time.monotonic()
    n = pushes if pushes is not None else (QUICK_PUSHES if quick else PUSHES)
    scenes = QUICK_SCENES if quick else None
    reps = 1 if quick else IRQ_REPS
    cap = None
    try:
        from texelpad.firmware.build import layout, repo_boards_dir
        bd = repo_boards_dir()
        cap = layout(bd / BOARD)[1] if bd else None
    except Exception:
        pass
    elf = str(Path(uf2).with_suffix(".elf"))
    out: dict[str, Any] = {"uf2": uf2, "elf": elf if os.path.isfile(elf) else None,
                           "goals": GOALS, "quick": quick, "romfs_capacity": cap or 0}
    out.update(uf2_sizes(uf2))
    fw = run_board(uf2, n, scenes, reps, say)
    fw["figures"] = summarize(fw)
    out["firmware"] = fw
    if stock:
        try:
            st = run_board(None, n, scenes, reps, say)
            st["figures"] = summarize(st)
            out["stock"] = st
        except Exception as e:          # today's path failing is a figure too: say it
            out["stock_error"] = "%s: %s" % (type(e).__name__, e)
            say("stock: %s" % out["stock_error"])
    out["notes"] = notes(out)
    if profile and not quick and out["elf"]:
        ok = [r for r in fw["rows"] if "refused" not in r]
        if ok:
            worst = max(ok, key=lambda r: r["playing_us"])
            from texelpad.link.board import host_check
            disp = {"positions": 19200, "dx_um": 5.3}
            sc = dict((name, s) for _c, name, s in scene_list(disp))[worst["name"]]
            say("profile: %s in script mode" % worst["name"])
            p = profile_push(uf2, host_check(sc), out["elf"], say)
            if p:
                p["scene"] = worst["name"]
                out["profile"] = p
    out["wall_s"] = time.monotonic() - t0
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.firmware",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--uf2", help="the texelpad firmware (.uf2; its .elf beside it for the "
                    "profile); default $TEXELPAD_FIRMWARE_UF2 or built once into ~/.cache")
    ap.add_argument("--json", help="write every figure as JSON here")
    ap.add_argument("--stock", action="store_true",
                    help="also measure today's path: stock MicroPython + texelpad deploy")
    ap.add_argument("--quick", action="store_true",
                    help="%d scenes, %d pushes, no profile (a smoke test)"
                    % (QUICK_SCENES, QUICK_PUSHES))
    ap.add_argument("--pushes", type=int, help="pushes in a row (default %d)" % PUSHES)
    ap.add_argument("--no-profile", action="store_true", help="skip the --profile run")
    a = ap.parse_args(argv)
    say = lambda m: print("..", m, file=sys.stderr, flush=True)     # noqa: E731
    uf2 = a.uf2 or default_uf2(say)
    out = run(uf2, stock=a.stock, quick=a.quick, pushes=a.pushes, profile=not a.no_profile,
              progress=say)
    print(table(out))
    if a.json:
        Path(a.json).write_text(json.dumps(out, indent=1, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
