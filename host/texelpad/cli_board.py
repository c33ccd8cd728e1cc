"""The `texelpad` subcommands that talk to a board (or to the virtual one):
demo, push, status, monitor, ports, virtual, deploy.

Same conventions as cli.py: a bad flag or a request the board refuses is one
line and exit 2; a failure of the world (no board, port busy, link lost) is
one line and exit 1. A failed push never changes what the board plays.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from .cli import (EXIT_FAIL, EXIT_OK, EXIT_USAGE, CliError, PARAM_FLAGS, _stderr,
                  positive_float, render_params)
from .link import DeviceError, LinkError, LiteralError


def _port_arg(p: argparse.ArgumentParser, help_none: str) -> None:
    p.add_argument("--port", metavar="PORT",
                   help="the board's serial port (/dev/ttyACM0, COM3, or a virtual board's "
                        "/dev/pts/N); default: %s" % help_none)
    p.add_argument("--timeout", type=positive_float, default=10.0, metavar="S",
                   help="seconds to wait for the board to answer (default 10)")


def _fail(e: LinkError) -> CliError:
    """A link/board error as a CliError: the board's refusal of what the user
    asked is a usage error (2), the rest a failure (1)."""
    if isinstance(e, DeviceError):
        return CliError("", "the board refused it: %s" % e, EXIT_USAGE)
    return CliError("", str(e), EXIT_FAIL)


def _connect(args: argparse.Namespace, check: bool = True) -> Any:
    from .board import connect
    try:
        return connect(args.port, timeout=args.timeout, check=check)
    except LinkError as e:
        raise _fail(e) from None


def describe_scene(desc: dict[str, Any] | None) -> str:
    """status()['scene'] as lines a person reads."""
    if not desc:
        return "nothing (the board plays its idle level)"
    lines = []
    for r in desc["regions"]:
        what = r["kind"]
        if what == "texel":
            what = "texel pitch %s dB, irregularity %s dB, seed %s" % (
                r["pitch_db"], r["irregularity_db"], r["seed"])
        elif what == "reference":
            what = "reference %s" % r["name"]
        elif what == "constant":
            what = "constant %.4f" % (r["amplitude"] / 65535)
        else:
            what = "samples (%d values, %s)" % (r["values"], r["fit"])
        lines.append("  %7.2f .. %7.2f mm  %-52s %s, %d B" % (
            r["start_mm"], r["end_mm"], what, r["mode"], r["bytes"]))
    lines.append("  %d region%s, %d bytes on the board" % (
        desc["count"], "" if desc["count"] == 1 else "s", desc["bytes"]))
    return "\n".join(lines)


# --- push ---------------------------------------------------------------------

def add_push(sub: Any) -> None:
    p = sub.add_parser(
        "push", help="play a texel texture (flags) or a scene (JSON file) on the board",
        description="Send a texel parameter set (as one full-display region) or a scene file "
                    "to the board and print what now plays. The scene is checked on the host "
                    "with the board's own validation, then on the board; if anything fails "
                    "the board keeps playing what it played.")
    g = p.add_argument_group("a texel texture over the whole display")
    g.add_argument("--pitch-db", type=float, metavar="DB", help="central pitch, -20 .. 19.747")
    g.add_argument("--irregularity-db", type=float, metavar="DB", help="irregularity, -30 .. 5")
    g.add_argument("--seed", type=int, metavar="N", help="random seed (default 0)")
    g.add_argument("--texel-samples", type=int, metavar="N", help="samples per texel (50)")
    g.add_argument("--quant-db", type=float, metavar="DB", help="pitch quantization grid (0)")
    g.add_argument("--gain", type=float, metavar="G", help="map scale 0 .. 1 (1)")
    g.add_argument("--band-limit-cpmm", type=float, metavar="F", help="clamp pitches to F c/mm")
    p.add_argument("--scene", metavar="FILE.json",
                   help="a scene file: {\"regions\": [{\"start_mm\": .., \"end_mm\": .., "
                        "\"texture\": {...}}, ...]} (docs/runtime.md)")
    p.add_argument("--board", metavar="NAME",
                   help="start texelpad with this board file first if it is not running "
                        "(e.g. pico, pyboard, virtual)")
    p.add_argument("--json", action="store_true", help="print the board's status as JSON")
    _port_arg(p, "the one board plugged in")
    p.set_defaults(func=cmd_push, length_samples=None)


def read_scene_file(path: str) -> dict[str, Any]:
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as e:
        raise CliError("--scene", "cannot read %s: %s" % (path, e.strerror or e)) from None
    except UnicodeDecodeError:
        raise CliError("--scene", "%s is not UTF-8 text" % path) from None
    try:
        scene = json.loads(text)
    except json.JSONDecodeError as e:
        raise CliError("--scene", "%s is not valid JSON: %s (line %d, column %d)"
                       % (path, e.msg, e.lineno, e.colno)) from None
    if not isinstance(scene, dict):
        raise CliError("--scene", "%s: a scene is a JSON object {\"regions\": [...]}, not a %s"
                       % (path, type(scene).__name__))
    return scene


def cmd_push(args: argparse.Namespace) -> int:
    params = render_params(args)
    if args.scene and params:
        raise CliError("--scene", "give either a scene file or texel flags, not both")
    if not args.scene and not params:
        raise CliError("", "nothing to push: give --pitch-db and --irregularity-db, or --scene")
    scene = read_scene_file(args.scene) if args.scene else None
    with _connect(args) as b:
        try:
            st = b.status()
            if not st.get("running"):
                if not args.board:
                    raise CliError("--board", "texelpad is not running on %s: say which board "
                                   "file to start it with (--board pico, --board virtual, ...)"
                                   % b.port)
                b.start(args.board)
            sent0 = b.link.sent
            t0 = time.perf_counter()
            st = b.push(scene) if scene is not None else b.push_texel(params)
            dt = time.perf_counter() - t0
        except (LiteralError, DeviceError) as e:
            raise _value_error(e, scene is None) from None
        except ValueError as e:                # the host-side check (the board's own code)
            raise _value_error(e, scene is None) from None
        except LinkError as e:
            raise _fail(e) from None
        if args.json:
            print(json.dumps(st, indent=1, sort_keys=True))
        else:
            print("now playing on %s (%s):" % (b.port, st.get("board")))
            print(describe_scene(st.get("scene")))
            print("push: %.1f ms from the host call to the board's confirmation, %d bytes sent"
                  % (dt * 1e3, b.link.sent - sent0))
    return EXIT_OK


def _value_error(e: Exception, from_flags: bool) -> CliError:
    """A refused parameter: name the flag when it came from one."""
    text = str(e)
    if from_flags:
        path, sep, rest = text.partition(": ")
        key = path.rsplit(".", 1)[-1]
        if sep and path.startswith("regions[0].texture.") and key in PARAM_FLAGS:
            return CliError(PARAM_FLAGS[key], rest)
        missing = "missing required key '"
        if path == "regions[0].texture" and rest.startswith(missing):
            key, _, more = rest[len(missing):].partition("'")
            if key in PARAM_FLAGS:
                return CliError(PARAM_FLAGS[key], "required%s" % more)
    prefix = "the board refused it: " if isinstance(e, DeviceError) else ""
    return CliError("--scene" if not from_flags else "", prefix + text)


# --- status -------------------------------------------------------------------

def add_status(sub: Any) -> None:
    p = sub.add_parser("status", help="what the board plays and how its loop runs",
                       description="Print texel.app.status() of the board: the scene, refresh "
                                   "rate, worst refresh time, overruns, free memory, firmware.")
    p.add_argument("--json", action="store_true", help="print it as JSON")
    _port_arg(p, "the one board plugged in")
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
    return "\n".join(lines)


def cmd_status(args: argparse.Namespace) -> int:
    with _connect(args) as b:
        try:
            st = b.status()
        except LinkError as e:
            raise _fail(e) from None
    print(json.dumps(st, indent=1, sort_keys=True) if args.json else format_status(st))
    return EXIT_OK


# --- monitor ------------------------------------------------------------------

def add_monitor(sub: Any) -> None:
    p = sub.add_parser("monitor", help="live finger position and amplitude, to the terminal "
                                       "or a CSV file",
                       description="Stream (time, position, amplitude) samples that the board's "
                                   "refresh loop takes itself (it is not disturbed) until "
                                   "Ctrl-C or --seconds.")
    p.add_argument("--rate", type=int, default=125, metavar="HZ",
                   help="samples per second, 1 .. the refresh rate (default 125)")
    p.add_argument("--seconds", type=positive_float, metavar="S", help="stop after S seconds")
    p.add_argument("--csv", metavar="FILE", help="write t_us,position,position_mm,amplitude rows")
    _port_arg(p, "the one board plugged in")
    p.set_defaults(func=cmd_monitor)


def _bar(amp: int, width: int = 40) -> str:
    n = round(amp / 65535 * width)
    return "#" * n + "." * (width - n)


def cmd_monitor(args: argparse.Namespace) -> int:
    if not 1 <= args.rate <= 50000:
        raise CliError("--rate", "must be 1 .. 50,000 samples/s, got %d" % args.rate)
    out = None
    if args.csv:
        try:
            out = open(args.csv, "w", encoding="utf-8")
        except OSError as e:
            raise CliError("--csv", "cannot write %s: %s" % (args.csv, e.strerror or e),
                           EXIT_FAIL) from None
        out.write("t_us,position,position_mm,amplitude\n")
    n = 0
    try:
        with _connect(args) as b:
            try:
                st = b.status()
                if not st.get("running"):
                    raise CliError("", "texelpad is not running on %s (texelpad push --board "
                                   "NAME starts it)" % b.port, EXIT_FAIL)
                dx = st["display"]["dx_um"] / 1000.0
                if not out:
                    print("%10s  %9s  %6s  amplitude" % ("t_ms", "mm", "amp"))
                for t, pos, amp in b.monitor(args.seconds, rate_hz=args.rate):
                    n += 1
                    mm = pos * dx if pos >= 0 else float("nan")
                    if out:
                        out.write("%d,%d,%.4f,%d\n" % (t, pos, mm, amp))
                    else:
                        print("%10.1f  %9s  %6d  %s" % (t / 1000, "lifted" if pos < 0 else
                                                        "%.3f" % mm, amp, _bar(amp)), flush=True)
            except LinkError as e:
                raise _fail(e) from None
    except KeyboardInterrupt:
        pass
    finally:
        if out:
            out.close()
            _stderr("monitor: %d samples written to %s" % (n, args.csv))
    return EXIT_OK


# --- ports --------------------------------------------------------------------

def add_ports(sub: Any) -> None:
    p = sub.add_parser("ports", help="list the boards plugged in",
                       description="List serial ports whose USB vendor is a MicroPython or "
                                   "CircuitPython board maker (Raspberry Pi, MicroPython, "
                                   "Adafruit, ST).")
    p.set_defaults(func=cmd_ports)


def cmd_ports(args: argparse.Namespace) -> int:
    from .link import ports
    found = ports()
    if not found:
        print("no boards found (texelpad virtual starts a virtual one)")
    for p in found:
        print("%-20s %-24s %s" % (p["port"], p["vendor"], p["description"]))
    return EXIT_OK


# --- virtual ------------------------------------------------------------------

def add_virtual(sub: Any) -> None:
    p = sub.add_parser(
        "virtual", help="run a virtual board; prints its serial port (a pty) first",
        description="Start the device image under the MicroPython unix port on a "
                    "pseudo-terminal, playing the study's split screen in real time, and print "
                    "its serial port as the first line, so texelpad --port, mpremote connect "
                    "PORT resume ..., or any serial tool can talk to it. Runs until Ctrl-C.")
    p.add_argument("--flash", metavar="DIR",
                   help="keep the board's filesystem in DIR (default: a temporary folder)")
    p.add_argument("--source", action="store_true",
                   help="run the device code from this checkout instead of deploying the "
                        "compiled image into the flash")
    p.add_argument("--no-start", action="store_true",
                   help="do not start texelpad (a bare board: for deploy tests)")
    p.add_argument("--seconds", type=positive_float, metavar="S", help="stop after S seconds")
    p.set_defaults(func=cmd_virtual)


def open_virtual(flash: str | None = None, source: bool = False, start: bool = True,
                 progress=None) -> Any:
    """A started VirtualBoard with texelpad's image (deployed into its flash,
    or the checkout's source) playing the default scene in real time."""
    from .board import connect
    from .virtual import VirtualBoard
    vb = VirtualBoard(flash, image="source" if source else None)
    vb.start()
    try:
        if not source:
            from .deploy import deploy
            with connect(vb.port, check=False) as b:
                deploy(b, include_main=False,
                       progress=(lambda m: progress("deploy: " + m)) if progress else None)
        if start:
            with connect(vb.port) as b:
                b.start("virtual", None, realtime=True)
    except BaseException:
        vb.stop()
        raise
    return vb


