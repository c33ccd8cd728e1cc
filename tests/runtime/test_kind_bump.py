"""Region kind "bump" (device/texel/runtime/kinds/bump.py): a virtual bump or
edge felt through friction. Its checks and canonical form, its map against
the definition written here independently with numpy (the surface h and a
numerical derivative, not the module's closed forms), the shape of what a
finger meets, sharing on rebuild, status words and labels, and the same map
on the device interpreters (the MicroPython unix port, the float32 ulab
build, CircuitPython's 30-bit floats) within 1 u16 of CPython's binary64."""
from __future__ import annotations

import numpy as np
import pytest

from texel.runtime import kinds, scene as S
from texelpad import toolchain

from support import mpy

D = {"positions": 19200, "dx_um": 5.3}


def _scene(tex, start=0.0, end=20.0):
    return {"regions": [{"start_mm": start, "end_mm": end, "texture": tex}]}


def _map(tex, start=0.0, end=20.0, display=D):
    sc = S.build(S.validate(_scene(tex, start, end), display), display)
    chunks = sc.buffers()[0]                # 1 KB chunks (kinds.K_CHUNK)
    return np.concatenate([np.frombuffer(c, dtype=np.uint16) for c in chunks]).astype(np.int64)


def _reference(tex, n, dx_um):
    """The definition: h(x) on a fine grid, g = |h'| / max |h'| by central
    differences, amplitude level * (1 - height * g)."""
    w = tex["width_mm"]
    x = ((np.arange(n) + 0.5) - tex["at"] * n) * dx_um / 1000.0     # mm from the centre

    def h(x):
        if tex["shape"] == "gaussian":
            s = w / 4.0
            return np.exp(-x * x / (2 * s * s))
        if tex["shape"] == "cosine":
            return np.where(np.abs(x) < w / 2, (1 + np.cos(2 * np.pi * x / w)) / 2, 0.0)
        return np.clip(np.where(np.abs(x) < w / 2, (1 - np.cos(np.pi * (x / w + 0.5))) / 2,
                                (x > 0).astype(float)), 0, 1)
    e = w * 1e-6
    slope = np.abs(h(x + e) - h(x - e)) / (2 * e)
    fine = np.linspace(-w, w, 200001)
    top = np.max(np.abs(np.gradient(h(fine), fine)))
    g = slope / top
    return np.floor(tex["level"] * (1 - tex["height"] * g) * 65535 + 0.5)


# --- checks -------------------------------------------------------------------------
def test_defaults_fill_the_canonical_texture():
    c = S.validate(_scene({"kind": "bump"}), D)
    assert c["regions"][0]["texture"] == {"kind": "bump", "shape": "gaussian", "width_mm": 2.0,
                                          "height": 1.0, "at": 0.5, "level": 1.0}
    assert S.validate(c, D) == c


@pytest.mark.parametrize("tex, msg", [
    ({"shape": "square"}, "regions[0].texture.shape: expected one of gaussian, cosine, edge, "
                          "got str 'square'"),
    ({"width_mm": 0}, "regions[0].texture.width_mm: 0 is out of range [0.01, 1000.0]"),
    ({"height": 1.5}, "regions[0].texture.height: 1.5 is out of range [0.0, 1.0]"),
    ({"at": float("nan")}, "regions[0].texture.at: nan is not finite (allowed [0.0, 1.0])"),
    ({"level": "1"}, "regions[0].texture.level: expected a number in [0.0, 1.0], got str '1'"),
    ({"wide": 3}, "regions[0].texture: unknown key 'wide' (allowed: kind, shape, width_mm, "
                  "height, at, level)"),
])
def test_bad_bumps_are_refused_with_the_path(tex, msg):
    with pytest.raises(ValueError) as ei:
        S.validate(_scene(dict({"kind": "bump"}, **tex)), D)
    assert str(ei.value) == msg


# --- the map ------------------------------------------------------------------------
@pytest.mark.parametrize("shape", ["gaussian", "cosine", "edge"])
@pytest.mark.parametrize("width, height, at, level", [
    (2.0, 1.0, 0.5, 1.0), (4.0, 0.6, 0.3, 0.8), (0.05, 1.0, 0.5, 1.0),    # 9 positions wide
    (30.0, 0.5, 0.9, 0.5),                                                # wider than the region
])
def test_the_map_is_the_definition_within_one_u16(shape, width, height, at, level):
    tex = S.validate(_scene({"kind": "bump", "shape": shape, "width_mm": width, "height": height,
                             "at": at, "level": level}), D)["regions"][0]["texture"]
    got = _map(tex)
    want = _reference(tex, len(got), D["dx_um"])
    # 1 u16: the rounding of a value the two compute to ~1e-9 apart (the
    # reference's derivative is numerical: relative error ~1e-8 of 65535)
    assert np.max(np.abs(got - want)) <= 1


