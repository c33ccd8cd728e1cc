"""A maker's own board file: `texelpad board check FILE` says what is wrong
with it for the firmware and chip it will run on (the board's own
validation, then the chip's facts: texelpad.deploy.boardcheck), one line a
problem; `texelpad board install FILE` checks it the same way, then writes
it to the board as /boards/NAME.json (the folder texel.runtime.boards.load
searches first), beside its old copy and renamed over it, and asks the board
whether it would start it: when the board refuses, the old file is put back.
Exit 0 fine, 2 the file (or the board's refusal of it), 1 the world (no
board, a lost link)."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from ..deploy import boardcheck
from ..link.transport import DeviceError, LinkError
from .connection import add_port_flags, connected_board
from .errors import EXIT_OK, CliError, to_stderr

BOARDS_DIR = "/boards"          # texel.runtime.boards.search_path(): the board's own first


def add_boardfile(p: argparse.ArgumentParser) -> None:
    from .parsing import Parser
    p.description = ("Your own board file (docs/runtime.md has the schema, hardware/README.md "
                     "the wiring): check it for the chip and firmware it will run on, or "
                     "install it on the board as /boards/NAME.json.")
    sub = p.add_subparsers(dest="action", metavar="ACTION", parser_class=Parser)
    s = sub.add_parser("check", help="say exactly what is wrong with a board file",
                       description="Check a board file with the board's own validation and "
                                   "the chip's facts (RP2040: GPIO, PWM slices and channels, "
                                   "ADC pins, PLL clocks; STM32F405: TIM1/TIM8 pins, ADC "
                                   "pins; CircuitPython: pwmio's TOP), one line per problem "
                                   "naming the key and what to do. Exit 0 and a summary when "
                                   "it is fine, 2 when not. Nothing is sent to a board.")
    s.add_argument("file", metavar="FILE", help="the board file (JSON); - for stdin")
    _firmware_arg(s)
    s.set_defaults(func=cmd_boardfile_check)
    s = sub.add_parser("install", help="check a board file, then put it on the board as "
                                       "/boards/NAME.json",
                       description="Check FILE as `board check` does (a refused file changes "
                                   "nothing), then write it to the board as /boards/NAME.json "
                                   "(beside the old copy, renamed over it) and ask the board "
                                   "whether it would start it (if not, the old file is put "
                                   "back). Then `texelpad push --board NAME` plays on it.")
    s.add_argument("file", metavar="FILE", help="the board file (JSON); - for stdin")
    s.add_argument("--name", metavar="NAME",
                   help="install it as /boards/NAME.json, its \"name\" set to NAME (default: "
                        "the file's \"name\"); a shipped board's name overrides that board")
    s.add_argument("--boot", action="store_true",
                   help="also make it the board the power-up starts (/texelpad.json, as "
                        "texelpad scene boot --board NAME does), with the scene playing now "
                        "or else the default scene")
    _firmware_arg(s)
    add_port_flags(s, "the one board plugged in, or the running texelpad virtual")
    s.set_defaults(func=cmd_boardfile_install)
    p.set_defaults(func=_no_action)


def _firmware_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--firmware", choices=boardcheck.FIRMWARES, default="stock",
                   help="what the board runs: stock = MicroPython (rp2, stm32) or CircuitPython "
                        "with texelpad deploy (default); texelpad = the texelpad firmware for "
                        "the Raspberry Pi Pico (rp2 board files only, Pico pins)")


def _no_action(args: argparse.Namespace) -> int:
    raise CliError("", "say what to do: texelpad board check FILE, or texelpad board install "
                   "FILE (see: texelpad board --help)")


def cmd_boardfile(args: argparse.Namespace) -> int:
    """The table's entry point (COMMANDS): the subcommand chosen."""
    return args.func(args)


