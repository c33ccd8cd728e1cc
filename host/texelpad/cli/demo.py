"""`texelpad demo`, the quick start's main job: play the study's split screen
on a board (the virtual one when no port is given), sweep a finger across
it, and draw one PNG of the map, its spectrum, the texel pitch histogram and
the amplitude the carrier actually played."""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np
import texel.app

from ..link.protocol import LiteralError
from ..link.transport import DeviceError, LinkError
from .connection import add_port_flags, link_failure, refused_scene
from .errors import EXIT_FAIL, EXIT_OK, CliError, to_stderr
from .files import check_output, write_output
from .parsing import positive_float
from .scene_files import read_scene_file

DEFAULT_SCENE = texel.app.DEFAULT_SCENE

# The simulated finger on the virtual board (ms, mm): rests lifted, touches
# down 2 mm in, sweeps to the far end at ~49 mm/s (a slow, deliberate swipe:
# about 40 telemetry samples per mm at 2 kHz), holds, lifts.
SWEEP: list[tuple[float, float | None]] = [(0, None), (100, 2.0), (2100, 99.76), (2200, 99.76),
                                           (2210, None), (2400, None)]
RATE_HZ = 2083          # telemetry every 4th refresh at 8,333 Hz: the 256-slot ring holds 123 ms
# The zoom's "what the plate plays" (hardware/README.md, "The envelope"): a plate's Q is
# measured per build (hardware/sweep.py); 20 is the README's example, and 100 mm/s a
# typical exploring swipe. Both are in the demo's --json report ("plate").
PLATE_Q = 20.0
SWIPE_MM_S = 100.0
POLL_S = 0.03           # drain the ring well inside that


def finger_truth(keyframes: list[tuple[float, float | None]], t0_us: int, dx_um: float,
                 t_us: np.ndarray) -> np.ndarray:
    """Where the scripted finger truly is (display index, -1 lifted) at board
    times t_us, for a script that started at t0_us: the virtual board's own
    rule (linear between keyframes, lifted from a None keyframe to the next,
    the last keyframe holds)."""
    kt = np.array([t * 1000.0 for t, _ in keyframes]) + t0_us
    kp: list[Any] = [None if p is None else p * 1000.0 / dx_um for _, p in keyframes]
    out = np.full(t_us.shape, -1.0)
    for i, t in enumerate(t_us):
        j = int(np.searchsorted(kt, t, side="right")) - 1
        if j < 0 or kp[j] is None:
            continue
        if j + 1 < len(kt) and kp[j + 1] is not None:
            a = (t - kt[j]) / (kt[j + 1] - kt[j])
            out[i] = kp[j] + a * (kp[j + 1] - kp[j])
        else:
            out[i] = kp[j]
    return np.rint(out).astype(np.int64)     # display indices, as the board's ADC sees them


def fitting_rate(board: Any, want_hz: int = RATE_HZ, reads: int = 5) -> tuple[int, float]:
    """(telemetry rate, board-time read interval in s): want_hz, or less when
    this link cannot read the 256-sample ring (TELEMETRY_SLOTS) before it laps.
    The interval is measured as collect() reads (full reads at want_hz, each
    followed by POLL_S) on the board's own clock: the newest sample's time
    stamp of one read to the next's. The emulated Pico takes ~0.2 s of wall
    time per read, longer than the ring lasts at 2,083 Hz (123 ms). The rate
    leaves the ring a 2x margin over the slowest read."""
    from texel.runtime.refresh import TELEMETRY_SLOTS
    newest = []
    board.stream(want_hz)
    try:
        for _ in range(reads):
            samples, _lost = board.telemetry()
            if samples:
                newest.append(samples[-1][0])
            time.sleep(POLL_S)
    finally:
        board.stream(0)
    # the time stamps wrap at 2^30 us (refresh.py _WRAP): a negative step is a wrap
    gaps = [((b - a) % (1 << 30)) / 1e6 for a, b in zip(newest, newest[1:])]
    worst = max(gaps) if gaps else 0.0
    if worst <= 0:
        return want_hz, worst
    return max(1, min(want_hz, int(TELEMETRY_SLOTS / (2 * worst)))), worst


