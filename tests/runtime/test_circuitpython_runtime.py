"""The display runtime for real under CircuitPython 10.2 (the unix build among
../shared/instruments: 30-bit floats, no viper): the pico_cpy board file
against the recording pwmio/analogio fakes (tests/support/fakes), started
with a scene, driven by a scripted finger, pushed to, refused, stopped. And a
format-2 texel scene plays the same samples there as on CPython, position for
position (format 1 would not: its plan is the interpreter's float)."""
from __future__ import annotations

import numpy as np
import pytest

from texel.runtime import scene as S
from texelpad import toolchain

from support import mpy

pytestmark = pytest.mark.instruments

D = {"positions": 19200, "dx_um": 5.3}
V2 = {"kind": "texel", "pitch_db": 13.0, "irregularity_db": -10.0, "seed": 3, "v": 2}
SCENE = {"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": V2},
                     {"start_mm": 50.88, "end_mm": 101.76,
                      "texture": {"kind": "reference", "name": "4sin"}}]}

SCRIPT = r"""
import json, gc
import texel.app as app
from texel.runtime import scene as S
import analogio, pwmio, board
out = {}
st = app.start("pico_cpy", %(scene)r)
out["start"] = [st["port"], st["running"], st["pwm_top"]]
o = pwmio.OUTS[-1]
# the finger held at three ADC readings in the format-2 region: where the
# refresh put it, what it played there and the duty (run_loop turns the
# output off when it returns, so the last refresh's figures come from status)
held = []
for v in (6000, 14000, 25000):
    analogio.script(board.GP26, [v])
    app.run_loop(seconds=0.02)
    s = app.status()
    held.append([v, s["position"], s["amplitude"], s["duty"]])
out["held"] = held
# a refused push leaves the scene playing
try:
    app.push({"regions": [{"start_mm": 0, "end_mm": 10, "texture": dict(%(v2)r, pitch_db=99)}]})
    out["refused"] = None
except ValueError as e:
    out["refused"] = str(e)
out["after_refusal"] = app.status()["scene"]["regions"][0]
st = app.push({"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": dict(%(v2)r, seed=4)}]})
out["pushed"] = [st["pushes"], st["scene"]["regions"][0]["seed"], st["faults"]]
app.run_loop(seconds=0.02)
out["refreshes"] = app.status()["refreshes"] > 0
app.stop()
out["stopped"] = o.duty_cycle
# the format-2 scene's samples at every 7th position, as CircuitPython plays them
sc = S.build(S.validate(%(scene)r, %(d)r), %(d)r)
out["amp"] = [sc.amp(i) for i in range(0, 19200, 7)]
print(json.dumps(out))
"""


@pytest.fixture(scope="module")
def cp():
    exe = toolchain.interpreter("circuitpython")
    if exe is None:
        pytest.skip("CircuitPython is not on this machine (../shared/instruments)")
    code = SCRIPT % {"scene": SCENE, "v2": V2, "d": D}
    return mpy.run_json(code, exe=exe, extra_path=mpy.FAKES, heapsize="4M", timeout=300)


def test_pico_cpy_starts_plays_and_stops_under_circuitpython(cp):
    assert cp["start"] == ["circuitpython", True, 3675]
    # a held finger: the amplitude played is the scene's sample at the
    # position the refresh read, the same as CPython's; duty within the cap
    sc = S.build(S.validate(SCENE, D), D)
    for v, pos, amp, duty in cp["held"]:
        assert 0 < pos < 9600, (v, pos)
        assert amp == sc.amp(pos), (v, pos)
        assert 0 <= duty <= 3676 // 2
    assert len(set(p for _, p, _, _ in cp["held"])) == 3
    assert cp["refreshes"] is True and cp["stopped"] == 0


def test_refused_push_leaves_the_scene_and_a_good_one_plays(cp):
    assert cp["refused"].startswith("regions[0].texture.pitch_db: 99")
    assert cp["after_refusal"]["seed"] == 3 and cp["after_refusal"]["v"] == 2
    assert cp["pushed"] == [2, 4, 0]


def test_format2_scene_plays_the_same_samples_as_on_cpython(cp):
    sc = S.build(S.validate(SCENE, D), D)
    want = [sc.amp(i) for i in range(0, 19200, 7)]
    k = 9600 // 7 + 1                           # the texel region (the reference is float)
    assert cp["amp"][:k] == want[:k]
    assert np.ptp(want[:k]) > 30000             # a texture, not a constant
    # the reference region: CircuitPython's own float, within one unit of 65535
    assert max(abs(a - b) for a, b in zip(cp["amp"][k:], want[k:])) <= 1