def test_what_a_finger_meets():
    flat = 65535
    g = _map({"kind": "bump", "shape": "gaussian", "width_mm": 4.0})
    n = len(g)
    assert g[0] == g[-1] == flat                                # flat far from the bump
    assert np.array_equal(g, g[::-1])                           # at 0.5: symmetric
    assert g[n // 2] == g[n // 2 - 1] > flat - 300              # its top: flat again (0.3 %)
    def lows(m):            # the low points: runs below a tenth of the flat level
        low = np.flatnonzero(m < 0.1 * m.max())
        runs = np.split(low, np.flatnonzero(np.diff(low) > 1) + 1)
        return [int(r[np.argmin(m[r])]) for r in runs if len(r)]
    ridges = lows(g)
    assert len(ridges) == 2 and g.min() <= 1                    # two flanks, full friction there
    s_pos = 4.0 / 4 * 1000 / D["dx_um"]                         # steepest at +-s (188.7 positions)
    assert abs((ridges[1] - ridges[0]) / 2 - s_pos) <= 1
    e = _map({"kind": "bump", "shape": "edge", "width_mm": 4.0, "height": 0.5})
    assert abs(int(e.min()) - 32768) <= 2                       # height 0.5: half the friction
    assert len(lows(np.where(e < 40000, 0, e))) == 1          # one ridge: the edge's slope
    c = _map({"kind": "bump", "shape": "cosine", "width_mm": 4.0, "level": 0.4})
    assert c.max() == round(0.4 * 65535) and np.count_nonzero(c != c[0]) < 4.0 / 0.0053 + 2


def test_a_rebuilt_scene_shares_the_bump_and_status_says_what_it_is():
    tex = {"kind": "bump", "shape": "edge", "width_mm": 3.0}
    scene = {"regions": [{"start_mm": 0, "end_mm": 20, "texture": tex},
                         {"start_mm": 20, "end_mm": 40, "texture": {"kind": "constant", "level": 0.2}}]}
    a = S.build(S.validate(scene, D), D)
    scene["regions"][1]["texture"]["level"] = 0.3
    b = S.build(S.validate(scene, D), D, reuse=a)
    assert b.buffers()[0] is a.buffers()[0]
    d = b.describe()["regions"][0]
    assert d["mode"] == "map" and d["bytes"] == 2 * (d["end"] - d["start"])
    assert max(len(c) for c in b.buffers()[0]) == 512       # no block over 1 KB
    assert kinds.words(d) == "bump edge, 3 mm wide, height 1, at 0.5 of the region, level 1"
    assert kinds.label(d) == "bump edge 3 mm, height 1"
    assert kinds.label_of(b.source["regions"][0]["texture"]) == "bump edge 3 mm, height 1"


# --- on the device interpreters ------------------------------------------------------
DEVICE = r"""
import json
from texel.runtime import scene as S
D = {"positions": 19200, "dx_um": 5.3}
out = []
for tex in %(texs)r:
    sc = S.build(S.validate({"regions": [{"start_mm": 0, "end_mm": 40, "texture": tex}]}, D), D)
    out.append([v for c in sc.buffers()[0] for v in c])
print(json.dumps(out))
"""
TEXS = [{"kind": "bump", "shape": "gaussian", "width_mm": 6.0, "height": 0.9, "at": 0.37},
        {"kind": "bump", "shape": "cosine", "width_mm": 11.0, "level": 0.7},
        {"kind": "bump", "shape": "edge", "width_mm": 0.5, "at": 0.81}]


@pytest.mark.parametrize("name", ["micropython", "micropython-ulab-f32", "circuitpython"])
def test_device_interpreters_render_the_same_map_within_one_u16(name):
    exe = toolchain.interpreter(name)
    if exe is None:
        pytest.skip("%s is not on this machine (../shared/instruments)" % name)
    got = mpy.run_json(DEVICE % {"texs": TEXS}, exe=exe, heapsize="4M", timeout=300)
    for tex, g in zip(TEXS, got):
        want = _map(tex, 0.0, 40.0)
        assert len(g) == len(want) and np.max(np.abs(np.array(g) - want)) <= 1, tex