def collect(board: Any, seconds: float, rate_hz: int = RATE_HZ) -> tuple[list, int]:
    """Telemetry for `seconds`: (samples, lost)."""
    samples = list(board.monitor(seconds, rate_hz=rate_hz, poll_s=POLL_S))
    return samples, board.lost


def run(port: str | None = None, out: str = "texelpad-demo.png", scene: dict | None = None,
        board_name: str | None = None, seconds: float = 6.0, flash: str | None = None,
        timeout: float = 10.0, progress: Callable[[str], None] = lambda m: None) -> dict[str, Any]:
    """The whole demo; returns its figures (and writes `out`)."""
    from ..link.board import connect
    from ..analysis.figures import demo_figure
    scene = DEFAULT_SCENE if scene is None else scene
    vb = None
    t_all = time.perf_counter()
    report: dict[str, Any] = {}
    try:
        if port is None:
            from ..sim.virtual import open_virtual
            progress("no --port: starting the virtual board (MicroPython unix port on a pty)")
            t0 = time.perf_counter()
            vb = open_virtual(flash, progress=progress)      # deployed, playing in real time
            report["deploy_s"] = time.perf_counter() - t0
            port = vb.port
        with connect(port, timeout=timeout) as b:
            st = b.status()
            if not st.get("running"):
                if not board_name:
                    raise LinkError("texelpad is not running on %s: say which board file to "
                                    "start (--board pico, pyboard, ...)" % port)
                progress("starting texelpad on %s (board %s)" % (port, board_name))
                b.start(board_name, None)
            progress("pushing the scene")
            sent0 = b.link.sent
            t0 = time.perf_counter()
            st = b.push(scene)
            report["push_ms"] = (time.perf_counter() - t0) * 1e3
            report["push_bytes"] = b.link.sent - sent0
            display = st["display"]
            truth = None
            if vb is not None:
                sweep_s = (SWEEP[-1][0]) / 1000.0
                progress("sweeping the simulated finger across the display (%.1f s)" % sweep_s)
                t0_us = b.finger(SWEEP)
                report["telemetry_hz"] = RATE_HZ
                samples, lost = collect(b, sweep_s + 0.1)
            else:
                rate, read_s = fitting_rate(b)
                report["telemetry_hz"] = rate
                if rate < RATE_HZ:
                    progress("telemetry at %d Hz, not %d: over this link a read comes every "
                             "%.0f ms of the board's own time, and the 256-sample ring must "
                             "outlast that twice" % (rate, RATE_HZ, read_s * 1e3))
                progress("swipe your finger across the plate now (%g s)" % seconds)
                samples, lost = collect(b, seconds, rate)
            tel = np.array(samples, dtype=np.int64).reshape(-1, 3)
            if vb is not None and len(tel):
                truth = np.column_stack([tel[:, 0], finger_truth(SWEEP, t0_us, display["dx_um"],
                                                                 tel[:, 0].astype(float))])
            st = b.status()
            canonical = b.scene_source()
            assert canonical is not None        # the scene pushed above plays
        progress("drawing %s" % out)
        plate = {"f0_hz": float(st["carrier_hz"]), "q": PLATE_Q, "speed_mm_s": SWIPE_MM_S}
        report["plate"] = plate
        figs = demo_figure(out, canonical, tel, display=display, truth=truth, plate=plate,
                           title="texelpad demo on %s (%s, %s refresh): %s"
                                 % (st["board"], st["firmware"], st["refresh"],
                                    _scene_title(canonical)))
        report.update(figs)
        report.update({"port": port, "board": st["board"], "dx_um": display["dx_um"],
                       "samples": int(len(tel)), "lost": int(lost), "refreshes": st["refreshes"],
                       "overruns": st["overruns"], "faults": st["faults"],
                       "scene_bytes": st["scene"]["bytes"], "out": str(out),
                       "total_s": time.perf_counter() - t_all})
        return report
    finally:
        if vb is not None:
            vb.stop()


