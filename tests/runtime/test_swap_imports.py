"""A push runs no import statement once the modules it needs are loaded: MicroPython runs an
import inside a function at every call, 80-120 us on the emulated Pico's firmware and 0.4-1 ms
on a stock Pico (bench/import_cost.py). One inside refresh_fast._zero, run for each of a swap's
3-40 arrays, made a swap +0.29 ms on the firmware and +1.5-3.6 ms on a stock Pico
(bench/firmware.py, swap_us); a reference region's check/store/fill, the chunk helpers,
format 2's grid and status()'s ulab version ran 1-25 more a push. The MicroPython unix port
playing the virtual board, every import statement counted through builtins.__import__."""

from __future__ import annotations

from support import mpy

SCRIPT = r"""
import json, builtins
import texel.app as app
A = {"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": {"kind": "constant", "level": 0.25}},
                 {"start_mm": 50.88, "end_mm": 101.76, "texture": {"kind": "texel",
                  "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7}}]}
B = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {"kind": "reference",
                  "name": "2sin"}}]}
C = {"regions": [{"start_mm": i * 6.36, "end_mm": (i + 1) * 6.36, "texture": {"kind": "texel",
      "pitch_db": -10.0 + i, "irregularity_db": -6.0, "seed": 3 + i}} for i in range(16)]}
D = {"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": {"kind": "reference", "name": "pink"}},
                 {"start_mm": 50.88, "end_mm": 101.76, "texture": {"kind": "samples",
                  "values": [0.1, 0.9, 0.5, 0.3]}}]}
app.start("virtual", A, record=64)
for s in (B, C, D, A):          # every module these scenes need is loaded
    app.push(s)
seen = []
_imp = builtins.__import__
def count(name, g=None, *rest):
    seen.append([name, g.get("__name__") if g is not None else None])
    return _imp(name, g, *rest)
builtins.__import__ = count
pushes = 0
try:
    for s in (B, C, D, A):
        app.push(s)
        pushes += 1
finally:
    builtins.__import__ = _imp
print(json.dumps({"pushes": pushes, "mode": app._rt.mode, "imports": seen}))
"""

_RES: list = []


def _res() -> dict:
    if not _RES:
        _RES.append(mpy.run_json(SCRIPT))
    return _RES[0]


def test_a_swap_runs_no_import_statement_in_the_refresh():
    res = _res()
    assert res["pushes"] == 4
    assert res["mode"].startswith("viper"), res      # the fused refresh: refresh_fast swaps
    assert [m for _name, m in res["imports"] if m == "texel.runtime.refresh_fast"] == [], res


def test_pushes_of_loaded_kinds_run_no_import_statement():
    # a reference, 16 texel regions (format 2's grid), a reference beside samples, a
    # constant beside a texel: app.push's own status() included
    res = _res()
    assert res["pushes"] == 4
    assert res["imports"] == [], res
