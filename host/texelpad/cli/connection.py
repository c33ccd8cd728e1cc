"""The board a command talks to: the --port and --timeout flags, and two
context managers - `connected_board(args)`, the board of --port (or the one
there is), and `running_board(args)`, that board running texelpad (else
one line, exit 1) - within which a failure of the link or a refusal of the
board is one line (link_failure). texelpad.link is the connection itself."""
from __future__ import annotations

import argparse
from contextlib import contextmanager
from typing import Any, Callable, Iterator

from ..link.transport import DeviceError, LinkError
from .errors import EXIT_FAIL, EXIT_USAGE, CliError
from .parsing import positive_float
from .texel_flags import PARAM_FLAGS


def add_port_flags(p: argparse.ArgumentParser, help_none: str) -> None:
    p.add_argument("--port", metavar="PORT",
                   help="the board's serial port (/dev/ttyACM0, COM3, or a virtual board's "
                        "/dev/pts/N); default: %s" % help_none)
    p.add_argument("--timeout", type=positive_float, default=10.0, metavar="S",
                   help="seconds to wait for the board to answer (default 10)")


def link_failure(e: LinkError) -> CliError:
    """A link/board error as a CliError: the board's refusal of what the user
    asked is a usage error (2), the rest a failure (1)."""
    if isinstance(e, DeviceError):
        return CliError("", "the board refused it: %s" % e, EXIT_USAGE)
    return CliError("", str(e), EXIT_FAIL)


START_HINT = "texelpad push --board NAME starts it"


def not_running(port: str, hint: str = START_HINT) -> CliError:
    """texelpad is not running on the board: a state of the world, not a
    bad flag (exit 1), in the same words from every command."""
    return CliError("", "texelpad is not running on %s (%s)" % (port, hint), EXIT_FAIL)


@contextmanager
def connected_board(args: argparse.Namespace, check: bool = True, import_image: bool = True,
                    refused: Callable[[ValueError], CliError] | None = None) -> Iterator[Any]:
    """`with connected_board(args) as b:` the board of --port (no --port:
    the one board there is, a running texelpad virtual included), connected
    (check, import_image: link.board.connect's); closed after the block.
    A LinkError, connecting or in the block, is one line (link_failure);
    with `refused`, a ValueError in the block (a DeviceError too: the board
    refused it) is refused(e) instead - the command names the flag."""
    from ..link.board import connect
    _one_board(args)
    try:
        board = connect(args.port, timeout=args.timeout, check=check, import_image=import_image)
    except LinkError as e:
        raise link_failure(e) from None
    with board:
        try:
            yield board
        except (ValueError, LinkError) as e:
            if refused is not None and isinstance(e, ValueError):
                raise refused(e) from None
            if isinstance(e, LinkError):
                raise link_failure(e) from None
            raise


@contextmanager
def running_board(args: argparse.Namespace, hint: str | Callable[[Any], str] = START_HINT,
                  start: str | None = None, stopped_ok: bool = False,
                  refused: Callable[[ValueError], CliError] | None = None,
                  start_scene: dict[str, Any] | None = None,
                  ) -> Iterator[tuple[Any, dict[str, Any]]]:
    """`with running_board(args) as (b, st):` a connected_board on which
    texelpad runs, and its status. Where it does not: board file `start`
    is started (in real time: a virtual board started from the host plays
    in real time, stepped it would play nothing; other ports ignore it),
    or with `stopped_ok` the board is taken as it is (st says so), or else
    not_running(port, hint) - hint a text or hint(board) - one line, exit 1.
    start_scene: what the start plays (None: the board's default scene)."""
    with connected_board(args, refused=refused) as b:
        st = b.status()
        if not st.get("running") and not stopped_ok:
            if not start:
                raise not_running(b.port, hint(b) if callable(hint) else hint)
            st = b.start(start, start_scene, realtime=True)
        yield b, st


def _one_board(args: argparse.Namespace) -> None:
    """No --port: the one board there is, a running `texelpad virtual`
    included (connect() itself only knows USB boards)."""
    if getattr(args, "port", None) is not None:
        return
    from ..link.transport import ports
    from ..sim.virtual import running_boards
    found = [p["port"] for p in ports()] + [e["port"] + " (virtual)" for e in running_boards()]
    if len(found) > 1:
        raise CliError("--port", "%d boards found (%s): say which with --port"
                       % (len(found), ", ".join(found)), EXIT_FAIL)
    if found:
        args.port = found[0].split(" ")[0]


def refused_scene(e: Exception, from_flags: bool) -> CliError:
    """A refused parameter: name the flag when it came from one."""
    text = str(e)
    if from_flags:
        path, sep, rest = text.partition(": ")
        key = path.rsplit(".", 1)[-1]
        if sep and path.startswith("regions[0].texture.") and key in PARAM_FLAGS:
            return CliError(PARAM_FLAGS[key], rest)
        missing = "missing required key '"
        if path == "regions[0].texture" and rest.startswith(missing):
            key, _, more = rest[len(missing):].partition("'")
            if key in PARAM_FLAGS:
                return CliError(PARAM_FLAGS[key], "required%s" % more)
    prefix = "the board refused it: " if isinstance(e, DeviceError) else ""
    return CliError("--scene" if not from_flags else "", prefix + text)