def cmd_virtual(args: argparse.Namespace) -> int:
    progress = lambda m: _stderr("virtual: " + m)       # noqa: E731
    try:
        vb = open_virtual(args.flash, args.source, not args.no_start, progress)
    except LinkError as e:
        raise _fail(e) from None
    try:
        print(vb.port, flush=True)
        _stderr("virtual: a virtual board is on %s (flash: %s); Ctrl-C stops it"
                % (vb.port, vb.flash))
        t_end = None if args.seconds is None else time.monotonic() + args.seconds
        while vb.alive() and (t_end is None or time.monotonic() < t_end):
            time.sleep(0.2)
        if not vb.alive():
            raise CliError("", "the virtual board exited", EXIT_FAIL)
    except KeyboardInterrupt:
        pass
    finally:
        vb.stop()
    return EXIT_OK


# --- deploy -------------------------------------------------------------------

def add_deploy(sub: Any) -> None:
    p = sub.add_parser(
        "deploy", help="install or update the device image on the board (only what changed)",
        description="Compile the device image with mpy-cross for the board's own .mpy format "
                    "and architecture (read from the board), compare sha256 hashes with what "
                    "the board holds, and write only the files that changed, each beside its "
                    "old copy then renamed over it. A playing display is stopped while "
                    "writing and started again on the new image with the scene it played. "
                    "Refuses firmware that is too old or of another .mpy format, and an "
                    "image that does not fit. mpremote users: mpremote mip install "
                    "github:<owner>/<repo> installs the source package (package.json).")
    p.add_argument("--source", action="store_true",
                   help="send the .py sources instead of .mpy (the board compiles them; "
                        "slower imports, more RAM)")
    p.add_argument("--no-main", action="store_true",
                   help="leave /main.py alone (by default it is written: the board then starts "
                        "its default scene at power-up)")
    p.add_argument("--dry-run", action="store_true", help="only say what would be written")
    _port_arg(p, "the one board plugged in")
    p.set_defaults(func=cmd_deploy)


