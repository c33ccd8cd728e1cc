# Power-up: start texelpad's default scene on this board, so a plate plays
# something the moment it is plugged in; the REPL stays free for the host.
# This is the board's /main.py: `texelpad deploy` writes it there (not under
# /lib/texel). It lives in the package so that an installed texelpad (a
# wheel) carries it; it is never imported (importing it would start the
# display).
# Board and scene come from /texelpad.json if present, e.g.
#   {"board": "pico_bridge", "scene": {"regions": [...]}}
# otherwise the board is picked from sys.platform and the scene is the
# study's split screen (texel.app.DEFAULT_SCENE).
import sys


# `texelpad scene boot` writes it (atomically: beside the old copy, renamed over).
# The unix port (the virtual board) has the host's filesystem: its "/" is its
# flash folder, the working directory, so the path is relative there (the
# rule of texelpad.deploy.install.on_board).
CONFIG = "texelpad.json" if sys.platform in ("linux", "darwin", "win32") else "/texelpad.json"


def _config():
    try:
        import json
        with open(CONFIG) as f:
            cfg = json.load(f)
        return cfg if isinstance(cfg, dict) else {}
    except (OSError, ValueError):
        return {}


def _firmware_board():
    """The board the texelpad firmware was built for (/rom/firmware.json,
    written by texelpad.firmware.build), or None on stock firmware."""
    try:
        import json
        with open("/rom/firmware.json") as f:
            return json.load(f).get("board")
    except (OSError, ValueError, AttributeError):
        return None


def _board_for_platform():
    p = sys.platform
    if sys.implementation.name == "circuitpython":
        return "pico_cpy"
    if p == "rp2":
        return "pico"
    if p == "pyboard":
        return "pyboard"
    return "virtual"


def main():
    cfg = _config()
    board = cfg.get("board") or _firmware_board() or _board_for_platform()
    if sys.platform == "rp2":
        try:                        # a refresh interrupt a soft reset left armed
            from texel.hw.rp2 import clear_stale_tick
            clear_stale_tick()
        except Exception as e:
            print("texelpad: could not check the refresh interrupt:", repr(e))
    try:
        import texel.app
        texel.app.start(board, cfg.get("scene"), report=False)
        st = texel.app.status(False)    # no full collection: the REPL answers sooner
        print("texelpad: playing on %s (%s refreshes/s)" % (st.get("board"), st.get("refresh_hz")))
        if st.get("refresh_mode") == "loop":      # no timer IRQ: this loop is the display
            texel.app.run_loop()
    except Exception as e:          # never brick the REPL: report and stay off
        print("texelpad: not started:", repr(e))


main()
