"""`texelpad virtual`: a virtual board on a pty until Ctrl-C."""
from __future__ import annotations

import argparse
import time

from ..link.transport import LinkError
from ..link.virtual import open_virtual
from .common import EXIT_FAIL, EXIT_OK, CliError, _fail, _stderr, positive_float


def add_virtual(p: argparse.ArgumentParser) -> None:
    p.description = ("Start the device image under the MicroPython unix port on a "
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

