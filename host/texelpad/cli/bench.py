"""`texelpad bench`, `bench-refresh`, `bench-link`: the benchmarks (texelpad.bench)."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from ..link.transport import LinkError
from .connection import link_failure
from .errors import EXIT_FAIL, EXIT_OK, CliError, to_stderr
from .files import check_output, write_output
from .parsing import csv_list, positive_float, positive_int


def add_bench(p: argparse.ArgumentParser) -> None:
    from ..bench.engines import RUNTIMES, TIMING_CASE
    from ..analysis.hard_cases import HARD_CASES
    p.description = ("Time a full 19,200-sample map (the %r case; plan and synthesis apart, "
                    "median of --repeat runs) with every engine on CPython, the MicroPython "
                    "unix port and, where this machine has them, the instrument interpreters "
                    "built like the boards (MicroPython + ulab in float32 and float64, "
                    "CircuitPython + ulab with 30-bit floats and no viper), and measure each "
                    "engine's error against the float64 reference over the hard-case suite, "
                    "in PWM steps (1/3676 of full scale). A runtime whose interpreter is "
                    "absent is listed as skipped. Also prints an op-count ESTIMATE for an "
                    "emulated RP2040. Progress goes to stderr, the table to stdout."
                    % TIMING_CASE)
    p.add_argument("--json", metavar="PATH",
                   help="also write every figure, per-case detail, machine and versions here")
    p.add_argument("--cases", type=csv_list, metavar="A,B,...",
                   help="hard cases to measure errors on (default: all %d: %s)"
                        % (len(HARD_CASES), ", ".join(HARD_CASES)))
    p.add_argument("--runtimes", type=csv_list, default=list(RUNTIMES), metavar="R,...",
                   help="runtimes to bench, of %s (default: all; one whose interpreter "
                        "is absent is skipped)" % ",".join(RUNTIMES))
    p.add_argument("--repeat", type=positive_int, default=11, metavar="N",
                   help="timing repeats, the median is reported (default: 11; a full map "
                        "takes milliseconds, and more runs steady the median on a busy host)")
    p.add_argument("--chip", choices=("rp2040",),
                   help="also on the emulated Pico (../shared/instruments/rp2emu, node): the "
                        "chip's own timings of every engine and of the plan in each texture "
                        "format, beside the estimate (a few wall minutes)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(func=cmd_bench)


def cmd_bench(args: argparse.Namespace) -> int:
    from ..bench import engines as bench
    from ..analysis.hard_cases import HARD_CASES
    bad = [r for r in args.runtimes if r not in bench.RUNTIMES]
    if bad:
        raise CliError("--runtimes", "unknown runtime %s (known: %s)"
                       % (", ".join(map(repr, bad)), ", ".join(bench.RUNTIMES)))
    if args.cases is not None:
        bad = [c for c in args.cases if c not in HARD_CASES]
        if bad:
            raise CliError("--cases", "unknown case %s (known: %s)"
                           % (", ".join(map(repr, bad)), ", ".join(HARD_CASES)))
    if args.json:                       # before the minutes of work, not after
        check_output("--json", args.json, (".json",))
    progress = None if args.quiet else (lambda m: to_stderr("bench: " + m))
    res = bench.run(args.cases, args.runtimes, args.repeat, progress, chip=args.chip)
    return _report(bench, res, args.json, progress)


def _report(module, res, json_path: str | None, progress) -> int:
    """A bench's ending: its table on stdout, its JSON if asked (the path was
    checked before the work), exit 1 when a runtime failed."""
    print(module.table(res), flush=True)
    if json_path:
        write_output("--json", json_path, lambda: module.write_json(res, json_path))
        if progress:
            progress("wrote %s" % json_path)
    return EXIT_FAIL if res.failed else EXIT_OK


def add_bench_refresh(p: argparse.ArgumentParser) -> None:
    from ..bench.refresh import BUDGET_US, DEFAULT_SECONDS, GOAL_US
    from ..bench.chip import CHIP_SOAK_S
    p.description = ("Run the device runtime on the virtual board under the MicroPython unix "
                    "port while a scripted finger swipes across the study's split screen, and "
                    "time one refresh (Python and, where present, the fused viper refresh; "
                    "batches timed with ticks_us), its parts (sensor.read, scene.amp, "
                    "law.duty, hw.set_duty), the memory of five scenes and app.push() split "
                    "into validate/build/swap. Also prints an op-count ESTIMATE for an "
                    "emulated RP2040 against the %d us refresh period (goal <= %g us). "
                    "Progress goes to stderr, the table to stdout." % (BUDGET_US, GOAL_US))
    p.add_argument("--json", metavar="PATH", help="also write every figure here")
    p.add_argument("--seconds", type=positive_float, default=DEFAULT_SECONDS, metavar="S",
                   help="wall time spent timing each refresh variant, at most (it also stops "
                        "at 16,384 batches of 100); each component gets S/4 (at most 4,096 "
                        "batches). Default %g" % DEFAULT_SECONDS)
    p.add_argument("--chip", choices=("rp2040",),
                   help="also on the emulated Pico (../shared/instruments/rp2emu; needs node): "
                        "the refresh's cost incl. IRQ entry/exit from the chip's own clock, the "
                        "rate and overruns while the host pushes scenes, the carrier on the "
                        "pin probe and the amplitude at the finger against the scene's map "
                        "(texelpad/bench/chip.py; a few minutes)")
    p.add_argument("--soak-seconds", type=positive_float, metavar="S",
                   help="with --chip: emulated seconds of pushes for the rate (default %g; "
                        "~5 wall seconds each)" % CHIP_SOAK_S)
    p.add_argument("--no-unix", action="store_true",
                   help="with --chip: leave the unix-port measurements out")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(func=cmd_bench_refresh)


def cmd_bench_refresh(args: argparse.Namespace) -> int:
    from ..bench import refresh as refresh_bench
    if not args.chip and (args.no_unix or args.soak_seconds is not None):
        raise CliError("--no-unix" if args.no_unix else "--soak-seconds",
                       "only with --chip rp2040")
    if args.json:
        check_output("--json", args.json, (".json",))
    if args.chip:
        from ..sim.emulated import why_not
        why = why_not()
        if why:
            raise CliError("--chip", why, EXIT_FAIL)
    progress = None if args.quiet else (lambda m: to_stderr("bench-refresh: " + m))
    res = refresh_bench.run(args.seconds, progress, chip=args.chip, soak_s=args.soak_seconds,
                            unix=not args.no_unix)
    return _report(refresh_bench, res, args.json, progress)


def add_bench_link(p: argparse.ArgumentParser) -> None:
    p.description = ("On a virtual board on a pty (real time): deploy the image into an empty "
                    "flash and again with nothing changed, then push --pushes texel textures, "
                    "timing each from the host call to the board's confirmation, counting the "
                    "bytes both ways, checking every acknowledgement and the board's free "
                    "memory after each push.")
    p.add_argument("--pushes", type=int, metavar="N",
                   help="pushes (default 200; 20 with --chip)")
    p.add_argument("--chip", choices=("rp2040",),
                   help="on the emulated Pico instead (texelpad virtual --chip rp2040; needs "
                        "../shared/instruments and node): the chip's own figures")
    p.add_argument("--json", metavar="PATH", help="also write every figure here")
    p.set_defaults(func=cmd_bench_link)


def cmd_bench_link(args: argparse.Namespace) -> int:
    from ..bench import link as link_bench
    if args.pushes is None:
        args.pushes = 20 if args.chip else 200
    if args.pushes < 1:
        raise CliError("--pushes", "must be >= 1, got %d" % args.pushes)
    if args.json:
        check_output("--json", args.json, (".json",))
    if args.chip:
        from ..sim.emulated import why_not
        why = why_not()
        if why:
            raise CliError("--chip", why, EXIT_FAIL)
    try:
        res = link_bench.run(args.pushes, progress=lambda m: to_stderr("bench-link: " + m),
                             chip=args.chip)
    except LinkError as e:
        raise link_failure(e) from None
    except RuntimeError as e:           # the emulator did not come up
        raise CliError("--chip", str(e), EXIT_FAIL) from None
    print(link_bench.table(res))
    if args.json:
        write_output("--json", args.json,
                     lambda: Path(args.json).write_text(json.dumps(res, indent=1, default=str)))
    return EXIT_OK if res["acked"] == res["pushes"] else EXIT_FAIL

