"""`texelpad lab`: the study protocols in the browser (web/server.py), on a board
(--port) or the virtual board. Binds 127.0.0.1 only; the URL is the first
line it prints. Runs until Ctrl-C, SIGTERM or SIGHUP."""
from __future__ import annotations

import argparse
import socket
import sys
import webbrowser

from .common import EXIT_FAIL, EXIT_OK, CliError, _stderr


def add_lab(p: argparse.ArgumentParser) -> None:
    p.add_argument("action", nargs="?", choices=("serve", "export"), default="serve",
                   help="serve (default) or export: every session under --data as tidy CSV "
                        "and one summary figure per session into --out")
    p.add_argument("--out", default="lab-export", metavar="DIR",
                   help="export: the folder for sessions.csv and the figures (default: "
                        "./lab-export)")
    p.description = ("Serve texelpad lab on http://127.0.0.1:PORT (this machine only): the "
                    "papers' protocols (free exploration, quantization test, "
                    "pursuit vector, texel-length staircase, preference search) driving one board, every answer written to the "
                    "session's file as it is given. Without --port it runs on the virtual "
                    "board. The URL is the first line printed.")
    p.add_argument("--port", help="the board's serial port (default: the virtual board)")
    p.add_argument("--board", help="board file to start when texelpad is not running there")
    p.add_argument("--data", default="lab-data", metavar="DIR",
                   help="the sessions folder (default: ./lab-data)")
    p.add_argument("--configs", metavar="DIR",
                   help="a folder of your own study configs (*.json) beside the shipped ones")
    p.add_argument("--brushes", metavar="DIR",
                   help="the scene editor's brush files (default: DATA/brushes)")
    p.add_argument("--http-port", type=int, default=0, metavar="N",
                   help="the web server's port on 127.0.0.1 (default: a free one)")
    p.add_argument("--open", action="store_true", help="open the page in the browser")
    p.set_defaults(func=cmd_lab)


def cmd_lab(args: argparse.Namespace) -> int:
    if args.action == "export":
        from ..study.export import export
        from ..study.session import SessionError
        try:
            res = export(args.data, args.out)
        except (OSError, SessionError) as e:
            raise CliError("--data", str(e), EXIT_FAIL) from None
        print("wrote %s (%d answers) and %d figures to %s"
              % (res["csv"], res["rows"], len(res["figures"]), args.out))
        return EXIT_OK
    import uvicorn

    from ..link.virtual import open_virtual, stop_on_signals
    from ..web.owner import BoardOwner
    from ..web.server import Lab, make_app
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind(("127.0.0.1", args.http_port))        # never another interface
    url = "http://127.0.0.1:%d/" % sock.getsockname()[1]
    with stop_on_signals():
        vb = None
        try:
            if args.port is None:
                _stderr("lab: starting the virtual board")
                vb = open_virtual(source=True)
                owner = BoardOwner(vb.port, args.board or "virtual", realtime=True)
            else:
                owner = BoardOwner(args.port, args.board)
            try:
                lab = Lab(owner, args.data, args.configs)
                if args.brushes:
                    lab.brushes = args.brushes
            except ValueError as e:
                raise CliError("--configs", str(e)) from None
            app = make_app(lab)
            print(url, flush=True)
            if args.open:
                webbrowser.open(url)
            server = uvicorn.Server(uvicorn.Config(app, log_level="warning", lifespan="off"))
            server.run(sockets=[sock])
            owner.close()
        except KeyboardInterrupt:
            pass
        finally:
            sock.close()
            if vb is not None:
                vb.stop()
    sys.stdout.flush()
    return EXIT_OK