def _read(path: str) -> tuple[str, bytes]:
    """(the name shown in messages, the file's bytes, at most READ_BYTES_MAX + 1)."""
    limit = boardcheck.READ_BYTES_MAX + 1
    try:
        if path == "-":
            stdin: Any = getattr(sys.stdin, "buffer", sys.stdin)   # bytes (a text stdin: str)
            data = stdin.read(limit)
            return "stdin", data
        with open(path, "rb") as f:
            return path, f.read(limit)
    except IsADirectoryError:
        raise CliError("FILE", "%s is a directory, not a board file" % path) from None
    except OSError as e:
        raise CliError("FILE", "cannot read %s: %s" % (path, e.strerror or e)) from None


def _stem(path: str) -> str | None:
    if path == "-":
        return None
    name = Path(path).name
    if name == "board.json":            # a board folder's (boards/NAME/board.json): the folder's name
        return Path(path).resolve().parent.name
    return name[:-5] if name.endswith(".json") else None


def _checked(args: argparse.Namespace, name: str | None = None) -> tuple[str, bytes, Any, Any]:
    """(shown, the file's bytes, the document, the Report) of FILE, with
    "name" set to `name` when given; its warnings printed; a refused file
    printed a problem a line and CliError (exit 2)."""
    shown, data = _read(args.file)
    doc, probs = boardcheck.read_board(data)
    if any(p.level == "error" for p in probs):
        for p in probs:
            to_stderr(p.line(shown))
        raise CliError("", "%s is not a board file" % shown)
    if name is not None and isinstance(doc, dict) and doc.get("name") != name:
        doc = dict(doc, name=name)
    else:
        name = None                     # the file as it is
    rep = boardcheck.check(doc, args.firmware, None if name is not None else _stem(args.file))
    rep.problems[:0] = probs
    for p in rep.problems:
        to_stderr(p.line(shown))
    if rep.errors:
        n, w = len(rep.errors), len(rep.warnings)
        raise CliError("", "%s: %d problem%s%s for %s: fix %s and check again" % (
            shown, n, "" if n == 1 else "s",
            " (and %d warning%s)" % (w, "" if w == 1 else "s") if w else "",
            "this firmware" if args.firmware == "stock" else "the texelpad firmware",
            "it" if n == 1 else "them"))
    return shown, (data if name is None else b""), doc, rep


def cmd_boardfile_check(args: argparse.Namespace) -> int:
    shown, data, doc, rep = _checked(args)
    for line in boardcheck.summary(rep.board, args.firmware):
        print(line)
    print("install it: texelpad board install %s [--port PORT]" % (
        args.file if args.file != "-" else "FILE"))
    return EXIT_OK


# --- install -----------------------------------------------------------------------------

def _board_port(firmware: dict[str, Any]) -> str | None:
    """The board-file port this firmware runs (rp2, stm32, circuitpython), or
    None: the unix port (the virtual board), which runs 'virtual' only."""
    from texel.runtime import boards
    if firmware.get("implementation") == "circuitpython":
        return "circuitpython"
    return boards.PLATFORM_PORT.get(firmware.get("platform"))


def _shipped() -> list[str]:
    import texel
    from texel.runtime import boards
    return boards.names(str(Path(texel.__file__).parent / boards.PACKAGE_BOARDS_DIR))


