"""runtime/scene_viper.py (the samples regions' fill in viper) makes exactly what the Python
loop of runtime/scene.py makes, on the unix port and the float32 ulab build (real viper), over
the hard cases: one value, onto one position, tiles that do not divide the region, stretches
with huge and tiny steps, the largest stretch it takes (32,769 positions) and ramps of every
sign."""
from __future__ import annotations

import pytest

from support import mpy

CASES = [  # (values, fit, n)
    ((7,), "stretch", 1), ((7,), "stretch", 500), ((0, 65535), "stretch", 1),
    ((0, 65535), "stretch", 19200), ((65535, 0), "stretch", 19200),
    ((1, 2, 3), "tile", 1000), ((65535,) * 3 + (0,), "tile", 9601),
    (tuple(range(0, 65536, 129)), "stretch", 333), (tuple(range(0, 65536, 129)), "stretch", 32769),
    ((40000, 3, 65535, 12, 30000), "stretch", 7), ((5, 9), "stretch", 2),
]

CODE = """
import json
from array import array
from texel.runtime import scene, scene_viper
from texel.runtime.kinds import samples as KS
out = []
for vals, fit, n in %r:
    a = array('H', bytes(2 * n)); b = array('H', bytes(2 * n))
    assert scene_viper.fill(tuple(vals), fit, n, a)
    KS._fast_fill = False                    # the Python loop
    KS.fill_samples(tuple(vals), fit, n, b)
    KS._fast_fill = None
    out.append(list(a) == list(b))
print(json.dumps(out))
"""


@pytest.mark.parametrize("exe", [None, "ulab-f32"])
def test_the_viper_fill_is_the_python_loop_value_for_value(exe):
    if exe:
        from texelpad import toolchain
        exe = toolchain.interpreter("micropython-ulab-f32")
        if exe is None:
            pytest.skip("no ../shared/instruments")
    assert mpy.run_json(CODE % (CASES,), exe=exe) == [True] * len(CASES)
