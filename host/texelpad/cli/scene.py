"""Scenes as files: `texelpad scene pull FILE` saves what the board plays,
`texelpad scene boot FILE` makes a scene the board's power-up scene
(/texelpad.json, read by its /main.py), `texelpad scene pin FILE...` writes
its format into every texel texture of a scene file that does not say it
(a file from before format 2 became the default keeps its texture), and
`texelpad scenes` lists the
example scenes shipped with texelpad (texelpad/scenes/*.json), which
`--scene NAME` and `scene boot NAME` find by name.

Output files are checked before the board is opened and written atomically
(a temporary file beside them, renamed over): a failure never leaves a half
file or clobbers the old one. The power-up file is checked on the host with
the board's own validation and written beside its old copy on the board,
then renamed over it, so a bad scene or a failed write leaves it as it was."""
from __future__ import annotations

import argparse
import json
import sys
from typing import cast

from ..link.transport import DeviceError
from .connection import add_port_flags, connected_board, not_running, running_board
from .errors import EXIT_FAIL, EXIT_OK, CliError
from .files import check_output, write_atomic, write_output
from .scene_files import pin_formats, read_scene_file, scene_json, shipped_scenes


def add_scene(p: argparse.ArgumentParser) -> None:
    from .parsing import Parser
    p.description = ("Scenes as files: save what the board plays (pull), or make a scene the "
                     "one the board plays at power-up (boot).")
    sub = p.add_subparsers(dest="action", metavar="ACTION", parser_class=Parser)
    s = sub.add_parser("pull", aliases=["save"], help="write the scene playing now to a file",
                       description="Write the scene the board plays now (its canonical form: "
                                   "every default filled in) to FILE as JSON, ready for "
                                   "texelpad push --scene FILE. FILE is checked writable "
                                   "before the board is opened and written atomically.")
    s.add_argument("file", metavar="FILE", help="the JSON file to write; - for stdout")
    add_port_flags(s, "the one board plugged in")
    s.set_defaults(func=cmd_scene_pull)
    s = sub.add_parser("boot", help="set (or --clear) the scene the board plays at power-up",
                       description="Make a scene the board's power-up scene: it is checked on "
                                   "the host with the board's own validation and written to "
                                   "/texelpad.json on the board with the board file to start "
                                   "(the board's /main.py reads it at power-up; texelpad "
                                   "deploy leaves it alone). The file is written beside its "
                                   "old copy and renamed over it: a bad scene or a failed "
                                   "write leaves the old one.")
    s.add_argument("file", metavar="FILE", nargs="*",
                   help="a scene file, - for stdin, or a shipped scene's name (texelpad "
                        "scenes); several: a playlist the board's button steps through "
                        "(the classroom kit, docs/kit.md), the first plays at power-up")
    s.add_argument("--current", action="store_true", help="the scene the board plays now")
    s.add_argument("--clear", action="store_true",
                   help="remove /texelpad.json: the board plays its default at power-up")
    s.add_argument("--board", metavar="NAME",
                   help="the board file to start at power-up (default: the one running now)")
    add_port_flags(s, "the one board plugged in")
    s.set_defaults(func=cmd_scene_boot)
    s = sub.add_parser("pin", help="write \"v\": 1 into every texel texture of scene files "
                                   "that does not say its format (files made before format 2 "
                                   "was the default keep their texture)",
                       description="A texel texture without \"v\" is format 2 (the integer "
                                   "plan) since texelpad 0.2; before, it was format 1 (the "
                                   "lab's float generator). pin writes \"v\": 1 (or --format) "
                                   "into every texel texture of each FILE that has no \"v\", "
                                   "so the file plays what it played before. A file with "
                                   "nothing to pin is not touched; the others are written "
                                   "atomically (a temporary file renamed over). Every file is "
                                   "read and checked before any is written.")
    s.add_argument("files", metavar="FILE", nargs="+", help="scene files (JSON) to pin")
    s.add_argument("--format", dest="v", type=int, choices=(1, 2), default=1,
                   help="the format to write (default 1: what a texture without \"v\" "
                        "played before 0.2)")
    s.add_argument("--check", action="store_true",
                   help="write nothing: list the files that would change, exit 1 if any")
    s.set_defaults(func=cmd_scene_pin)
    p.set_defaults(func=_no_action)


def _no_action(args: argparse.Namespace) -> int:
    raise CliError("", "say what to do: texelpad scene pull FILE, texelpad scene boot "
                   "FILE|--current|--clear, or texelpad scene pin FILE... (see: texelpad "
                   "scene --help)")


# --- pull ----------------------------------------------------------------------------

def cmd_scene_pull(args: argparse.Namespace) -> int:
    if args.file != "-":
        check_output("", args.file)          # before the board is opened
    with running_board(args) as (b, _):
        scene = b.scene_source()
    if scene is None:                           # it stopped since
        raise not_running(b.port)
    text = scene_json(scene)
    if args.file == "-":
        sys.stdout.write(text)
        return EXIT_OK
    write_output("", args.file, lambda: write_atomic(args.file, text))
    print("saved the scene playing on %s (%d region%s%s) to %s" % (
        b.port, len(scene["regions"]), "" if len(scene["regions"]) == 1 else "s",
        ", %r" % scene["name"] if scene.get("name") else "", args.file))
    return EXIT_OK


# --- boot ----------------------------------------------------------------------------

