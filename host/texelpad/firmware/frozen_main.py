# texelpad firmware: what runs at power-up (frozen into the firmware as main.py by
# `texelpad firmware`; MicroPython runs a frozen main.py before looking at the filesystem).
# A /main.py of your own on the board's filesystem runs instead (an empty one gives a bare
# REPL); otherwise texelpad's power-up, texel.main (frozen, or from the ROMFS partition when
# deploy put code there: frozen_boot.py): the scene of /texelpad.json (`texelpad scene boot`)
# on the firmware's board.
import os

try:
    os.stat("/main.py")
    _own = True
except OSError:
    _own = False
if _own:
    with open("/main.py") as _f:
        _code = _f.read()
    exec(_code, {"__name__": "__main__"})
    del _f, _code
else:
    try:
        import texel.main  # noqa: F401  (starts the display)
    except ImportError as _e:
        print("texelpad: texel.main cannot be imported (%r): texelpad deploy" % (_e,))
del _own
