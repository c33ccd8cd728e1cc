"""A swap imports nothing per array it zeroes (texel.runtime.refresh_fast._zero): an import
statement inside _zero, run for each of a swap's 3-40 arrays, took 70-120 us each on the
emulated Pico's firmware (+0.29 ms a swap) and 1.5-3.6 ms a swap on a stock Pico
(bench/firmware.py, swap_us). The MicroPython unix port playing the virtual board, every
import statement counted through builtins.__import__ while scenes are pushed."""
from __future__ import annotations

from support import mpy

SCRIPT = r"""
import json, builtins
import texel.app as app
from texel.runtime import refresh_fast
A = {"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": {"kind": "constant", "level": 0.25}},
                 {"start_mm": 50.88, "end_mm": 101.76, "texture": {"kind": "texel",
                  "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7}}]}
B = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {"kind": "reference",
                  "name": "2sin"}}]}
app.start("virtual", A, record=64)
app.push(B)
app.push(A)                     # every module a swap needs is loaded, _zero's helper too
seen = []
_imp = builtins.__import__
def count(name, g=None, *rest):
    if g is not None and g.get("__name__") == refresh_fast.__name__:
        seen.append(name)
    return _imp(name, g, *rest)
builtins.__import__ = count
swaps = 0
try:
    for s in (B, A, B, A):
        app.push(s)
        swaps += 1
finally:
    builtins.__import__ = _imp
print(json.dumps({"swaps": swaps, "fast": app._rt.mode, "imports": seen}))
"""


def test_a_swap_runs_no_import_statement_in_the_refresh():
    res = mpy.run_json(SCRIPT)
    assert res["swaps"] == 4
    assert res["fast"].startswith("viper"), res      # the fused refresh: refresh_fast swaps
    assert res["imports"] == [], res