def cmd_boardfile_install(args: argparse.Namespace) -> int:
    from texel.runtime import boards
    from ..link import protocol
    from ..link.board import BOOT_FILE, board_display, boot_config, on_board_path, write_boot
    if args.name is not None and not boards._valid_name(args.name):
        raise CliError("--name", "%r: use 1..%d of a-z, 0-9, _ and -"
                       % (args.name, boards.NAME_MAX))
    shown, data, doc, rep = _checked(args, args.name)
    name = rep.board["name"]
    port = rep.board["port"]
    if data:                            # the maker's file as it is (its notes, its layout)
        text = data.decode("utf-8")
        data = (text[1:] if text.startswith("\ufeff") else text).encode("utf-8")
    else:                               # renamed (--name): "name" is the file's name
        data = (json.dumps(doc, indent=2, ensure_ascii=False) + "\n").encode("utf-8")
    with connected_board(args) as b:
        here = _board_port(b.firmware)
        if port != "virtual" and here != port:
            raise CliError("", "%s is for %s, but %s runs %s on %r (%s): nothing was written"
                           % (shown, boards.PORT_CHIP[port], b.port,
                              b.firmware["implementation"], b.firmware["platform"],
                              boards.PORT_CHIP[here] if here else
                              "the virtual board: it runs 'virtual' board files"))
        path = on_board_path(b, "%s/%s.json" % (BOARDS_DIR, name))
        tmp, old = path + ".new", path + ".old"
        kind = None
        try:
            ans = b.link.eval(protocol.preflight([path], [], "/", probe=False))
            if not (type(ans) is tuple and len(ans) == 2 and type(ans[0]) is dict):
                raise LinkError("unexpected answer from %s: %r" % (b.port, ans))
            kind = ans[0].get(path)
            if kind == "d":
                raise CliError("", "%s on %s is a folder: nothing was written" % (path, b.port))
            b.link.exec(protocol.mkdirs([on_board_path(b, BOARDS_DIR)]))
            b.link.write_file(tmp, data)
            if kind == "f":                 # the old copy kept until the board takes the new
                b.link.exec(protocol.replace_file(old, path))
            b.link.exec(protocol.replace_file(path, tmp))
        except LinkError:
            _undo(b, path, tmp, old if kind == "f" else None)
            raise
        try:
            display = board_display(b, name)    # the board loads it with its own code
        except DeviceError as e:
            _undo(b, path, tmp, old if kind == "f" else None)
            raise CliError("", "the board refused it: %s; %s" % (
                e, "its old %s is back" % path if kind == "f" else "nothing was left on it"))
        if kind == "f":
            b.link.exec(protocol.remove_file(old))
        st = b.status()
        print("installed %s on %s as %s/%s.json (%s bytes%s%s)" % (
            shown, b.port, BOARDS_DIR, name, format(len(data), ","),
            "; it replaced the one there" if kind == "f" else "",
            "; it overrides the shipped board %s" % name if name in _shipped() else ""))
        if st.get("running") and st.get("board") == name:
            print("the display plays the old %s until it starts again (texelpad stop, then "
                  "texelpad push --board %s)" % (name, name))
        if args.boot:
            try:
                scene = b.scene_source() if st.get("running") else None
                if scene is None:
                    import texel.app
                    scene = texel.app.DEFAULT_SCENE
                size = write_boot(b, boot_config(name, scene, display))
            except ValueError as e:
                raise CliError("--boot", "%s; the board file is installed, the power-up "
                               "unchanged" % e) from None
            print("power-up: board %s with %s (%s bytes in %s)" % (
                name, "the scene playing now" if st.get("running") else "the default scene",
                format(size, ","), BOOT_FILE))
    pp = "" if args.port is None else " --port %s" % args.port
    print("use it: texelpad push --board %s%s (texelpad stop first if another board file "
          "plays)%s" % (name, pp, "" if args.boot else
                        "; at power-up: texelpad board install --boot, or texelpad scene "
                        "boot SCENE --board %s" % name))
    return EXIT_OK


def _undo(b: Any, path: str, tmp: str, old: str | None) -> None:
    """Leave the board as it was: the new file and its temporary gone, the old
    copy (if there was one) back in place. Best effort: the link may be gone."""
    from ..link import protocol
    try:
        b.link.exec(protocol.remove_files([tmp]))
        if old is not None:
            ans = b.link.eval(protocol.preflight([old], [], "/", probe=False))
            if type(ans) is tuple and ans and type(ans[0]) is dict and ans[0].get(old) == "f":
                b.link.exec(protocol.replace_file(path, old))
        else:
            b.link.exec(protocol.remove_files([path]))
    except LinkError:
        pass

