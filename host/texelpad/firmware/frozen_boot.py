# texelpad firmware: what runs at every boot and soft reset (frozen into the firmware as
# boot.py by `texelpad firmware`; MicroPython runs a frozen boot.py before the filesystem's).
# texelpad's code is frozen in the firmware; its data (reference maps, boards) is in the ROMFS
# partition at /rom/lib/texel. When `texelpad deploy` has put a different texelpad's code into
# the ROMFS (/rom/lib/texel/__init__.mpy), that code runs instead of the frozen copy: the frozen
# modules move to the end of sys.path. Then a /boot.py of your own runs (e.g. machine.freq()).
import os
import sys

try:
    os.stat("/rom/lib/texel/__init__.mpy")
    if ".frozen" in sys.path:
        sys.path.remove(".frozen")
        sys.path.append(".frozen")
except OSError:
    pass
try:
    os.stat("/boot.py")
    _own = True
except OSError:
    _own = False
if _own:
    with open("/boot.py") as _f:
        _code = _f.read()
    exec(_code, {"__name__": "__main__"})
    del _f, _code
del _own
