"""The `texelpad` command line: one table of commands, each imported only when
it runs, so `texelpad --help` is fast and no command module imports another.

To add a command: write `add_<name>(p)` (set p.description, add the flags,
p.set_defaults(func=cmd_<name>)) and `cmd_<name>(args) -> exit code` in a
module of this package, and add one row to COMMANDS. Conventions (common.py):
a bad flag or a refused request is one line naming the flag and exit 2; a
failure of the world (no board, a file that cannot be written) exit 1.
"""
from __future__ import annotations

import argparse
import importlib
import sys
from typing import Sequence

from .. import __version__

# name -> (module in texelpad.cli, the function suffix, one-line summary);
# the order is the order of `texelpad --help`.
COMMANDS: dict[str, tuple[str, str, str]] = {
    "demo": ("demo", "demo",
             "the quick start: play the study's split screen, sweep a finger, plot it"),
    "push": ("board", "push", "play a texel texture (flags) or a scene (JSON file) on the board"),
    "deploy": ("deploy", "deploy",
               "install or update the device image on the board (only what changed)"),
    "virtual": ("virtual", "virtual", "run a virtual board; prints its serial port (a pty) first"),
    "status": ("board", "status", "what the board plays and how its loop runs"),
    "monitor": ("board", "monitor",
                "live finger position and amplitude, to the terminal or a CSV file"),
    "ports": ("board", "ports", "list the boards plugged in"),
    "bench-link": ("bench", "bench_link", "deploy time, push latency, bytes on the wire and a "
                                          "push soak, on the virtual board"),
    "bench": ("bench", "bench", "speed against error of every render engine on every runtime"),
    "render": ("render", "render", "render a texel texture on the host, summarise it, save it"),
    "tank": ("tank", "tank",
             "resonant tank calculator: series inductor, tuning capacitor, frequency"),
    "bench-refresh": ("bench", "bench_refresh", "what one refresh of the 8,333 Hz loop costs, "
                                                "and scene memory and swap latency"),
}


def _chosen(argv: Sequence[str]) -> str | None:
    """The command word in argv (the first argument that is not an option)."""
    for a in argv:
        if not a.startswith("-"):
            return a
    return None


def build_parser(argv: Sequence[str] = ()) -> argparse.ArgumentParser:
    """The parser; only the command named in argv gets its flags (its module
    is imported), the others are listed with their summaries."""
    from .common import _Parser
    parser = _Parser(
        prog="texelpad",
        description="texelpad: host toolkit for Single-Pitch Texel friction textures on "
                    "microcontroller boards.")
    import texel
    parser.add_argument("--version", action="version",
                        version="texelpad %s (texel %s)" % (__version__, texel.__version__))
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    chosen = _chosen(argv)
    for name, (module, func, summary) in COMMANDS.items():
        p = sub.add_parser(name, help=summary, description=summary)
        if name == chosen:
            mod = importlib.import_module("%s.%s" % (__name__, module))
            getattr(mod, "add_" + func)(p)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    from .common import EXIT_USAGE, CliError, _stderr
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(argv)
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
