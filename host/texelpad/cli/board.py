"""The commands that talk to a running board (or the virtual one): push, status,
monitor, ports. A bad flag or a request the board refuses is one line and
exit 2; a failure of the world (no board, port busy, link lost) is one line
and exit 1. A failed push never changes what the board plays."""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from typing import Any

from ..link.transport import DeviceError
from texel.runtime.kinds import label as kind_label, words as kind_words

from .connection import add_port_flags, connected_board, refused_scene, running_board
from .errors import EXIT_FAIL, EXIT_OK, CliError, to_stderr
from .parsing import positive_float
from .progress import ProgressBar
from .scene_files import read_scene_file
from .texel_flags import TEXEL_KEYS, add_texel_flags, device_error, render_params


def describe_scene(desc: dict[str, Any] | None) -> str:
    """status()['scene'] as lines a person reads."""
    if not desc:
        return "nothing (the board plays its idle level)"
    lines = ["  %s" % desc["name"]] if desc.get("name") else []
    for r in desc["regions"]:
        what = kind_words(r)            # the kind's own words (texel/runtime/kinds/)
        lines.append("  %7.2f .. %7.2f mm  %-62s %s, %d B" % (
            r["start_mm"], r["end_mm"], what, r["mode"], r["bytes"]))
    flash = sum(1 for r in desc["regions"] if r["mode"] == "flash")
    lines.append("  %d region%s, %d bytes of RAM on the board%s" % (
        desc["count"], "" if desc["count"] == 1 else "s", desc["bytes"],
        " (%d map%s played in place from flash: no RAM)" % (flash, "" if flash == 1 else "s")
        if flash else ""))
    return "\n".join(lines)


def add_push(p: argparse.ArgumentParser) -> None:
    p.description = ("Send a texel parameter set, a reference texture or a constant level (as "
                     "one full-display region) or a scene file to the board and print what "
                     "now plays. The scene is checked on the host with the board's own "
                     "validation, then on the board; if anything fails the board keeps "
                     "playing what it played.")
    g = p.add_argument_group("a texel texture over the whole display")
    add_texel_flags(g, tuple(k for k in TEXEL_KEYS if k != "length_samples"))
    p.add_argument("--scene", metavar="FILE.json",
                   help="a scene file: {\"regions\": [{\"start_mm\": .., \"end_mm\": .., "
                        "\"texture\": {...}}, ...]} (docs/runtime.md); - reads it from stdin; "
                        "a shipped scene's name (texelpad scenes) when no such file exists")
    p.add_argument("--reference", metavar="NAME",
                   help="a reference texture of the study over the whole display (2sin, 4sin, "
                        "square, pink, bp-4-0.5, ...)")
    p.add_argument("--constant", type=float, metavar="LEVEL",
                   help="a constant friction reduction 0 .. 1 over the whole display")
    p.add_argument("--board", metavar="NAME",
                   help="start texelpad with this board file first if it is not running "
                        "(e.g. pico, pyboard, virtual)")
    p.add_argument("--json", action="store_true", help="print the board's status as JSON")
    add_port_flags(p, "the one board plugged in")
    p.set_defaults(func=cmd_push)


# Sample uploads of at least this many bytes show a progress bar also when
# stderr is not a terminal (a log then gets one line); on a terminal always.
PROGRESS_MIN_BYTES = 16 * 1024


class _UploadProgress:
    """Board.push's progress(done, total) as a ProgressBar on stderr."""

    def __init__(self) -> None:
        self.bar: ProgressBar | None = None

    def __call__(self, done: int, total: int) -> None:
        if self.bar is None:
            if not (sys.stderr.isatty() or total >= PROGRESS_MIN_BYTES):
                return
            self.bar = ProgressBar(sys.stderr, label="push")
        self.bar(done, total, "samples upload")

    def end(self) -> None:
        if self.bar is not None:
            self.bar.end()


def _what_to_push(args: argparse.Namespace) -> tuple[str, Any]:
    """Exactly one of: texel flags, --scene, --reference, --constant, as
    (kind, its value); checked before the board is opened."""
    import math

    import texel
    params = render_params(args)
    given = [name for name, on in (("texel flags", bool(params)),
                                   ("--scene", args.scene is not None),
                                   ("--reference", args.reference is not None),
                                   ("--constant", args.constant is not None)) if on]
    if len(given) > 1:
        raise CliError("", "give one of texel flags, --scene, --reference or --constant, "
                       "not %s" % " and ".join(given))
    if not given:
        raise CliError("", "nothing to push: give --pitch-db and --irregularity-db, --scene, "
                       "--reference or --constant")
    if params:
        try:
            texel.validate(params)      # the generator's own words, as render says them
        except ValueError as e:
            raise device_error(e) from None
        return "texel", params
    if args.scene is not None:
        return "scene", read_scene_file(args.scene)
    if args.reference is not None:
        known = texel.reference_names()
        if args.reference not in known:
            raise CliError("--reference", "unknown reference texture %r (known: %s)"
                           % (args.reference[:40], ", ".join(known)))
        return "texture", {"kind": "reference", "name": args.reference}
    if not (math.isfinite(args.constant) and 0 <= args.constant <= 1):
        raise CliError("--constant", "must be a friction level 0 .. 1, got %s" % args.constant)
    return "texture", {"kind": "constant", "level": args.constant}


