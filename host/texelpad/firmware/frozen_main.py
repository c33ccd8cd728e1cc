# texelpad firmware: what runs at power-up (frozen into the firmware as main.py by
# `texelpad firmware`; MicroPython runs a frozen main.py before looking at the filesystem).
# A /main.py of your own on the board's filesystem runs instead (an empty one gives a bare
# REPL); otherwise texelpad's power-up from the ROMFS partition: /rom/lib/texel/main.mpy
# plays the scene of /texelpad.json (`texelpad scene boot`) on the firmware's board.
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
        print("texelpad: no texelpad in this firmware's ROMFS (%r): texelpad deploy" % (_e,))
del _own
