"""`texelpad lab`: the study protocols in the browser (web/server.py), on a board
(--port) or the virtual board; `lab export` (study/export.py) and `lab describe
CONFIG` (study/describe.py: a study's trial list, no board). Binds
127.0.0.1 only; the URL is the first line it prints. Runs until Ctrl-C,
SIGTERM or SIGHUP.

One server per data folder (texelpad.study.session.DataLock): a second one
is refused, naming the process that holds it. Without --http-port the lab
serves on the port of the folder's last run (so a participant's open page
finds it again after a crash), or a free one when that is taken. --board is
checked on the board at startup."""
from __future__ import annotations

import argparse
import socket
import sys
import webbrowser

from .errors import EXIT_FAIL, EXIT_OK, CliError, cut_repr, to_stderr


def add_lab(p: argparse.ArgumentParser) -> None:
    p.add_argument("action", nargs="?", choices=("serve", "export", "describe"),
                   default="serve",
                   help="serve (default); export: every session under --data as tidy CSV, "
                        "one summary figure per session and the papers' study figures into "
                        "--out; describe CONFIG: the study's full trial list (what plays "
                        "where, the order, the seeds) before anyone runs it")
    p.add_argument("target", nargs="?", metavar="CONFIG",
                   help="describe: a shipped or --configs config's name, or a config .json "
                        "file")
    p.add_argument("--seed", type=int, default=None, metavar="N",
                   help="describe: the session seed to describe (default: the config's; a "
                        "config without one has its seed drawn when a session starts, and "
                        "seed 0 is described)")
    p.add_argument("--json", action="store_true",
                   help="describe: print the description as JSON (default: a table)")
    p.add_argument("--display", default=None, metavar="POSITIONS[,DX_UM]",
                   help="describe: the board's display (default: the TPaD's 19200,5.3)")
    p.add_argument("--out", default="lab-export", metavar="DIR",
                   help="export: the folder for sessions.csv and the figures (default: "
                        "./lab-export)")
    p.description = ("Serve texelpad lab on http://127.0.0.1:PORT (this machine only): the "
                    "papers' protocols (free exploration, quantization test, "
                    "pursuit vector, texel-length staircase, texel parameter mapping, preference "
                    "search) driving one board, every answer written to the "
                    "session's file as it is given. Without --port it runs on the virtual "
                    "board. The URL is the first line printed. `texelpad lab describe "
                    "CONFIG` prints a study's full trial list without a board; `texelpad lab "
                    "export` writes the data folder's CSV and figures.")
    p.add_argument("--port", help="the board's serial port (default: the virtual board)")
    p.add_argument("--board", help="board file to start when texelpad is not running there")
    p.add_argument("--data", default="lab-data", metavar="DIR",
                   help="the sessions folder (default: ./lab-data)")
    p.add_argument("--configs", metavar="DIR",
                   help="a folder of your own study configs (*.json) beside the shipped ones")
    p.add_argument("--brushes", metavar="DIR",
                   help="the scene editor's brush files (default: DATA/brushes)")
    p.add_argument("--http-port", type=int, default=None, metavar="N",
                   help="the web server's port on 127.0.0.1 (default: the data folder's last "
                        "one, else a free one; 0: a free one)")
    p.add_argument("--open", action="store_true", help="open the page in the browser")
    p.set_defaults(func=cmd_lab)


def cmd_lab(args: argparse.Namespace) -> int:
    if args.action == "describe":
        return _describe(args)
    if args.target is not None:
        raise CliError("CONFIG", "only describe takes a config (got %s)" % cut_repr(args.target))
    for flag, given in (("--seed", args.seed is not None), ("--json", args.json),
                        ("--display", args.display is not None)):
        if given:
            raise CliError(flag, "only lab describe takes it")
    if args.action == "export":
        return _export(args)
    if args.http_port is not None and not 0 <= args.http_port <= 65535:
        raise CliError("--http-port", "expected 0 .. 65535, got %d" % args.http_port)
    import uvicorn

    from ..sim.virtual import open_virtual, stop_on_signals
    from ..study import configs as C
    from ..study.session import DataLock, SessionError
    from ..web.owner import BoardLost, BoardOwner
    from ..web.server import Lab, make_app
    try:
        C.available(args.configs)           # a broken --configs folder: said before anything
    except ValueError as e:
        raise CliError("--configs", str(e)) from None
    lock = DataLock(args.data)
    try:
        lock.acquire()                      # one server per data folder
    except SessionError as e:
        raise CliError("--data", str(e), EXIT_FAIL) from None
    try:
        sock = _bind(args.http_port, lock.previous.get("http_port"))
        port = sock.getsockname()[1]
        lock.update(http_port=port)
        url = "http://127.0.0.1:%d/" % port
        with stop_on_signals():
            vb = None
            try:
                if args.port is None:
                    to_stderr("lab: starting the virtual board")
                    vb = open_virtual(source=True)
                    owner = BoardOwner(vb.port, args.board or "virtual", realtime=True)
                else:
                    owner = BoardOwner(args.port, args.board)
                if args.board:
                    try:
                        owner.check_board_name()
                    except BoardLost as e:      # (said on the pages too; it may come back)
                        to_stderr("lab: could not check --board %s: %s" % (args.board, e))
                    except ValueError as e:
                        owner.close()
                        raise CliError("--board", str(e)) from None
                try:
                    lab = Lab(owner, args.data, args.configs, data_lock=lock)
                    if args.brushes:
                        lab.brushes = args.brushes
                except ValueError as e:
                    raise CliError("--configs", str(e)) from None
                app = make_app(lab)
                print(url, flush=True)
                if args.open:
                    webbrowser.open(url)
                # a request still running at shutdown gets a few seconds, then
                # the server stops anyway (a client that stalls cannot keep it up)
                server = _Server(uvicorn.Config(app, log_level="warning", lifespan="off",
                                                timeout_graceful_shutdown=3))
                server.run(sockets=[sock])
                lab.stop_recording()        # (before the owner closes: it would reconnect)
                owner.close()
            except KeyboardInterrupt:
                pass
            finally:
                sock.close()
                if vb is not None:
                    vb.stop()
    finally:
        lock.release()
    sys.stdout.flush()
    return EXIT_OK