def _fitting_hint(b: Any) -> str:
    return ("--board NAME starts it; board files that fit this board: %s"
            % (", ".join(b.fitting()) or "none"))


def _refused(e: ValueError, kind: str, args: argparse.Namespace) -> CliError:
    """A refused push, naming the flag it came from."""
    if kind == "texture":
        return CliError("--reference" if args.reference is not None else "--constant",
                        ("the board refused it: " if isinstance(e, DeviceError) else "") + str(e))
    return refused_scene(e, kind == "texel")


# What `push --board` starts a board with, the instant before the push replaces it: one
# millimetre of constant 0 (valid on every display). The default split screen would be
# built only to be thrown away - 2 s and a 19 KB map on a CircuitPython Pico, whose
# fragmented heap then had no room for the pushed scene (tests/host/test_emulated_cpy.py).
QUIET_START = {"regions": [{"start_mm": 0, "end_mm": 1,
                            "texture": {"kind": "constant", "level": 0}}]}


def cmd_push(args: argparse.Namespace) -> int:
    from ..link.board import full_screen
    kind, what = _what_to_push(args)
    progress = _UploadProgress()
    # not running: --board starts it; a ValueError (LiteralError, DeviceError, the
    # host-side check: the board's own code) names the flag it came from (_refused)
    with running_board(args, _fitting_hint, start=args.board, start_scene=QUIET_START,
                       refused=lambda e: _refused(e, kind, args)) as (b, st):
        if args.board and args.board != st.get("board"):    # another board file runs
            raise CliError("--board", "%s already runs board file %r, not %r; the scene "
                           "was not sent (texelpad stop first to start another board file)"
                           % (b.port, st.get("board"), args.board))
        try:
            sent0 = b.link.sent
            t0 = time.perf_counter()
            if kind == "texel":
                st = b.push_texel(what)
            else:
                scene = what if kind == "scene" else full_screen(what, st["display"])
                st = b.push(scene, progress=progress)
            dt = time.perf_counter() - t0
        finally:
            progress.end()
        if args.json:
            print(json.dumps(st, indent=1, sort_keys=True))
        else:
            print("now playing on %s (%s):" % (b.port, st.get("board")))
            print(describe_scene(st.get("scene")))
            print("push: %.1f ms from the host call to the board's confirmation, %d bytes sent%s"
                  % (dt * 1e3, b.link.sent - sent0, board_push_time(st.get("last_push"))))
    return EXIT_OK


def board_push_time(lp: dict[str, Any] | None) -> str:
    """'; on the board's own clock: validate V + build B + swap S ms' from
    status()["last_push"] (texel/app.py _install), or '' when the board gave none.
    The host's wall time above it adds the link: the request's bytes, the
    board's answer, the host's own check."""
    if not isinstance(lp, dict) or not all(isinstance(lp.get(k), int)
                                           for k in ("validate_us", "build_us", "swap_us")):
        return ""
    v, b, s = lp["validate_us"], lp["build_us"], lp["swap_us"]
    return ("; on the board's own clock: validate %.1f + build %.1f + swap %.1f = %.1f ms%s"
            % (v / 1e3, b / 1e3, s / 1e3, (v + b + s) / 1e3,
               # texel/app.py MAKE_ROOM: the new scene did not fit beside the old one
               "; it did not fit beside the scene that played, so the display was idle for "
               "the %.1f ms of its build" % (b / 1e3) if lp.get("made_room") else ""))


def add_status(p: argparse.ArgumentParser) -> None:
    p.description = ("Print texel.app.status() of the board: the scene, refresh "
                                   "rate, worst refresh time, overruns, free memory, firmware.")
    p.add_argument("--json", action="store_true", help="print it as JSON")
    add_port_flags(p, "the one board plugged in")
    p.set_defaults(func=cmd_status)


