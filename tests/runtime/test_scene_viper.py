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


# samples regions play from chunks of 512 (kinds/samples.py fill_chunks: no block above 1 KB):
# from a tuple (viper per chunk, the tile and the stretch resuming mid-region) and from an
# upload's chunks (runs copied for a tile, each chunk's span gathered for a stretch) - the
# same map as the Python loop over one flat buffer, on the hard cases: regions that are not a
# multiple of 512, an upload longer and shorter than the region, 1 value, 1 position, a
# stretch past 32,769 positions (the Python loop's two-step weights) and a shrink
CHUNK_CASES = [  # (m values, fit, n)
    (1, "tile", 1), (1, "stretch", 1000), (5, "tile", 1023), (3, "stretch", 513),
    (700, "tile", 9600), (700, "tile", 600), (1300, "stretch", 9601), (9600, "stretch", 700),
    (4800, "tile", 9600), (513, "stretch", 40000), (19200, "stretch", 19200),
    (2, "stretch", 2), (600, "stretch", 1),
]

CHUNK_CODE = """
import json, random
from array import array
from texel.runtime.kinds import samples as KS
from texel.runtime.upload import Chunks
random.seed(5)
out = []
for m, fit, n in %r:
    vals = tuple(random.getrandbits(16) for _ in range(m))
    flat = array('H', bytes(2 * n))
    KS._fast_fill = False
    KS.fill_samples(vals, fit, n, flat)           # the Python loop, one flat buffer
    KS._fast_fill = None
    up = Chunks(m)
    for i in range(m):
        up[i] = vals[i]
    got = []
    for src in (vals, up):
        for fast in (None, False):                 # viper where it loads, then Python only
            KS._fast_fill = fast
            dest = Chunks(n)
            KS.fill_chunks(src, fit, n, dest.chunks)
            ok = True
            for i in range(n):
                if dest[i] != flat[i]:
                    ok = False
                    break
            got.append(ok)
            got.append(max(len(c) for c in dest.chunks) <= 512)
    KS._fast_fill = None
    out.append(got)
print(json.dumps(out))
"""


@pytest.mark.parametrize("exe", [None, "ulab-f32"])
def test_chunked_samples_maps_are_the_flat_map_value_for_value(exe):
    if exe:
        from texelpad import toolchain
        exe = toolchain.interpreter("micropython-ulab-f32")
        if exe is None:
            pytest.skip("no ../shared/instruments")
    got = mpy.run_json(CHUNK_CODE % (CHUNK_CASES,), exe=exe, timeout=600)
    assert got == [[True] * 8] * len(CHUNK_CASES), list(zip(CHUNK_CASES, got))
