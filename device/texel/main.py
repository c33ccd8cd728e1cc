# Power-up: start texelpad's default scene on this board, so a plate plays
# something the moment it is plugged in; the REPL stays free for the host.
# This is the board's /main.py: `texelpad deploy` writes it there (not under
# /lib/texel). It lives in the package so that an installed texelpad (a
# wheel) carries it; it is never imported (importing it would start the
# display).
# Board and scene come from /texelpad.json if present, e.g.
#   {"board": "pico_bridge", "scene": {"regions": [...]}}
# otherwise the board is the port's own (texel.compat.PORT_TABLE: the firmware's
# board, else its port's default board) and the scene is the study's split
# screen (texel.app.DEFAULT_SCENE).


def _config():
    """/texelpad.json (texel.app.CONFIG: `texelpad scene boot` writes it,
    atomically), or {}."""
    try:
        import json
        from texel.app import CONFIG
        with open(CONFIG) as f:
            cfg = json.loads(f.read())      # (json.load reads a byte at a time)
        return cfg if isinstance(cfg, dict) else {}
    except (OSError, ValueError, MemoryError):    # MemoryError: the default plays
        return {}


def main():
    """Start the display; returns the playlist the button steps (the scene
    playing first), or None. main's frame, and the config with it, is gone
    while the kit runs: only the playlist stays on the heap."""
    try:
        from texel import compat
    except Exception as e:          # no image, or a broken one: the REPL stays free
        print("texelpad: not started:", repr(e))
        return
    if compat.PORT == "rp2":
        try:                        # a refresh interrupt a soft reset left armed
            from texel.hw.rp2 import clear_stale_tick
            clear_stale_tick()
        except Exception as e:
            print("texelpad: could not check the refresh interrupt:", repr(e))
    try:
        import texel.app
        cfg = _config()
        board = cfg.get("board") or texel.app.default_board(config=False)
        then = cfg.get("then")                  # the playlist after the first scene
        texel.app.start(board, cfg.get("scene"), report=False)
        st = texel.app.status(False)    # no full collection: the REPL answers sooner
        print("texelpad: playing on %s (%s refreshes/s)" % (st.get("board"), st.get("refresh_hz")))
        if st.get("refresh_mode") == "loop":      # no timer IRQ: this loop is the display,
            texel.app.serve()                     # and it answers the host (texel/serve.py)
            return
    except Exception as e:          # never brick the REPL: report and stay off
        print("texelpad: not started:", repr(e))
        return
    if isinstance(then, list) and then and "scene" in cfg:
        return [cfg["scene"]] + then
    return None


def _kit(playlist):
    """The classroom kit (texel/kit.py): a playlist the button steps, until
    a Ctrl-C (a laptop's texelpad or mpremote) hands the board to the REPL
    with the scene playing."""
    if playlist is None:
        return
    try:
        import texel.kit
        print("texelpad: a playlist of %d scenes: the button steps it; Ctrl-C for the REPL"
              % len(playlist))
        texel.kit.run(playlist)
    except Exception as e:          # the scene plays on; only the stepping is off
        print("texelpad: the playlist does not step:", repr(e))


_kit(main())