def format_status(st: dict[str, Any]) -> str:
    fw = "%s, texel %s, protocol %s, ulab %s, viper %s" % (
        st.get("firmware"), st.get("texel"), st.get("protocol"), st.get("ulab") or "none",
        "yes" if st.get("viper") else "no")
    if not st.get("running"):
        return "texelpad is not running (%s); free memory %s bytes" % (fw, st.get("mem_free"))
    lines = ["board %s (%s), refresh %s at %s Hz: %s refreshes, measured %s Hz, worst %s us, "
             "%s overruns, %s faults" % (st["board"], st["port"], st["refresh"],
                                         st["refresh_hz"], st["refreshes"], st["rate_hz"],
                                         st["worst_us"], st["overruns"], st["faults"]),
             "carrier %s Hz (PWM top %s); finger at %s, amplitude %s, duty %s"
             % (st["carrier_hz"], st["pwm_top"],
                "lifted" if st["position"] < 0 else "%.2f mm" % (
                    st["position"] * st["display"]["dx_um"] / 1000),
                st["amplitude"], st["duty"]),
             "free memory %s bytes; %s" % (st.get("mem_free"), fw),
             "scene (%s pushes):" % st.get("pushes"), describe_scene(st.get("scene"))]
    if st.get("late") is not None:
        # CircuitPython's paced loop (docs/runtime.md, "CircuitPython: serve")
        lines.insert(1, "paced loop: %s refreshes started late; the refresh timed once in %s"
                     % (st["late"], st.get("timed_every", 1)))
    return "\n".join(lines)


STEPPED = ("the virtual board's time is stepped (texel.app.start('virtual') without "
           "realtime=True): no refresh runs unless texel.wire.advance(ms) runs it; start it in real "
           "time with app.start('virtual', realtime=True) (texelpad virtual and texelpad push "
           "--board virtual do)")


def _stepped(b: Any, st: dict[str, Any]) -> bool:
    """A running virtual board whose refresh does not advance by itself:
    started without realtime=True, it plays nothing when driven over its pty."""
    if not st.get("running") or st.get("port") != "virtual":
        return False
    time.sleep(0.1)                 # ~800 refreshes at 8,333 Hz in real time
    return b.status().get("refreshes") == st.get("refreshes")


def cmd_status(args: argparse.Namespace) -> int:
    with connected_board(args) as b:
        st = b.status()
        stepped = _stepped(b, st)
    if args.json:
        print(json.dumps(st, indent=1, sort_keys=True))
        if stepped:
            to_stderr("status: warning: " + STEPPED)
    else:
        print(format_status(st))
        if stepped:
            print("WARNING: " + STEPPED)
    return EXIT_OK


def add_stop(p: argparse.ArgumentParser) -> None:
    p.description = ("Safety: turn the carrier off now (texel.app.stop(): the refresh stops, "
                     "the carrier goes to its safe off state). Says what played; a board "
                     "already stopped is fine (exit 0). Works with an image older than this "
                     "host too. texelpad push --board NAME starts it again.")
    add_port_flags(p, "the one board plugged in")
    p.set_defaults(func=cmd_stop)


def scene_line(desc: dict[str, Any] | None) -> str:
    """status()['scene'] in a few words: its name, else its regions."""
    if not desc:
        return "nothing"
    if desc.get("name"):
        return repr(desc["name"])
    parts = []
    for r in desc["regions"]:
        parts.append(kind_label(r))
    more = len(parts) - 3
    return ", ".join(parts[:3]) + (" and %d more region%s" % (more, "s" * (more > 1))
                                   if more > 0 else "")


def cmd_stop(args: argparse.Namespace) -> int:
    # check=False: a safety command must work on an image older than this host
    # (texel.app.stop and status have been there since the first one)
    with connected_board(args, check=False) as b:
        if b.image is None:
            print("%s has no texelpad image: texelpad plays nothing there" % b.port)
            return EXIT_OK
        st = b.status()
        if not st.get("running"):
            print("texelpad is not running on %s: the carrier is already off" % b.port)
            return EXIT_OK
        b.stop()
        after = b.status()
    if after.get("running"):         # the board's stop() returned but the display runs
        raise CliError("", "%s still runs texelpad after stop(); unplug the board's power "
                       "stage" % b.port, EXIT_FAIL)
    print("stopped %s (board %s): it played %s; the carrier is off"
          % (b.port, st.get("board"), scene_line(st.get("scene"))))
    return EXIT_OK


def add_monitor(p: argparse.ArgumentParser) -> None:
    p.description = ("Stream (time, position, amplitude) samples that the board's "
                                   "refresh loop takes itself (it is not disturbed) until "
                                   "Ctrl-C or --seconds.")
    p.add_argument("--rate", type=int, default=125, metavar="HZ",
                   help="samples per second, 1 .. the board's refresh rate (default 125); "
                        "the board samples every (refresh rate // HZ)-th refresh")
    p.add_argument("--seconds", type=positive_float, metavar="S", help="stop after S seconds")
    p.add_argument("--csv", metavar="FILE", help="write t_us,position,position_mm,amplitude rows "
                   "(checked writable before the board is opened)")
    add_port_flags(p, "the one board plugged in")
    p.set_defaults(func=cmd_monitor)