class ProgressBar:
    """Upload progress on stderr: a redrawn bar on a terminal, a line per
    file otherwise (logs, CI)."""

    def __init__(self, stream: Any = None, width: int = 30):
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()
        self.width = width
        self.last = None

    def __call__(self, done: int, total: int, name: str) -> None:
        frac = done / total if total else 1.0
        if self.tty:
            n = int(frac * self.width)
            self.stream.write("\r[%s%s] %3d%% %7s / %s bytes  %-32s" % (
                "#" * n, "." * (self.width - n), frac * 100, format(done, ","),
                format(total, ","), name[-32:]))
            self.stream.flush()
        elif name != self.last:
            self.stream.write("deploy: %3d%% %s\n" % (frac * 100, name))
        self.last = name

    def end(self) -> None:
        if self.tty and self.last is not None:
            self.stream.write("\n")


def cmd_deploy(args: argparse.Namespace) -> int:
    from .deploy import deploy
    from .image import ImageError
    bar = ProgressBar()
    with _connect(args, check=False) as b:
        try:
            rep = deploy(b, source=args.source, include_main=not args.no_main,
                         dry_run=args.dry_run, progress=lambda m: _stderr("deploy: " + m), bar=bar)
        except ImageError as e:
            raise CliError("", str(e), EXIT_FAIL) from None
        except LinkError as e:
            raise _fail(e) from None
        finally:
            bar.end()
    print("%s %s: %d of %d files written (%s bytes), %d unchanged, %d removed, in %.2f s%s" % (
        "would deploy to" if args.dry_run else "deployed to", b.port, rep["written"],
        rep["files"], format(rep["bytes_written"], ","), rep["unchanged"], len(rep["removed"]),
        rep["seconds"], "; restarted %s with its scene" % rep["restarted"]
        if rep["restarted"] else ""))
    return EXIT_OK


