"""The `texelpad` command line: one table of commands, each imported only when
it runs, so `texelpad --help` is fast and no command module imports another.

To add a command: write `add_<name>(p)` (set p.description, add the flags,
p.set_defaults(func=cmd_<name>)) and `cmd_<name>(args) -> exit code` in a
module of this package, and add one row to COMMANDS. Conventions (errors.py):
a bad flag or a refused request is one line naming the flag and exit 2; a
failure of the world (no board, a file that cannot be written) exit 1.
Output closed early (`texelpad render ... | head -1`): exit 1 quietly, no
traceback (main(), _broken_pipe). Output files are checked before the work
that fills them (files.check_output).
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
    "push": ("board", "push", "play a texel texture (flags), a reference texture, a constant "
                              "level or a scene (JSON file) on the board"),
    "deploy": ("deploy", "deploy",
               "install or update the device image on the board (only what changed)"),
    "firmware": ("firmware", "firmware", "build the texelpad firmware (.uf2) for a Pico: "
                                         "MicroPython + ulab + texelpad in flash"),
    "virtual": ("virtual", "virtual", "run a virtual board; prints its serial port (a pty) first"),
    "stop": ("board", "stop", "safety: turn the carrier off now"),
    "status": ("board", "status", "what the board plays and how its loop runs"),
    "scene": ("scene", "scene", "save the scene playing to a file (pull), or set the scene the "
                                "board plays at power-up (boot)"),
    "scenes": ("scene", "scenes", "list the example scenes shipped with texelpad"),
    "board": ("boardfile", "boardfile", "your own board file: check it for its chip and "
                                        "firmware (check), put it on the board (install)"),
    "monitor": ("board", "monitor",
                "live finger position and amplitude, to the terminal or a CSV file"),
    "ports": ("board", "ports", "list the boards plugged in"),
    "bench-link": ("bench", "bench_link", "deploy time, push latency, bytes on the wire and a "
                                          "push soak, on the virtual board"),
    "bench": ("bench", "bench", "speed against error of every render engine on every runtime"),
    "render": ("render", "render", "render a texel texture on the host, summarise it, save it"),
    "encode": ("encode", "encode", "a friction map (file, reference, scene region) -> the texel "
                                   "parameters that feel the same, with the reasoning"),
    "brush": ("brush", "brush", "the Tactile Paintbrush: fit a brush from a recording, design, "
                                "paint (a map or a scene), show, compare"),
    "lab": ("lab", "lab", "the papers' study protocols in the browser, on a board or the "
                          "virtual one (127.0.0.1 only)"),
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
    from .parsing import Parser
    parser = Parser(
        prog="texelpad",
        description="texelpad: host toolkit for Single-Pitch Texel friction textures on "
                    "microcontroller boards.")
    import texel
    parser.add_argument("--version", action="version",
                        version="texelpad %s (texel %s)" % (__version__, texel.__version__))
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    chosen = _chosen(argv)
    for name, (module, func, summary) in COMMANDS.items():
        p = sub.add_parser(name, help=summary, description=summary)
        if name == chosen:
            mod = importlib.import_module("%s.%s" % (__name__, module))
            getattr(mod, "add_" + func)(p)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        return _main(argv)
    except BrokenPipeError:             # also from --help, or an error line on a closed stderr
        return _broken_pipe(_chosen(argv) or "")


def _main(argv: list[str]) -> int:
    from .errors import EXIT_USAGE, CliError, to_stderr
    parser = build_parser(argv)
    try:
        args = parser.parse_args(argv)
    except SystemExit:                  # --help, --version, a usage error: flush it here
        sys.stdout.flush()
        raise
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    try:
        code = args.func(args)
        sys.stdout.flush()              # a closed pipe shows here, not at exit
        return code
    except CliError as e:
        to_stderr("texelpad %s: error: %s" % (args.command, e))
        return e.code
    except KeyboardInterrupt as e:
        # link.transport.Interrupted says what the board does now
        to_stderr("texelpad %s: %s" % (args.command, str(e) or "interrupted"))
        return 130


def _closed(stream: object) -> bool:
    """Whether stream is a pipe whose reader has gone (poll: POLLERR);
    True where that cannot be told (no poll, as on Windows)."""
    try:
        fd = stream.fileno()           # type: ignore[attr-defined]
    except (AttributeError, OSError, ValueError):
        return False
    try:
        import select
        poller = select.poll()
        poller.register(fd, select.POLLOUT)
        return any(ev & (select.POLLERR | select.POLLHUP) for _, ev in poller.poll(0))
    except (AttributeError, OSError, ValueError):
        return True


def _broken_pipe(command: str) -> int:
    """The reader of our output went away (`texelpad ... | head`): the Python
    docs' recipe (library/signal, "Note on SIGPIPE"): point stdout at devnull
    so the interpreter's final flush cannot fail again, and exit 1 QUIETLY -
    as a Unix tool cut off by `head` prints nothing. A broken pipe that is not
    stdout's or stderr's (a subprocess the command feeds) is a failure of the
    world: one line, exit 1."""
    import os
    from .errors import EXIT_FAIL, to_stderr
    quiet = False
    for stream in (sys.stdout, sys.stderr):
        if _closed(stream):
            quiet = True
            try:
                devnull = os.open(os.devnull, os.O_WRONLY)
                os.dup2(devnull, stream.fileno())
                os.close(devnull)
            except (AttributeError, OSError, ValueError):
                pass
    if not quiet:
        try:
            to_stderr("texelpad%s: error: broken pipe (a process it wrote to went away)"
                      % (" " + command if command else ""))
        except OSError:
            pass
    return EXIT_FAIL