def _scene_title(canonical: dict[str, Any]) -> str:
    parts = []
    for r in canonical["regions"]:
        t = r["texture"]
        if t["kind"] == "texel":
            parts.append("texel %g dB/%g dB seed %d" % (t["pitch_db"], t["irregularity_db"],
                                                        t["seed"]))
        elif t["kind"] == "reference":
            parts.append("reference %s" % t["name"])
        else:
            parts.append(t["kind"])
    return " | ".join(parts)


# --- the command -----------------------------------------------------------------

def add_demo(p: argparse.ArgumentParser) -> None:
    p.description = ("With no --port: start the virtual board (the device image under the "
                    "MicroPython unix port), deploy the image into it, play the study's split "
                    "screen (reference 4sin left, texel 6.3 dB / -12.9 dB / seed 7 right), "
                    "sweep a simulated finger across it and write one PNG: the map with the "
                    "amplitude the carrier played, a zoom, the spectra, the texel pitch "
                    "histogram against the pitch distribution, and amplitude and finger over "
                    "time. With --port the same on a real board, with your finger.")
    p.add_argument("--out", default="texelpad-demo.png", metavar="FILE.png",
                   help="the figure (default texelpad-demo.png)")
    p.add_argument("--scene", metavar="FILE.json", help="play this scene instead")
    p.add_argument("--board", metavar="NAME",
                   help="with --port: the board file to start if texelpad is not running")
    p.add_argument("--seconds", type=positive_float, default=6.0, metavar="S",
                   help="with --port: how long to record your swipe (default 6)")
    p.add_argument("--json", metavar="PATH", help="also write the figures here")
    add_port_flags(p, "the virtual board")
    p.set_defaults(func=cmd_demo)


def cmd_demo(args: argparse.Namespace) -> int:
    if not args.out.lower().endswith(".png"):
        raise CliError("--out", "the demo writes a PNG: give a FILE.png, not %r" % args.out)
    scene = read_scene_file(args.scene) if args.scene else None
    if scene is not None:
        from ..link.board import host_check
        try:                      # the board's own check, before starting anything
            host_check(scene)
        except ValueError as e:
            raise refused_scene(e, False) from None
    # both output files are checked before the board is started, not after
    check_output("--out", args.out, (".png",))
    if args.json:
        check_output("--json", args.json, (".json",))
    try:
        rep = run(args.port, args.out, scene, args.board, args.seconds,
                       timeout=args.timeout, progress=lambda m: to_stderr("demo: " + m))
    except (LiteralError, DeviceError) as e:
        raise refused_scene(e, False) from None
    except LinkError as e:
        raise link_failure(e) from None
    except OSError as e:                # the figure (its directory was checked: a full disk)
        raise CliError("--out", "cannot write %s: %s" % (args.out, e.strerror or e),
                       EXIT_FAIL) from None
    from ..analysis.figures import finger_words, played_words
    words = [w for w in (played_words(rep.get("amp_err_max"), rep.get("amp_mismatches", 0),
                                      rep.get("down", 0)),
                         finger_words(rep.get("pos_err_max"), rep["dx_um"])) if w]
    print("played on %s (%s): %d telemetry samples (%d lost), %d with the finger down%s"
          % (rep["port"], rep["board"], rep["samples"], rep["lost"], rep.get("down", 0),
             "".join("; " + w for w in words)))
    print("push %.1f ms, %d bytes on the wire (the original lab sent 76,800 bytes per change); "
          "scene holds %d bytes on the board; %d refreshes, %d overruns, %d faults"
          % (rep["push_ms"], rep["push_bytes"], rep["scene_bytes"], rep["refreshes"],
             rep["overruns"], rep["faults"]))
    if args.json:
        write_output("--json", args.json,
                     lambda: Path(args.json).write_text(json.dumps(rep, indent=1, default=float)))
    print("wrote %s" % args.out)
    return EXIT_OK