def _bar(amp: int, width: int = 40) -> str:
    n = round(amp / 65535 * width)
    return "#" * n + "." * (width - n)


def _csv_error(path: str, e: OSError) -> CliError:
    return CliError("--csv", "cannot write %s: %s" % (path, e.strerror or e), EXIT_FAIL)


def cmd_monitor(args: argparse.Namespace) -> int:
    if not 1 <= args.rate <= 50000:
        raise CliError("--rate", "must be 1 .. the board's refresh rate (at most 50,000) "
                       "samples/s, got %d" % args.rate)
    out = None
    created = False
    if args.csv:
        created = not os.path.exists(args.csv)
        try:
            out = open(args.csv, "w", encoding="utf-8")
            out.write("t_us,position,position_mm,amplitude\n")
            out.flush()
        except OSError as e:
            if out:
                out.close()
            raise _csv_error(args.csv, e) from None
    n = 0
    b = None
    failed = True
    try:
        with running_board(args) as (b, st):
            hz = st["refresh_hz"]
            if args.rate > hz:
                raise CliError("--rate", "must be 1 .. %s samples/s, the refresh rate of %s "
                               "(one sample per refresh at most), got %d"
                               % (hz, b.port, args.rate))
            if _stepped(b, st):
                raise CliError("", "no samples would come: " + STEPPED, EXIT_FAIL)
            dx = st["display"]["dx_um"] / 1000.0
            if not out:
                print("%10s  %9s  %6s  amplitude" % ("t_ms", "mm", "amp"))
            samples = b.monitor(args.seconds, rate_hz=args.rate)
            try:
                for t, pos, amp in samples:
                    n += 1
                    mm = pos * dx if pos >= 0 else float("nan")
                    if out:
                        try:
                            out.write("%d,%d,%.4f,%d\n" % (t, pos, mm, amp))
                        except OSError as e:
                            raise _csv_error(args.csv, e) from None
                    else:
                        print("%10.1f  %9s  %6d  %s" % (t / 1000, "lifted" if pos < 0 else
                                                        "%.3f" % mm, amp, _bar(amp)),
                              flush=True)
            finally:
                samples.close()         # the stream off before the link closes
            actual = hz / b.divider if b.divider else 0
            if actual and abs(actual - args.rate) > 0.01 * args.rate:
                to_stderr("monitor: the board sampled every %srefresh of %s Hz: %.1f "
                          "samples/s, not %d" % ("%d%s " % (b.divider, _ordinal(b.divider))
                                                 if b.divider > 1 else "", hz, actual,
                                                 args.rate))
        failed = False
    except KeyboardInterrupt:
        failed = False
    finally:
        if out:
            try:
                out.close()
            except OSError as e:
                if not failed:
                    failed = True
                    raise _csv_error(args.csv, e) from None
            if failed and n == 0 and created:
                try:
                    os.unlink(args.csv)         # nothing but a header: leave no file behind
                except OSError:
                    pass
            elif not failed:
                to_stderr("monitor: %d samples written to %s" % (n, args.csv))
        lost = getattr(b, "lost", 0) if b is not None else 0
        if lost:
            to_stderr("monitor: warning: %s of %s samples lost: the board's 256-sample telemetry "
                      "ring was lapped between two reads (the link did not keep up with %d "
                      "samples/s; a lower --rate loses fewer)"
                      % (format(lost, ","), format(lost + n, ","), args.rate))
    return EXIT_OK


def _ordinal(k: int) -> str:
    return "th" if 10 <= k % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")


def add_ports(p: argparse.ArgumentParser) -> None:
    p.description = ("List serial ports whose USB vendor is a MicroPython or "
                                   "CircuitPython board maker (Raspberry Pi, MicroPython, "
                                   "Adafruit, ST), and the running texelpad virtual boards.")
    p.set_defaults(func=cmd_ports)


def cmd_ports(args: argparse.Namespace) -> int:
    from ..link.transport import ports
    from ..sim.virtual import running_boards
    found = ports()
    virtual = running_boards()
    if not found and not virtual:
        print("no boards found (texelpad virtual starts a virtual one)")
    for p in found:
        print("%-20s %-24s %s" % (p["port"], p["vendor"], p["description"]))
    for e in virtual:
        chip = e.get("chip")
        print("%-20s %-24s %s" % (e["port"], "emulated " + chip.upper() if chip else "virtual",
                                  "texelpad virtual%s (pid %s, flash %s)"
                                  % (" --chip " + chip if chip else "", e["pid"], e["flash"])))
    return EXIT_OK

