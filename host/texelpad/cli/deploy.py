"""`texelpad deploy`: the device image onto a board (texelpad.deploy)."""
from __future__ import annotations

import argparse

from ..link.transport import LinkError
from .common import EXIT_FAIL, EXIT_OK, CliError, ProgressBar, _connect, _fail, _port_arg, \
    _stderr


def add_deploy(p: argparse.ArgumentParser) -> None:
    p.description = ("Compile the device image with mpy-cross for the board's own .mpy format "
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


def cmd_deploy(args: argparse.Namespace) -> int:
    from ..deploy.install import deploy
    from ..deploy.image import ImageError
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

