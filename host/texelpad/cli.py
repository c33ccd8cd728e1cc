"""The `texelpad` command line.

One function pair per subcommand: ``add_<name>(subparsers)`` declares the
flags, ``cmd_<name>(args) -> int`` runs it. To add a subcommand, write the
pair and append the adder to ``SUBCOMMANDS``.

Errors in what the user typed print one line naming the flag and exit 2 (no
traceback); failures of the world (a file that cannot be written) exit 1.
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any, Callable, NoReturn, Sequence

import texel

from . import __version__

EXIT_OK = 0
EXIT_FAIL = 1
EXIT_USAGE = 2


class CliError(Exception):
    """A bad command-line value: printed as one line, exit 2."""

    def __init__(self, flag: str, message: str, code: int = EXIT_USAGE):
        super().__init__("%s: %s" % (flag, message) if flag else message)
        self.code = code


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (plus a hint), exit 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, "%s: error: %s (see: %s --help)\n" % (self.prog, message, self.prog))


# --- shared helpers -----------------------------------------------------------

# texel parameter key -> the flag that sets it (for error messages)
PARAM_FLAGS = {
    "pitch_db": "--pitch-db",
    "irregularity_db": "--irregularity-db",
    "seed": "--seed",
    "texel_samples": "--texel-samples",
    "length_samples": "--length-samples",
    "quant_db": "--quant-db",
    "gain": "--gain",
    "band_limit_cpmm": "--band-limit-cpmm",
    "engine": "--engine",
}


def device_error(e: ValueError) -> CliError:
    """A device ValueError ("pitch_db: nan is not finite ...") as a CliError
    naming the flag instead of the parameter key."""
    text = str(e)
    key, sep, rest = text.partition(": ")
    if sep and key in PARAM_FLAGS:
        return CliError(PARAM_FLAGS[key], rest)
    return CliError("", text)


def csv_list(text: str) -> list[str]:
    items = [s.strip() for s in text.split(",")]
    if not all(items):
        raise argparse.ArgumentTypeError("expected a comma-separated list, got %r" % text)
    return items


def positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError("invalid int value: %r" % text) from None
    if v < 1:
        raise argparse.ArgumentTypeError("must be >= 1, got %d" % v)
    return v


def _stderr(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


# --- bench ------------------------------------------------------------------

def add_bench(sub: Any) -> None:
    from .bench import RUNTIMES, TIMING_CASE
    from .cases import HARD_CASES
    p = sub.add_parser(
        "bench", help="speed against error of every render engine on every runtime",
        description="Time a full 19,200-sample map (the %r case; plan and synthesis apart, "
                    "median of --repeat runs) with every engine on CPython and on the "
                    "MicroPython unix port, and measure each engine's error against the "
                    "float64 reference over the hard-case suite, in PWM steps (1/3676 of "
                    "full scale). Also prints an op-count ESTIMATE for an emulated RP2040. "
                    "Progress goes to stderr, the table to stdout." % TIMING_CASE)
    p.add_argument("--json", metavar="PATH",
                   help="also write every figure, per-case detail, machine and versions here")
    p.add_argument("--cases", type=csv_list, metavar="A,B,...",
                   help="hard cases to measure errors on (default: all %d: %s)"
                        % (len(HARD_CASES), ", ".join(HARD_CASES)))
    p.add_argument("--runtimes", type=csv_list, default=list(RUNTIMES), metavar="R,...",
                   help="runtimes to bench (default: %s)" % ",".join(RUNTIMES))
    p.add_argument("--repeat", type=positive_int, default=11, metavar="N",
                   help="timing repeats, the median is reported (default: 11; a full map "
                        "takes milliseconds, and more runs steady the median on a busy host)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(func=cmd_bench)


def cmd_bench(args: argparse.Namespace) -> int:
    from . import bench
    from .cases import HARD_CASES
    bad = [r for r in args.runtimes if r not in bench.RUNTIMES]
    if bad:
        raise CliError("--runtimes", "unknown runtime %s (known: %s)"
                       % (", ".join(map(repr, bad)), ", ".join(bench.RUNTIMES)))
    if args.cases is not None:
        bad = [c for c in args.cases if c not in HARD_CASES]
        if bad:
            raise CliError("--cases", "unknown case %s (known: %s)"
                           % (", ".join(map(repr, bad)), ", ".join(HARD_CASES)))
    progress = None if args.quiet else (lambda m: _stderr("bench: " + m))
    res = bench.run(args.cases, args.runtimes, args.repeat, progress)
    print(bench.table(res), flush=True)
    if args.json:
        try:
            bench.write_json(res, args.json)
        except OSError as e:
            raise CliError("--json", "cannot write %s: %s" % (args.json, e.strerror or e),
                           EXIT_FAIL) from None
        if progress:
            progress("wrote %s" % args.json)
    return EXIT_FAIL if res.failed else EXIT_OK


# --- render -----------------------------------------------------------------

OUT_TYPES = (".png", ".csv", ".npy")


def add_render(sub: Any) -> None:
    p = sub.add_parser(
        "render", help="render a texel texture on the host, summarise it, save it",
        description="Render a Single-Pitch Texel friction map on the host and print a summary "
                    "(texels, fraction above Nyquist, pitch range). --out writes the map as "
                    ".csv (sample, x_mm, friction) or .npy (float64), or a .png figure of the "
                    "map, its spectrum and the texel pitch histogram against the "
                    "Normal(pitch_db, 10*sigma) pitch distribution.")
    g = p.add_argument_group("texture parameters (ranges: see the texel package)")
    g.add_argument("--pitch-db", type=float, required=True, metavar="DB",
                   help="central pitch, 10*log10(P / 1 cycle/mm), -20 .. 19.747")
    g.add_argument("--irregularity-db", type=float, required=True, metavar="DB",
                   help="irregularity, 10*log10(sigma / 1 decade), -30 .. 5")
    g.add_argument("--seed", type=int, metavar="N", help="random seed, 0 .. 2^32-1 (default 0)")
    g.add_argument("--texel-samples", type=int, metavar="N",
                   help="samples per texel (default 50 = 0.265 mm)")
    g.add_argument("--length-samples", type=int, metavar="N",
                   help="map length in samples of 5.3 um (default 9600 = half the screen)")
    g.add_argument("--quant-db", type=float, metavar="DB",
                   help="quantize log pitch to this grid, dB (default 0 = off)")
    g.add_argument("--gain", type=float, metavar="G", help="map scale, 0 .. 1 (default 1)")
    g.add_argument("--band-limit-cpmm", type=float, metavar="F",
                   help="clamp drawn pitches to at most F cycles/mm (default: faithful, "
                        "pitches above Nyquist alias as in the original)")
    p.add_argument("--engine", metavar="NAME",
                   help="render engine: numpy (default on CPython), int, pure, ulab "
                        "(ulab through the host stand-in)")
    p.add_argument("--out", metavar="FILE", help="write FILE.png, FILE.csv or FILE.npy")
    p.set_defaults(func=cmd_render)


def render_params(args: argparse.Namespace) -> dict[str, Any]:
    """The texel parameter dict from the flags that were given."""
    params: dict[str, Any] = {}
    for key in ("pitch_db", "irregularity_db", "seed", "texel_samples", "length_samples",
                "quant_db", "gain", "band_limit_cpmm"):
        v = getattr(args, key)
        if v is not None:
            params[key] = v
    return params


def _ensure_engine(name: str | None) -> Callable[[], None]:
    """Make `name` usable; returns the undo. ulab on CPython goes through the
    host stand-in (texelpad.ulab_standin) when it is present."""
    if name == "ulab" and "ulab" not in texel.engines():
        try:
            from . import ulab_standin
        except ImportError:
            return lambda: None
        ulab_standin.install()
        return ulab_standin.uninstall
    return lambda: None


def to_numpy(buf: Any) -> Any:
    import numpy as np
    try:
        return np.asarray(buf, dtype=np.float64)
    except (TypeError, ValueError):
        from .ulab_standin import to_numpy as standin_to_numpy
        return np.asarray(standin_to_numpy(buf), dtype=np.float64)


def summary(plan: Any, engine: str) -> str:
    """One paragraph: texels, pitch range, fraction above Nyquist."""
    p = plan.params
    f = [float(x) for x in plan.f]
    lo, hi = min(f), max(f)
    srt = sorted(f)
    med = srt[len(srt) // 2] if len(srt) % 2 else 0.5 * (srt[len(srt) // 2 - 1] + srt[len(srt) // 2])
    sigma = 10.0 ** (p["irregularity_db"] / 10.0)
    L = plan.L
    whole, rest = divmod(plan.n, L)
    texels = "%d texel%s of %d sample%s (%.4g mm)" % (
        whole, "" if whole == 1 else "s", L, "" if L == 1 else "s", L * texel.DX_MM)
    if rest and whole:
        texels += " plus one cut to %d" % rest
    elif rest:
        texels = "one texel of %d samples (%.4g mm) cut to the map" % (L, L * texel.DX_MM)
    quant = ("pitches quantized to a %g dB grid" % p["quant_db"]) if p["quant_db"] > 0 \
        else "no quantization"
    if p["band_limit_cpmm"] is not None:
        quant += ", pitches clamped to <= %.4g c/mm" % p["band_limit_cpmm"]
    above = plan.above_nyquist
    return (
        "Rendered %d samples (%.2f mm) with the %s engine: %s. Central pitch %.4g c/mm "
        "(%.2f dB), irregularity %.4g decade (%.2f dB), seed %d, %s, gain %g. Drawn texel "
        "pitches span %.4g .. %.4g c/mm (%.2f .. %.2f dB, median %.4g c/mm); %d of %d texels "
        "(%.1f %%) lie above Nyquist (%.2f c/mm)%s."
        % (plan.n, plan.n * texel.DX_MM, engine, texels, 10 ** (p["pitch_db"] / 10.0),
           p["pitch_db"], sigma, p["irregularity_db"], p["seed"], quant, p["gain"],
           lo, hi, 10 * math.log10(lo), 10 * math.log10(hi), med, above, plan.count,
           100.0 * above / plan.count, texel.NYQUIST_CPMM,
           "" if above == 0 else " and alias, as in the original generator"))


def cmd_render(args: argparse.Namespace) -> int:
    import numpy as np
    out = Path(args.out) if args.out else None
    if out is not None and out.suffix.lower() not in OUT_TYPES:
        raise CliError("--out", "unsupported file type %r (use %s)"
                       % (out.suffix or out.name, ", ".join(OUT_TYPES)))
    params = render_params(args)
    undo = _ensure_engine(args.engine)
    try:
        try:
            plan = texel.plan(params)
            engine = args.engine or texel.default_engine()
            fmap = to_numpy(texel.render(params, engine=engine))
        except ValueError as e:
            raise device_error(e) from None
    finally:
        undo()
    print(summary(plan, engine))
    if out is None:
        return EXIT_OK
    try:
        kind = out.suffix.lower()
        if kind == ".npy":
            np.save(out, fmap)
        elif kind == ".csv":
            k = np.arange(fmap.size)
            np.savetxt(out, np.column_stack([k, k * texel.DX_MM, fmap]),
                       fmt=("%d", "%.4f", "%.10f"), delimiter=",",
                       header="sample,x_mm,friction", comments="")
        else:
            from .plots import render_figure
            render_figure(fmap, plan, out, engine=engine)
    except OSError as e:
        raise CliError("--out", "cannot write %s: %s" % (out, e.strerror or e),
                       EXIT_FAIL) from None
    print("wrote %s" % out)
    return EXIT_OK


# --- tank -------------------------------------------------------------------

def add_tank(sub: Any) -> None:
    from .tank import arg_quantity
    p = sub.add_parser(
        "tank", help="resonant tank calculator: series inductor, tuning capacitor, frequency",
        description="f = 1/(2*pi*sqrt(L*C)) for the series inductor and the piezo plate "
                    "(hardware/README.md). Give two of -L, -C, -f for the third; or the "
                    "piezo's capacitance (--piezo) with -f for the "
                    "series inductor, with -L and -f for the tuning capacitor to add, or with "
                    "-L for the frequency. Values take SI prefixes: 390u, 390uH, 56n, 34k.")
    p.add_argument("-L", "--inductance", type=arg_quantity("H"), metavar="H",
                   help="series inductance, e.g. 390u (the TPad Fire used 390 uH)")
    p.add_argument("-C", "--capacitance", type=arg_quantity("F"), metavar="F",
                   help="total tank capacitance, e.g. 56n")
    p.add_argument("-f", "--frequency", type=arg_quantity("Hz"), metavar="HZ",
                   help="resonant frequency, e.g. 34k (the plate's measured resonance)")
    p.add_argument("--piezo", type=arg_quantity("F"), metavar="F",
                   help="the piezo discs' capacitance (an LCR meter at ~1 kHz gives a first "
                        "value; final tuning is measured)")
    p.add_argument("--bus-volts", type=arg_quantity("V"), metavar="V",
                   help="with --q: estimate the piezo voltage and tank current at full amplitude")
    p.add_argument("--q", type=arg_quantity(""), metavar="Q",
                   help="the loaded tank's quality factor (measure: f0 / -3 dB bandwidth)")
    p.add_argument("--drive", choices=("single", "bridge"), default="single",
                   help="for the estimate: single-ended or full bridge (default single)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON (SI units)")
    p.set_defaults(func=cmd_tank)


def cmd_tank(args: argparse.Namespace) -> int:
    import json
    from .tank import TankInputError, report
    try:
        text, data = report(args.inductance, args.capacitance, args.frequency, args.piezo,
                            args.bus_volts, args.q, args.drive)
    except TankInputError as e:
        raise CliError(e.flag, str(e)) from None
    print(json.dumps(data, indent=2) if args.json else text)
    return EXIT_OK


# --- bench-refresh ----------------------------------------------------------

def positive_float(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError("invalid number: %r" % text) from None
    if not (v > 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError("must be a finite number > 0, got %s" % text)
    return v


def add_bench_refresh(sub: Any) -> None:
    from .refresh_bench import BUDGET_US, DEFAULT_SECONDS, GOAL_US
    p = sub.add_parser(
        "bench-refresh", help="what one refresh of the 8,333 Hz loop costs, and scene memory "
                              "and swap latency",
        description="Run the device runtime on the virtual board under the MicroPython unix "
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
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(func=cmd_bench_refresh)


def cmd_bench_refresh(args: argparse.Namespace) -> int:
    from . import refresh_bench
    progress = None if args.quiet else (lambda m: _stderr("bench-refresh: " + m))
    res = refresh_bench.run(args.seconds, progress)
    print(refresh_bench.table(res), flush=True)
    if args.json:
        try:
            refresh_bench.write_json(res, args.json)
        except OSError as e:
            raise CliError("--json", "cannot write %s: %s" % (args.json, e.strerror or e),
                           EXIT_FAIL) from None
        if progress:
            progress("wrote %s" % args.json)
    return EXIT_FAIL if res.failed else EXIT_OK


# --- entry point ----------------------------------------------------------------

SUBCOMMANDS: list[Callable[[Any], None]] = [add_bench, add_render, add_tank,
                                             add_bench_refresh]


def _board_subcommands() -> list[Callable[[Any], None]]:
    # the board commands live in cli_board.py, which imports the helpers above
    from .cli_board import BOARD_SUBCOMMANDS
    return BOARD_SUBCOMMANDS


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="texelpad",
        description="texelpad: host toolkit for Single-Pitch Texel friction textures on "
                    "microcontroller boards.")
    parser.add_argument("--version", action="version",
                        version="texelpad %s (texel %s)" % (__version__, texel.__version__))
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for add in _board_subcommands() + SUBCOMMANDS:
        add(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    try:
        return args.func(args)
    except CliError as e:
        _stderr("texelpad %s: error: %s" % (args.command, e))
        return e.code
    except KeyboardInterrupt:
        _stderr("texelpad %s: interrupted" % args.command)
        return 130


if __name__ == "__main__":
    sys.exit(main())
