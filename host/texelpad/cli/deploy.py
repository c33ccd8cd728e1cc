"""`texelpad deploy`: the device image onto a board (texelpad.deploy)."""
from __future__ import annotations

import argparse

from .connection import add_port_flags, connected_board
from .errors import EXIT_FAIL, EXIT_OK, CliError, to_stderr
from .progress import ProgressBar


def add_deploy(p: argparse.ArgumentParser) -> None:
    p.description = ("Compile the device image with mpy-cross for the board's own .mpy format "
                    "and architecture (read from the board), compare sha256 hashes with what "
                    "the board holds, and write only the files that changed, each beside its "
                    "old copy then renamed over it; the leftovers of an interrupted deploy "
                    "are completed or removed (hashes decide). Refuses firmware that is too "
                    "old or of another .mpy format, an image that does not fit and paths "
                    "that cannot be written, before anything changes. A playing display is "
                    "stopped while writing and started again on the new image with the "
                    "scene it played (also when the deploy fails: the error says what the "
                    "board holds and what to run). Prints the command to run next. "
                    "mpremote users: mpremote mip install ./package.json, run in a "
                    "texelpad checkout, installs the source package.")
    p.add_argument("--source", action="store_true",
                   help="send the .py sources instead of .mpy (the board compiles them; "
                        "slower imports, more RAM)")
    p.add_argument("--no-main", action="store_true",
                   help="leave /main.py alone (by default it is written: the board then starts "
                        "its default scene at power-up)")
    p.add_argument("--no-maps", action="store_true",
                   help="on a stock Pico: leave out the reference maps of square, triangle and "
                        "sawtooth (115,200 bytes of its filesystem; they are then rendered on "
                        "the board, about 1-1.6 s a full screen instead of ~12 ms read) and "
                        "remove any it holds")
    p.add_argument("--dry-run", action="store_true", help="only say what would be written")
    p.add_argument("--force", action="store_true",
                   help="on the texelpad firmware: rewrite its ROMFS partition with this "
                        "texelpad's code in it (run instead of the frozen copy), even when it "
                        "holds what it should")
    add_port_flags(p, "the one board plugged in")
    p.set_defaults(func=cmd_deploy)


def cmd_deploy(args: argparse.Namespace) -> int:
    from ..deploy.install import deploy
    from ..image import ImageError
    bar = ProgressBar()
    with connected_board(args, check=False, import_image=False) as b:
        try:
            rep = deploy(b, source=args.source, include_main=not args.no_main,
                         dry_run=args.dry_run, progress=lambda m: to_stderr("deploy: " + m),
                         bar=bar, force=args.force, maps=not args.no_maps)
        except ImageError as e:
            raise CliError("", str(e), EXIT_FAIL) from None
        finally:
            bar.end()
    if rep.get("form") == "romfs":          # the texelpad firmware (deploy/romfs_install.py)
        print("%s %s (texelpad firmware, board %s): ROMFS partition %s (%s bytes, %s), in %.2f s%s"
              % ("would deploy to" if args.dry_run else "deployed to", b.port, rep["board"],
                 "rewritten" if rep["written"] else "already holds this texelpad",
                 format(rep["image_bytes"], ","),
                 "data and this texelpad's code" if rep["code_in_romfs"] else
                 "data; the code is the firmware's, frozen", rep["seconds"],
                 "; restarted %s with its scene" % rep["restarted"] if rep["restarted"] else ""))
        if not args.dry_run:
            print("next: texelpad demo --port %s" % b.port)
        return EXIT_OK
    rep_fixed = rep["repaired"]
    print("%s %s: %d of %d files written (%s bytes), %d unchanged, %d removed%s, in %.2f s%s" % (
        "would deploy to" if args.dry_run else "deployed to", b.port, rep["written"],
        rep["files"], format(rep["bytes_written"], ","), rep["unchanged"], len(rep["removed"]),
        "; %s an interrupted deploy (%d .new file%s completed, %d removed)" % (
            "would repair" if args.dry_run else "repaired", len(rep_fixed["completed"]), "" if len(rep_fixed["completed"]) == 1 else "s",
            len(rep_fixed["removed"])) if rep_fixed["completed"] or rep_fixed["removed"] else "",
        rep["seconds"], "; restarted %s with its scene" % rep["restarted"]
        if rep["restarted"] else ""))
    if not args.dry_run:
        print(next_step(b.port, rep))
    return EXIT_OK


def next_step(port: str, rep: dict) -> str:
    """What to run after a deploy: the demo, with the board file to start
    when nothing plays (the shipped boards of this firmware's port)."""
    if rep.get("playing"):
        return "next: texelpad demo --port %s   (texelpad plays %s on it)" % (port, rep["playing"])
    names = rep.get("boards") or []
    if not names:
        return ("next: texelpad demo --port %s --board NAME   (NAME: your board file, "
                "/boards/NAME.json on the board)" % port)
    family = rep.get("board_port") or "this"
    text = "next: texelpad demo --port %s --board %s" % (port, names[0])
    if len(names) > 1:
        text += ("   (board files for %s firmware: %s; use the one wired like your board, or "
                 "your own /boards/NAME.json)" % (family, ", ".join(names)))
    else:
        text += "   (the board file for %s firmware)" % family
    if rep.get("main"):
        text += "; after a reset /main.py starts texelpad by itself"
    return text