def cmd_scene_boot(args: argparse.Namespace) -> int:
    from ..link.board import BOOT_FILE, board_display, boot_config, clear_boot, write_boot
    given = [n for n, on in (("FILE", bool(args.file)), ("--current", args.current),
                             ("--clear", args.clear)) if on]
    if len(given) != 1:
        raise CliError("", "give one of FILE, --current or --clear%s"
                       % (", not %s" % " and ".join(given) if given else ""))
    if args.clear and args.board:
        raise CliError("--board", "--clear removes the power-up file; there is no board to name")
    if args.file.count("-") > 1:
        raise CliError("FILE", "stdin (-) can be read once")
    scenes = [read_scene_file(f, "FILE") for f in args.file]     # all read before the board
    scene = scenes[0] if scenes else None

    def refused(e: ValueError) -> CliError:
        if isinstance(e, DeviceError):          # only the named board file is the board's
            return CliError("--board", "the board refused it: %s" % e)
        # the host-side check (the board's own code)
        return CliError("", "%s: %s" % (_source(args), e))

    if args.clear:
        with connected_board(args, refused=refused) as b:
            removed = clear_boot(b)
            print("%s %s on %s: at power-up the board plays its default (the study's split "
                  "screen, on the board file its firmware picks)"
                  % ("removed" if removed else "there was no", BOOT_FILE, b.port))
        return EXIT_OK
    # the board file: --board, else the one running (stopped, --board must say)
    with running_board(args, "--board NAME says which board file to start at power-up",
                       stopped_ok=bool(args.board), refused=refused) as (b, st):
        running = st.get("running")
        name = cast(str, args.board or st.get("board"))    # stopped: args.board (above)
        if running and name == st.get("board"):
            display = st["display"]
        else:                                   # the named board file, as the board reads it
            display = board_display(b, name)
        if len(scenes) > 1 and b.firmware["implementation"] == "circuitpython":
            # its display is texel.app.serve()'s paced loop: no main loop for a button
            raise CliError("FILE", "a playlist needs a board with a timer interrupt; "
                                   "CircuitPython's display is a paced loop, so its button "
                                   "would never be read: give one FILE (docs/kit.md)")
        if args.current:                        # the scene playing (after --board's check)
            if not running:
                raise not_running(b.port)
            scene = b.scene_source()
        config = boot_config(name, scene, display, scenes[1:], _playlist_refused)
        size = write_boot(b, config)
    desc = config["scene"]
    print("power-up scene of %s: board %s, %s (%d region%s); %s bytes in %s"
          % (b.port, name, repr(desc["name"]) if desc.get("name") else _source(args),
             len(desc["regions"]), "" if len(desc["regions"]) == 1 else "s",
             format(size, ","), BOOT_FILE))
    if "then" in config:
        print("playlist of %d scenes (%s): the board's button steps it, its LED blinks the "
              "scene's number (docs/kit.md)" % (1 + len(config["then"]), ", ".join(args.file)))
    return EXIT_OK


def _playlist_refused(i: int, e: ValueError) -> CliError:
    return CliError("FILE", "scene %d of the playlist: %s" % (i + 1, e))


def _source(args: argparse.Namespace) -> str:
    if args.current:
        return "the scene playing now"
    return "stdin" if args.file[0] == "-" else args.file[0]


# --- pin ------------------------------------------------------------------------------

def cmd_scene_pin(args: argparse.Namespace) -> int:
    from pathlib import Path

    plans = []
    for f in args.files:                        # every file read and checked before any write
        if not Path(f).is_file():
            raise CliError("FILE", "%s: no such file (pin changes scene files; a shipped "
                           "scene says its format already)" % f)
        scene = read_scene_file(f, "FILE")
        try:
            pinned, count, said = pin_formats(scene, args.v)
        except ValueError as e:
            raise CliError("FILE", "%s: %s" % (f, e)) from None
        plans.append((f, pinned, count, said))
    changed = 0
    for f, pinned, count, said in plans:
        if not count:
            print("%s: nothing to pin (%d texel texture%s, each says its format)"
                  % (f, said, "" if said == 1 else "s"))
            continue
        changed += 1
        what = "%d texel texture%s without \"v\"" % (count, "" if count == 1 else "s")
        if args.check:
            print("%s: would pin %s to format %d" % (f, what, args.v))
            continue
        text = scene_json(pinned)
        write_output("FILE", f, lambda f=f, text=text: write_atomic(f, text))
        print("%s: pinned %s to format %d (\"v\": %d)" % (f, what, args.v, args.v))
    return EXIT_FAIL if args.check and changed else EXIT_OK


# --- the shipped scenes ------------------------------------------------------------

def add_scenes(p: argparse.ArgumentParser) -> None:
    p.description = ("List the example scenes shipped with texelpad: name, what to type "
                     "(texelpad push --scene NAME, texelpad scene boot NAME) and the first "
                     "line of their notes.")
    p.add_argument("--json", action="store_true",
                   help="print them as JSON: [{\"stem\", \"name\", \"notes\"}]")
    p.set_defaults(func=cmd_scenes)


def cmd_scenes(args: argparse.Namespace) -> int:
    rows = []
    for stem, f in shipped_scenes().items():
        try:
            scene = json.loads(f.read_text(encoding="utf-8"))
        except (OSError, ValueError) as e:
            raise CliError("", "shipped scene %s cannot be read: %s" % (stem, e), EXIT_FAIL)
        rows.append({"stem": stem, "name": scene.get("name", stem),
                     "notes": scene.get("notes", "")})
    if args.json:
        print(json.dumps(rows, indent=1))
        return EXIT_OK
    ws = max([len(r["stem"]) for r in rows] + [4])
    wn = max([len(r["name"]) for r in rows] + [4])
    print("%-*s  %-*s  %s" % (ws, "SCENE", wn, "NAME", "NOTES"))
    for r in rows:
        first = (r["notes"].splitlines() or [""])[0]
        print("%-*s  %-*s  %s" % (ws, r["stem"], wn, r["name"], first))
    print("(texelpad push --scene NAME plays one; texelpad scene boot NAME plays it at power-up)")
    return EXIT_OK