# --- demo ---------------------------------------------------------------------

def add_demo(sub: Any) -> None:
    p = sub.add_parser(
        "demo", help="the quick start: play the study's split screen, sweep a finger, plot it",
        description="With no --port: start the virtual board (the device image under the "
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
    _port_arg(p, "the virtual board")
    p.set_defaults(func=cmd_demo)


def cmd_demo(args: argparse.Namespace) -> int:
    from . import demo
    if not args.out.lower().endswith(".png"):
        raise CliError("--out", "the demo writes a PNG: give a FILE.png, not %r" % args.out)
    scene = read_scene_file(args.scene) if args.scene else None
    if scene is not None:
        import texel.scene
        from .link import literal
        try:                      # the board's own check, before starting anything
            literal(scene)
            texel.scene.validate(scene, {"positions": 19200, "dx_um": 5.3})
        except ValueError as e:
            raise _value_error(e, False) from None
    try:
        rep = demo.run(args.port, args.out, scene, args.board, args.seconds,
                       timeout=args.timeout, progress=lambda m: _stderr("demo: " + m))
    except (LiteralError, DeviceError) as e:
        raise _value_error(e, False) from None
    except LinkError as e:
        raise _fail(e) from None
    print("played on %s (%s): %d telemetry samples (%d lost), %d with the finger down; "
          "played amplitude vs the map at the sensed position: max error %s counts%s"
          % (rep["port"], rep["board"], rep["samples"], rep["lost"], rep.get("down", 0),
             rep.get("amp_err_max"), "" if rep.get("pos_err_max") is None else
             "; sensed vs true finger: max %s positions" % rep["pos_err_max"]))
    print("push %.1f ms, %d bytes on the wire (the original lab sent 76,800 bytes per change); "
          "scene holds %d bytes on the board; %d refreshes, %d overruns, %d faults"
          % (rep["push_ms"], rep["push_bytes"], rep["scene_bytes"], rep["refreshes"],
             rep["overruns"], rep["faults"]))
    if args.json:
        Path(args.json).write_text(json.dumps(rep, indent=1, default=float))
    print("wrote %s" % args.out)
    return EXIT_OK


# --- bench-link -------------------------------------------------------------------

def add_bench_link(sub: Any) -> None:
    p = sub.add_parser(
        "bench-link", help="deploy time, push latency, bytes on the wire and a push soak, on "
                           "the virtual board",
        description="On a virtual board on a pty (real time): deploy the image into an empty "
                    "flash and again with nothing changed, then push --pushes texel textures, "
                    "timing each from the host call to the board's confirmation, counting the "
                    "bytes both ways, checking every acknowledgement and the board's free "
                    "memory after each push.")
    p.add_argument("--pushes", type=int, default=200, metavar="N", help="pushes (default 200)")
    p.add_argument("--json", metavar="PATH", help="also write every figure here")
    p.set_defaults(func=cmd_bench_link)


def cmd_bench_link(args: argparse.Namespace) -> int:
    from . import link_bench
    if args.pushes < 1:
        raise CliError("--pushes", "must be >= 1, got %d" % args.pushes)
    try:
        res = link_bench.run(args.pushes, progress=lambda m: _stderr("bench-link: " + m))
    except LinkError as e:
        raise _fail(e) from None
    print(link_bench.table(res))
    if args.json:
        try:
            Path(args.json).write_text(json.dumps(res, indent=1, default=str))
        except OSError as e:
            raise CliError("--json", "cannot write %s: %s" % (args.json, e.strerror or e),
                           EXIT_FAIL) from None
    return EXIT_OK if res["acked"] == res["pushes"] else EXIT_FAIL


BOARD_SUBCOMMANDS = [add_demo, add_push, add_deploy, add_virtual, add_status, add_monitor,
                     add_ports, add_bench_link]