def _server_class() -> type:
    import asyncio

    import uvicorn

    from ..web.api import stop_reading

    class Server(uvicorn.Server):
        """uvicorn's server, which on Ctrl-C / SIGTERM also ends the request
        bodies still arriving (web.api.stop_reading: a client that stalls
        gets 503 at once instead of holding the shutdown until uvicorn's
        graceful timeout cancels it with a traceback)."""
        loop = None

        async def serve(self, sockets=None):
            self.loop = asyncio.get_running_loop()
            await super().serve(sockets)

        def handle_exit(self, sig, frame):
            super().handle_exit(sig, frame)
            if self.loop is not None:
                self.loop.call_soon_threadsafe(stop_reading)
    return Server


def _Server(config):                # noqa: N802 - a class made when uvicorn is imported
    return _server_class()(config)


def _bind(asked: int | None, last: object) -> socket.socket:
    """A socket on 127.0.0.1 (never another interface): the port asked; else
    the data folder's last one when it is free (a participant's open page
    finds the lab there again after a crash); else a free one."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        if asked is not None:
            try:
                sock.bind(("127.0.0.1", asked))
            except OSError as e:
                raise CliError("--http-port", "cannot serve on 127.0.0.1:%d: %s"
                               % (asked, e.strerror or e), EXIT_FAIL) from None
            return sock
        if isinstance(last, int) and not isinstance(last, bool) and 0 < last <= 65535:
            try:
                sock.bind(("127.0.0.1", last))
                return sock
            except OSError as e:
                to_stderr("lab: the last port of this data folder, %d, is taken (%s): serving "
                          "on another one" % (last, e.strerror or e))
        sock.bind(("127.0.0.1", 0))
        return sock
    except BaseException:
        sock.close()
        raise


def _export(args: argparse.Namespace) -> int:
    """Every session that can be exported is; a broken one is named with the
    reason on stderr (exit 1, the rest written)."""
    from ..study.export import export
    from ..study.session import SessionError
    try:
        res = export(args.data, args.out)
    except (OSError, SessionError) as e:
        raise CliError("--data", str(e), EXIT_FAIL) from None
    print("wrote %s (%d answers) and %d figures to %s"
          % (res["csv"], res["rows"], len(res["figures"]), args.out))
    if res["study_figures"]:
        print("the papers' figures: %s" % ", ".join(res["study_figures"]))
    for _, why in res["broken"]:
        to_stderr("lab export: left out %s" % why)
    if res["broken"]:
        to_stderr("lab export: %d of %d sessions left out (the rest are exported)"
                  % (len(res["broken"]), res["sessions"]))
        return EXIT_FAIL
    return EXIT_OK


def _describe(args: argparse.Namespace) -> int:
    """The study's trial list (texelpad.study.describe): a table, or JSON."""
    import json

    from ..study.describe import describe, parse_display, render_text
    if not args.target:
        raise CliError("CONFIG", "lab describe needs a config: a shipped or --configs config's "
                                 "name, or a config .json file")
    if args.seed is not None and not 0 <= args.seed < 1 << 31:
        raise CliError("--seed", "expected an int in [0, 2^31), got %d" % args.seed)
    display = None
    if args.display is not None:
        try:
            display = parse_display(args.display)
        except ValueError as e:
            raise CliError("--display", str(e)) from None
    try:
        d = describe(args.target, args.seed, display, args.configs)
    except ValueError as e:             # SessionError: an unknown config, a bad file
        raise CliError("CONFIG", str(e)) from None
    if args.json:
        print(json.dumps(d, indent=1))
    else:
        sys.stdout.write(render_text(d))
    sys.stdout.flush()
    return EXIT_OK
