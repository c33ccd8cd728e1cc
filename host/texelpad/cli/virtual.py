"""`texelpad virtual`: a virtual board on a pty until Ctrl-C (or SIGTERM, SIGHUP)."""
from __future__ import annotations

import argparse
import time

from ..link.transport import LinkError
from ..link.virtual import open_virtual, stop_on_signals
from .common import EXIT_FAIL, EXIT_OK, CliError, _fail, _stderr, positive_float


def add_virtual(p: argparse.ArgumentParser) -> None:
    p.description = ("Start the device image under the MicroPython unix port on a "
                    "pseudo-terminal, playing the study's split screen in real time, and print "
                    "its serial port as the first line, so texelpad --port, mpremote connect "
                    "PORT resume ..., or any serial tool can talk to it; texelpad ports lists "
                    "it. A soft reset (Ctrl-D, mpremote's default) restarts the interpreter "
                    "on the same port, as on a board. Runs until Ctrl-C, SIGTERM or SIGHUP.")
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
    vb = None
    # SIGTERM/SIGHUP end it as Ctrl-C does: the interpreter killed, the
    # temporary flash and the registry entry removed (also while deploying)
    with stop_on_signals():
        try:
            try:
                vb = open_virtual(args.flash, args.source, not args.no_start, progress)
            except LinkError as e:
                raise _fail(e) from None
            vb.announce()
            print(vb.port, flush=True)
            _stderr("virtual: a virtual board is on %s (flash: %s); Ctrl-C stops it"
                    % (vb.port, vb.flash))
            t_end = None if args.seconds is None else time.monotonic() + args.seconds
            while vb.alive() and (t_end is None or time.monotonic() < t_end):
                time.sleep(0.2)
            if not vb.alive():
                raise CliError("", "the virtual board on %s stopped: %s" % (
                    vb.port, vb.failure or "its supervisor ended"), EXIT_FAIL)
        except KeyboardInterrupt:       # Ctrl-C, SIGTERM, SIGHUP: the normal way to stop it
            pass
        finally:
            if vb is not None:
                vb.stop()
    return EXIT_OK
