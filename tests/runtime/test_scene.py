"""texel.runtime.scene: validation, building and the hard-IRQ amplitude lookup, on
CPython and under the real MicroPython unix port.

- the study's split screen (reference "4sin" left, texel right) plays exactly
  the reference and the texel rendering of the region's length;
- gaps, constants, samples (tile and stretch), idle amplitude;
- memory per scene (printed), constant-only scenes hold no sample buffer,
  max_bytes refused before anything is allocated, a real MemoryError (small
  MicroPython heap) becomes a ValueError and the playing scene is untouched;
- every validation error path, table-driven, with the exact message, the same
  on CPython and MicroPython;
- Scene.amp() allocation-free under micropython.heap_lock() (with controls
  that do raise), timing of the linear scan vs a binary search;
- a hypothesis property (>= 500 cases): validate() returns a canonical dict
  that build() accepts, or raises ValueError - never anything else - and the
  same cases give the same answers under MicroPython.

Figures are printed: run with `pytest -s` to see them.
"""
from __future__ import annotations

import copy
import json
import os
import random
import re
from array import array

import pytest
from hypothesis import given, settings, strategies as st

from support import hyp_profiles, mpy  # noqa: F401 (hyp_profiles: registers the profiles)
import texel
from texel.runtime import scene as S
from texel.runtime.kinds import samples as KS

D = {"positions": 19200, "dx_um": 5.3}
SMALL = {"positions": 2000, "dx_um": 5.3}          # 10.6 mm: quick builds for fuzzing

# Helpers shared by CPython and the MicroPython scripts (exec'd in both), so
# the validation table below is one text evaluated by both interpreters.
HELPERS = r"""
nan = float('nan')
inf = float('inf')
D = {"positions": 19200, "dx_um": 5.3}
REF = {"kind": "reference", "name": "4sin"}
TEX = {"kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7}
def split(right=None, left=None):
    return {"regions": [
        {"start_mm": 0, "end_mm": 50.88, "texture": REF if left is None else left},
        {"start_mm": 50.88, "end_mm": 101.76, "texture": TEX if right is None else right}]}
def tx(**kw):
    d = dict(TEX)
    d.update(kw)
    return d
def drop(d, k):
    d = dict(d)
    del d[k]
    return d
def region(**kw):
    r = {"start_mm": 0, "end_mm": 50.88, "texture": REF}
    r.update(kw)
    return {"regions": [r]}
def one(tex):
    return region(texture=tex)
def with_(d, **kw):
    d = dict(d)
    d.update(kw)
    return d
def put(d, k, v):
    d = dict(d)
    d[k] = v
    return d
"""
_H: dict = {}
exec(HELPERS, _H)
SPLIT = _H["split"]()
TEXEL_RIGHT = {"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7}

TEXEL_ALLOWED = ("kind, pitch_db, irregularity_db, texel_samples, quant_db, seed, gain, v, "
                 "band_limit_cpmm, min_cpmm, phase")
KINDS = "texel, reference, constant, samples, brush, bump"
REF_NAMES = ", ".join(texel.reference_names())

# (id, scene expression, display expression or None (= D), exact message)
ERRORS = [
    # display (the board's)
    ("display-type", "split()", "[19200, 5.3]",
     "display: expected the board's display dict {'positions': ..., 'dx_um': ...}, got list of 2 items"),
    ("display-missing", "split()", "{'positions': 19200}", "display: missing required key 'dx_um'"),
    ("display-positions", "split()", "{'positions': 0, 'dx_um': 5.3}",
     "display.positions: 0 is out of range [1, 1048576]"),
    ("display-dx-nan", "split()", "{'positions': 19200, 'dx_um': nan}",
     "display.dx_um: nan is not finite (allowed [0.001, 1000000.0])"),
    # top level
    ("scene-type", "[1, 2]", None, "scene: expected a dict with 'regions', got list of 2 items"),
    ("scene-str", "'import os'", None, "scene: expected a dict with 'regions', got str 'import os'"),
    ("scene-unknown", "with_(split(), bogus=1)", None,
     "scene: unknown key 'bogus' (allowed: regions, idle_amplitude, name, notes)"),
    ("scene-unknown-nonstr", "{'regions': [], 7: 1}", None,
     "scene: unknown key int 7 (allowed: regions, idle_amplitude, name, notes)"),
    ("scene-unknown-smallest", "with_(split(), zz=1, aa=2, mm=3)", None,
     "scene: unknown key 'aa' (allowed: regions, idle_amplitude, name, notes)"),
    ("scene-unknown-quotes", "put(split(), 'a\"b\\'\\nc', 1)", None,
     "scene: unknown key 'a\"b\\'\\nc' (allowed: regions, idle_amplitude, name, notes)"),
    ("scene-unknown-long", "put(split(), 'x' * 1000, 1)", None,
     "scene: unknown key 'xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx'... (1000 chars) "
     "(allowed: regions, idle_amplitude, name, notes)"),
    ("scene-missing-regions", "{'idle_amplitude': 0}", None,
     "scene: missing required key 'regions' (a list of 1 .. 16 regions)"),
    ("regions-type", "{'regions': 'left'}", None, "regions: expected a list of 1 .. 16 regions, got str 'left'"),
    ("regions-dict", "{'regions': {'a': 1}}", None, "regions: expected a list of 1 .. 16 regions, got dict of 1 keys"),
    ("regions-empty", "{'regions': []}", None, "regions: 0 regions; allowed 1 .. 16"),
    ("regions-too-many", "{'regions': [split()['regions'][0]] * 17}", None, "regions: 17 regions; allowed 1 .. 16"),
    ("regions-huge", "{'regions': [None] * 100000}", None, "regions: 100000 regions; allowed 1 .. 16"),
    ("idle-bool", "with_(split(), idle_amplitude=True)", None,
     "idle_amplitude: expected an int in [0, 65535], got bool True"),
    ("idle-float", "with_(split(), idle_amplitude=1.5)", None,
     "idle_amplitude: expected an int in [0, 65535], got float 1.5"),
    ("idle-range", "with_(split(), idle_amplitude=65536)", None, "idle_amplitude: 65536 is out of range [0, 65535]"),
    ("idle-negative", "with_(split(), idle_amplitude=-1)", None, "idle_amplitude: -1 is out of range [0, 65535]"),
    ("idle-none", "with_(split(), idle_amplitude=None)", None,
     "idle_amplitude: expected an int in [0, 65535], got NoneType None"),
    # regions
    ("region-type", "{'regions': [None]}", None,
     "regions[0]: expected a region dict with 'start_mm', 'end_mm', 'texture', got NoneType None"),
    ("region-type-2", "{'regions': [split()['regions'][0], [0, 5]]}", None,
     "regions[1]: expected a region dict with 'start_mm', 'end_mm', 'texture', got list of 2 items"),
    ("region-unknown", "region(label='left')", None,
     "regions[0]: unknown key 'label' (allowed: start_mm, end_mm, texture)"),
    ("region-unknown-nested", "region(extra={'a': [1, {'b': None}]})", None,
     "regions[0]: unknown key 'extra' (allowed: start_mm, end_mm, texture)"),
    ("region-missing-texture", "{'regions': [{'start_mm': 0, 'end_mm': 5}]}", None,
     "regions[0]: missing required key 'texture'"),
    ("region-missing-start", "{'regions': [{'end_mm': 5, 'texture': REF}]}", None,
     "regions[0]: missing required key 'start_mm'"),
    ("start-str", "region(start_mm='0')", None,
     "regions[0].start_mm: expected a number in [0.0, 101.76], got str '0'"),
    ("start-bool", "region(start_mm=False)", None,
     "regions[0].start_mm: expected a number in [0.0, 101.76], got bool False"),
    ("start-nan", "region(start_mm=nan)", None, "regions[0].start_mm: nan is not finite (allowed [0.0, 101.76])"),
    ("start-negative", "region(start_mm=-1)", None, "regions[0].start_mm: -1 is out of range [0.0, 101.76]"),
    ("start-negative-float", "region(start_mm=-0.001)", None,
     "regions[0].start_mm: -0.001 is out of range [0.0, 101.76]"),
    ("end-beyond", "region(end_mm=102)", None, "regions[0].end_mm: 102 is out of range [0.0, 101.76]"),
    ("end-beyond-half", "region(end_mm=101.7627)", None,
     "regions[0].end_mm: 101.7627 is out of range [0.0, 101.76]"),
    ("end-inf", "region(end_mm=inf)", None, "regions[0].end_mm: inf is not finite (allowed [0.0, 101.76])"),
    ("end-neg-inf", "region(end_mm=-inf)", None, "regions[0].end_mm: -inf is not finite (allowed [0.0, 101.76])"),
    ("end-huge-int", "region(end_mm=10 ** 400)", None,
     "regions[0].end_mm: a huge int (beyond 2^62) is out of range [0.0, 101.76]"),
    ("end-list", "region(end_mm=[1] * 50000)", None,
     "regions[0].end_mm: expected a number in [0.0, 101.76], got list of 50000 items"),
    ("end-not-after", "region(start_mm=5, end_mm=5.0)", None,
     "regions[0].end_mm: 5.0 is not after start_mm 5.0"),
    ("end-before", "region(start_mm=20, end_mm=10)", None,
     "regions[0].end_mm: 10.0 is not after start_mm 20.0"),
    ("rounds-empty", "region(start_mm=10.0, end_mm=10.001)", None,
     "regions[0]: 10.0 .. 10.001 mm rounds to no position (one position is 5.3 um)"),
    ("overlap", "{'regions': [split()['regions'][0], {'start_mm': 40, 'end_mm': 60, 'texture': TEX}]}", None,
     "regions[1]: overlaps regions[0] (positions 7547..11321 and 0..9600)"),
    ("overlap-order", "{'regions': [{'start_mm': 40, 'end_mm': 60, 'texture': TEX}, split()['regions'][0]]}", None,
     "regions[0]: overlaps regions[1] (positions 7547..11321 and 0..9600)"),
    ("overlap-inside", "{'regions': [{'start_mm': 0, 'end_mm': 100, 'texture': REF}, "
     "{'start_mm': 20, 'end_mm': 21, 'texture': {'kind': 'constant', 'level': 1}}]}", None,
     "regions[1]: overlaps regions[0] (positions 3774..3962 and 0..18868)"),
    ("overlap-one-position", "{'regions': [{'start_mm': 0, 'end_mm': 10.6, 'texture': REF}, "
     "{'start_mm': 10.5947, 'end_mm': 20, 'texture': REF}]}", None,
     "regions[1]: overlaps regions[0] (positions 1999..3774 and 0..2000)"),
    # textures
    ("texture-type", "one('texel')", None,
     "regions[0].texture: expected a texture dict with 'kind' (one of: %s), got str 'texel'" % KINDS),
    ("texture-missing-kind", "one({'name': '4sin'})", None,
     "regions[0].texture: missing required key 'kind' (one of: %s)" % KINDS),
    ("kind-unknown", "one({'kind': 'noise'})", None,
     "regions[0].texture.kind: unknown kind 'noise' (one of: %s)" % KINDS),
    ("kind-int", "one({'kind': 1})", None, "regions[0].texture.kind: unknown kind int 1 (one of: %s)" % KINDS),
    ("kind-code", "one({'kind': \"texel'); import os; os.system('rm -rf /')\\n\"})", None,
     "regions[0].texture.kind: unknown kind \"texel'); import os; os.system('rm -rf /'\"... (42 chars) "
     "(one of: %s)" % KINDS),
    ("kind-unicode", "one({'kind': 't\\xebxel\\u20ac\\U0001f600'})", None,
     "regions[0].texture.kind: unknown kind 't\\xebxel\\u20ac\\U0001f600' (one of: %s)" % KINDS),
    # texel
    ("texel-pitch-unicode", "split(right=tx(pitch_db='\\xe96'))", None,
     "regions[1].texture.pitch_db: expected a number in [-20.0, 19.747], got str '\\xe96'"),
    ("texel-pitch-nan", "split(right=tx(pitch_db=nan))", None,
     "regions[1].texture.pitch_db: nan is not finite (allowed [-20.0, 19.747])"),
    ("texel-pitch-range", "split(right=tx(pitch_db=20))", None,
     "regions[1].texture.pitch_db: 20.0 is out of range [-20.0, 19.747]"),
    ("texel-pitch-str", "split(right=tx(pitch_db='6.3'))", None,
     "regions[1].texture.pitch_db: expected a number in [-20.0, 19.747], got str '6.3'"),
    ("texel-pitch-code", "split(right=tx(pitch_db=\"__import__('os')\\n\"))", None,
     "regions[1].texture.pitch_db: expected a number in [-20.0, 19.747], got str \"__import__('os')\\n\""),
    ("texel-pitch-long-str", "split(right=tx(pitch_db='9' * 5000))", None,
     "regions[1].texture.pitch_db: expected a number in [-20.0, 19.747], got str "
     "'9999999999999999999999999999999999999999'... (5000 chars)"),
    ("texel-pitch-list", "split(right=tx(pitch_db=[6.3] * 100000))", None,
     "regions[1].texture.pitch_db: expected a number in [-20.0, 19.747], got list of 100000 items"),
    ("texel-pitch-dict", "split(right=tx(pitch_db={'a': {'b': [nan]}}))", None,
     "regions[1].texture.pitch_db: expected a number in [-20.0, 19.747], got dict of 1 keys"),
    ("texel-pitch-none", "split(right=tx(pitch_db=None))", None,
     "regions[1].texture.pitch_db: None is not allowed (expected a number in [-20.0, 19.747])"),
    ("texel-irr-missing", "split(right=drop(TEX, 'irregularity_db'))", None,
     "regions[1].texture: missing required key 'irregularity_db' (a number in [-30.0, 5.0])"),
    ("texel-pitch-missing", "split(right=drop(TEX, 'pitch_db'))", None,
     "regions[1].texture: missing required key 'pitch_db' (a number in [-20.0, 19.747])"),
    ("texel-seed-bool", "split(right=tx(seed=True))", None,
     "regions[1].texture.seed: expected an int in [0, 4294967295], got bool True"),
    ("texel-seed-float", "split(right=tx(seed=7.0))", None,
     "regions[1].texture.seed: expected an int in [0, 4294967295], got float 7.0"),
    ("texel-seed-huge", "split(right=tx(seed=2 ** 32))", None,
     "regions[1].texture.seed: 4294967296 is out of range [0, 4294967295]"),
    ("texel-seed-huger", "split(right=tx(seed=10 ** 100))", None,
     "regions[1].texture.seed: expected an int in [0, 4294967295], got a huge int (beyond 2^62)"),
    ("texel-samples-zero", "split(right=tx(texel_samples=0))", None,
     "regions[1].texture.texel_samples: 0 is out of range [1, 1048576]"),
    ("texel-gain", "split(right=tx(gain=1.5))", None, "regions[1].texture.gain: 1.5 is out of range [0.0, 1.0]"),
    ("texel-quant-inf", "split(right=tx(quant_db=-inf))", None,
     "regions[1].texture.quant_db: -inf is not finite (allowed [0.0, 20.0])"),
    ("texel-v", "split(right=tx(v=3))", None, "regions[1].texture.v: 3 is out of range [1, 2]"),
    ("texel-band", "split(right=tx(band_limit_cpmm=200))", None,
     "regions[1].texture.band_limit_cpmm: 200.0 is out of range [0.01, 94.33962264150944]"),
    ("texel-length-given", "split(right=tx(length_samples=9600))", None,
     "regions[1].texture.length_samples: set by the region (here 9600 samples); remove it"),
    ("texel-length-given-bad", "split(right=tx(length_samples='x'))", None,
     "regions[1].texture.length_samples: set by the region (here 9600 samples); remove it"),
    ("texel-unknown", "split(right=tx(pitch=6.3))", None,
     "regions[1].texture: unknown key 'pitch' (allowed: %s)" % TEXEL_ALLOWED),
    ("texel-unknown-name", "split(right=tx(name='4sin'))", None,
     "regions[1].texture: unknown key 'name' (allowed: %s)" % TEXEL_ALLOWED),
    # reference
    ("ref-missing-name", "one({'kind': 'reference'})", None,
     "regions[0].texture: missing required key 'name' (one of: %s)" % REF_NAMES),
    ("ref-unknown", "one({'kind': 'reference', 'name': '5sin'})", None,
     "regions[0].texture.name: unknown reference texture '5sin' (known: %s)" % REF_NAMES),
    ("ref-newline", "one({'kind': 'reference', 'name': '4sin\\n'})", None,
     "regions[0].texture.name: unknown reference texture '4sin\\n' (known: %s)" % REF_NAMES),
    ("ref-list", "one({'kind': 'reference', 'name': ['4sin']})", None,
     "regions[0].texture.name: unknown reference texture list of 1 items (known: %s)" % REF_NAMES),
    ("ref-unknown-key", "one({'kind': 'reference', 'name': '4sin', 'length_samples': 9600})", None,
     "regions[0].texture: unknown key 'length_samples' (allowed: kind, name)"),
    # constant
    ("const-missing", "one({'kind': 'constant'})", None,
     "regions[0].texture: missing required key 'level' (a number in [0.0, 1.0])"),
    ("const-range", "one({'kind': 'constant', 'level': 1.5})", None,
     "regions[0].texture.level: 1.5 is out of range [0.0, 1.0]"),
    ("const-int-range", "one({'kind': 'constant', 'level': 2})", None,
     "regions[0].texture.level: 2 is out of range [0.0, 1.0]"),
    ("const-nan", "one({'kind': 'constant', 'level': nan})", None,
     "regions[0].texture.level: nan is not finite (allowed [0.0, 1.0])"),
    ("const-bool", "one({'kind': 'constant', 'level': True})", None,
     "regions[0].texture.level: expected a number in [0.0, 1.0], got bool True"),
    ("const-unknown", "one({'kind': 'constant', 'level': 0.5, 'u16': 3})", None,
     "regions[0].texture: unknown key 'u16' (allowed: kind, level)"),
    # samples
    ("samples-neither", "one({'kind': 'samples'})", None,
     "regions[0].texture: give exactly one of 'values' (numbers 0..1) or 'u16' (ints 0..65535), 19200 at most"),
    ("samples-both", "one({'kind': 'samples', 'values': [0.5], 'u16': [1]})", None,
     "regions[0].texture: give exactly one of 'values' (numbers 0..1) or 'u16' (ints 0..65535), 19200 at most"),
    ("samples-values-type", "one({'kind': 'samples', 'values': 0.5})", None,
     "regions[0].texture.values: expected a list of numbers in [0.0, 1.0], got float 0.5"),
    ("samples-u16-type", "one({'kind': 'samples', 'u16': '1,2,3'})", None,
     "regions[0].texture.u16: expected a list of ints in [0, 65535], got str '1,2,3'"),
    ("samples-empty", "one({'kind': 'samples', 'values': []})", None,
     "regions[0].texture.values: 0 values; allowed 1 .. 19200"),
    ("samples-too-many", "one({'kind': 'samples', 'u16': [0] * 19201})", None,
     "regions[0].texture.u16: 19201 values; allowed 1 .. 19200"),
    ("samples-value-nan", "one({'kind': 'samples', 'values': [0.0, 0.5, 1, nan]})", None,
     "regions[0].texture.values[3]: nan is not finite (allowed [0.0, 1.0])"),
    ("samples-value-range", "one({'kind': 'samples', 'values': [0.0, 1.0000001]})", None,
     "regions[0].texture.values[1]: 1.0000001 is out of range [0.0, 1.0]"),
    ("samples-value-str", "one({'kind': 'samples', 'values': [0.1, '0.2']})", None,
     "regions[0].texture.values[1]: expected a number in [0.0, 1.0], got str '0.2'"),
    ("samples-value-bool", "one({'kind': 'samples', 'values': [True]})", None,
     "regions[0].texture.values[0]: expected a number in [0.0, 1.0], got bool True"),
    ("samples-value-nested", "one({'kind': 'samples', 'values': [0.1, [0.2]]})", None,
     "regions[0].texture.values[1]: expected a number in [0.0, 1.0], got list of 1 items"),
    ("samples-u16-range", "one({'kind': 'samples', 'u16': [0, 65535, 65536]})", None,
     "regions[0].texture.u16[2]: 65536 is out of range [0, 65535]"),
    ("samples-u16-float", "one({'kind': 'samples', 'u16': [1.0]})", None,
     "regions[0].texture.u16[0]: expected an int in [0, 65535], got float 1.0"),
    ("samples-u16-bool", "one({'kind': 'samples', 'u16': [1, False]})", None,
     "regions[0].texture.u16[1]: expected an int in [0, 65535], got bool False"),
    ("samples-u16-huge", "one({'kind': 'samples', 'u16': [1, -10 ** 30]})", None,
     "regions[0].texture.u16[1]: a huge int (beyond 2^62) is out of range [0, 65535]"),
    ("samples-fit", "one({'kind': 'samples', 'u16': [1], 'fit': 'zoom'})", None,
     "regions[0].texture.fit: expected one of tile, stretch, got str 'zoom'"),
    ("samples-fit-none", "one({'kind': 'samples', 'u16': [1], 'fit': None})", None,
     "regions[0].texture.fit: expected one of tile, stretch, got NoneType None"),
    ("samples-unknown", "one({'kind': 'samples', 'u16': [1], 'repeat': 2})", None,
     "regions[0].texture: unknown key 'repeat' (allowed: kind, values, u16, fit)"),
    ("samples-unknown-first", "one({'kind': 'samples', 'u16': [1], 1.5: 2, None: 3})", None,
     "regions[0].texture: unknown key NoneType None (allowed: kind, values, u16, fit)"),
]


def _eval(expr):
    return eval(expr, dict(_H))


@pytest.mark.parametrize("case", ERRORS, ids=[c[0] for c in ERRORS])
def test_validation_error_table(case):
    _, expr, disp, msg = case
    scene = _eval(expr)
    display = D if disp is None else _eval(disp)
    before = repr(scene)
    with pytest.raises(ValueError) as ei:
        S.validate(scene, display)
    assert str(ei.value) == msg
    assert repr(scene) == before                      # input never changed
    # build() validates again: the same error, nothing allocated
    with pytest.raises(ValueError) as ei:
        S.build(scene, display)
    assert str(ei.value) == msg


def test_error_ids_unique_and_paths_cover_every_level():
    assert len({c[0] for c in ERRORS}) == len(ERRORS)
    heads = {re.match(r"[^: ]+", c[3]).group(0) for c in ERRORS}
    for p in ("display", "display.positions", "display.dx_um", "scene", "regions", "idle_amplitude",
              "regions[0]", "regions[1]", "regions[0].start_mm", "regions[0].end_mm", "regions[0].texture",
              "regions[0].texture.kind", "regions[1].texture.pitch_db", "regions[1].texture.seed",
              "regions[0].texture.name", "regions[0].texture.level", "regions[0].texture.values[3]",
              "regions[0].texture.u16[2]", "regions[0].texture.fit", "regions[1].texture.length_samples"):
        assert p in heads, p


def test_validation_error_table_under_micropython():
    """The same table under MicroPython: the same messages, byte for byte
    (dict order differs there, so this also checks which key is named)."""
    rows = [(c[0], c[1], c[2]) for c in ERRORS]
    code = HELPERS + r"""
import json
from texel.runtime import scene as S
from texel.runtime.kinds import samples as KS
ROWS = %r
out = {}
for cid, expr, disp in ROWS:
    sc = eval(expr)
    dd = D if disp is None else eval(disp)
    try:
        S.validate(sc, dd)
        out[cid] = "no error"
    except ValueError as e:
        out[cid] = str(e)
    except Exception as e:
        out[cid] = "OTHER %%s: %%s" %% (type(e).__name__, e)
print(json.dumps(out))
""" % (rows,)
    got = mpy.run_json(code)
    bad = {c[0]: (got[c[0]], c[3]) for c in ERRORS if got[c[0]] != c[3]}
    assert not bad, bad


# --------------------------------------------------------------------------
# Canonical form
# --------------------------------------------------------------------------

def test_canonical_form():
    c = S.validate(SPLIT, D)
    assert c == {"regions": [
        {"start_mm": 0.0, "end_mm": 50.88, "texture": {"kind": "reference", "name": "4sin"}},
        {"start_mm": 50.88, "end_mm": 101.76, "texture": {
            "kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "texel_samples": 50,
            "quant_db": 0.0, "seed": 7, "gain": 1.0, "v": 2, "band_limit_cpmm": None}}]}   # no "v": format 2
    assert isinstance(c["regions"][0]["start_mm"], float)
    assert "idle_amplitude" not in c
    assert S.validate(c, D) == c                     # idempotent
    assert c is not SPLIT and c["regions"][0] is not SPLIT["regions"][0]
    # regions come out sorted by start, whatever the input order
    rev = {"regions": SPLIT["regions"][::-1], "idle_amplitude": 5}
    c2 = S.validate(rev, D)
    assert c2["regions"] == c["regions"] and c2["idle_amplitude"] == 5
    # tuples are accepted for lists
    assert S.validate({"regions": tuple(SPLIT["regions"])}, D) == c


def test_positions_round_to_nearest_sample():
    def span(s, e):
        sc = S.build({"regions": [{"start_mm": s, "end_mm": e,
                                   "texture": {"kind": "constant", "level": 1}}]}, D)
        return sc.spans()[0][:2]
    assert span(0, 50.88) == (0, 9600)
    assert span(50.88, 101.76) == (9600, 19200)
    dx = 0.0053
    # 10 mm = 1886.79 positions -> 1887; 1.00265 mm = 189.18 -> 189; x.5 rounds up
    assert span(10.0, 20.0) == (1887, 3774)
    assert span(1.0 * 0.5 * dx, 2.4999 * dx) == (1, 2)          # 0.5 -> 1, 2.4999 -> 2
    assert span(0.49 * dx, 1.51 * dx) == (0, 2)
    # the display's own end is accepted even a hair beyond (float rounding of 19200*5.3)
    assert span(100, 101.7626) == (18868, 19200)
    # touching in mm = touching in positions: allowed
    sc = S.validate({"regions": [{"start_mm": 0, "end_mm": 33.3, "texture": {"kind": "constant", "level": 0}},
                                 {"start_mm": 33.3, "end_mm": 50, "texture": {"kind": "constant", "level": 1}}]}, D)
    assert len(sc["regions"]) == 2


def test_validate_never_mutates_and_copies_lists():
    u = [1, 2, 3]
    scene = {"regions": [{"start_mm": 0, "end_mm": 1, "texture": {"kind": "samples", "u16": u}}]}
    before = copy.deepcopy(scene)
    c = S.validate(scene, D)
    assert scene == before
    assert c["regions"][0]["texture"] == {"kind": "samples", "u16": (1, 2, 3), "fit": "tile"}
    u[0] = 999                                       # caller mutates its list later
    assert c["regions"][0]["texture"]["u16"] == (1, 2, 3)
    t = tuple(range(100))
    c = S.validate({"regions": [{"start_mm": 0, "end_mm": 1, "texture": {"kind": "samples", "u16": t}}]}, D)
    assert c["regions"][0]["texture"]["u16"] is t    # immutable: shared, not copied


# --------------------------------------------------------------------------
# The study's split screen
# --------------------------------------------------------------------------

def test_split_screen_plays_reference_and_texel():
    sc = S.build(S.validate(SPLIT, D), D)
    ref = texel.reference_u16("4sin", 9600)
    # the texel half plays from its plan, sample by sample: exactly what the
    # integer engine (the board's) renders
    tx = texel.render_u16(dict(TEXEL_RIGHT, length_samples=9600), engine="int")
    amps = [sc.amp(p) for p in range(19200)]
    assert amps[:9600] == list(ref)
    assert amps[9600:] == [int(v) for v in tx]
    assert len(set(amps[9600:])) > 1000 and len(set(amps[:9600])) > 1000   # not a constant
    (bufs,) = sc.buffers()          # the reference in 1 KB chunks (kinds/reference.py)
    assert [len(b) for b in bufs] == [512] * 18 + [9600 - 18 * 512]
    # (memoryviews of 8-chunk blocks where the heap has them: kinds.SLAB)
    assert all(b.typecode == "H" if isinstance(b, array) else b.format == "H" for b in bufs)
    (t28, d28, L, g), = sc.plans()
    assert len(t28) == len(d28) == 192 and L == 50 and g == 16384
    # 9,600 samples + 192 texels * 8 bytes + 2 regions and a sentinel row of 4 int32
    assert sc.nbytes == 2 * 9600 + 8 * 192 + 3 * 4 * 4 == 20784
    assert sc.idle == 0
    # asking for an engine renders the map with it instead
    scn = S.build(S.validate(SPLIT, D), D, engine="numpy")
    assert [len(b) for b in scn.buffers()] == [19, 9600] and scn.plans() == ()
    txn = texel.render_u16(dict(TEXEL_RIGHT, length_samples=9600), engine="numpy")
    assert [scn.amp(p) for p in range(9600, 19200)] == [int(v) for v in txn]
    for p in (-1, -1000, 19200, 19201, 10 ** 6, 2 ** 30 - 2, -(2 ** 30)):
        assert sc.amp(p) == 0
    # every table value (sentinel included) is a small int on a 32-bit board
    # (a bigint read in the IRQ would allocate; the unix port cannot see it)
    assert max(sc._t) < 2 ** 30 and min(sc._t) >= 0
    assert S.SENTINEL == 2 ** 30 - 1
    assert sc.source == S.validate(SPLIT, D)
    d = sc.describe()
    assert d["count"] == 2 and d["bytes"] == sc.nbytes and d["positions"] == 19200
    assert d["regions"][0] == {"kind": "reference", "name": "4sin", "start": 0, "end": 9600,
                               "start_mm": 0.0, "end_mm": 50.88, "bytes": 19200, "mode": "map"}
    r1 = d["regions"][1]
    assert (r1["kind"], r1["start"], r1["end"], r1["start_mm"], r1["end_mm"], r1["bytes"],
            r1["mode"]) == ("texel", 9600, 19200, 50.88, 101.76, 8 * 192, "plan")
    assert (r1["pitch_db"], r1["irregularity_db"], r1["seed"]) == (6.3, -12.9, 7)
    json.dumps(d)                                   # literals only


def test_texel_region_renders_with_its_own_length():
    # a 3.3 mm texel region: 623 positions -> length_samples 623 (last texel cut short)
    scene = {"regions": [{"start_mm": 20, "end_mm": 23.3, "texture": {"kind": "texel", "pitch_db": 10,
                                                                     "irregularity_db": -5, "seed": 3,
                                                                     "texel_samples": 40}}]}
    sc = S.build(S.validate(scene, D), D, engine="int")
    s, e = sc.spans()[0][:2]
    assert (s, e) == (3774, 4396)
    want = texel.render_u16({"pitch_db": 10, "irregularity_db": -5, "seed": 3, "texel_samples": 40,
                             "length_samples": e - s}, engine="int")
    assert list(sc.buffers()[0]) == list(want)
    assert [sc.amp(p) for p in range(s, e)] == list(want)
    assert sc.amp(s - 1) == 0 and sc.amp(e) == 0


def test_engine_choice_and_unknown_engine():
    sc_int = S.build(SPLIT, D, engine="int")
    sc_np = S.build(SPLIT, D)
    a = [sc_int.amp(p) for p in range(9600, 19200)]
    b = [sc_np.amp(p) for p in range(9600, 19200)]
    assert max(abs(x - y) for x, y in zip(a, b)) <= 3     # fixed point vs float64
    with pytest.raises(ValueError, match=r"^engine: str 'gpu' is not available here"):
        S.build(SPLIT, D, engine="gpu")
    # no texel region: the engine is not consulted
    S.build({"regions": [SPLIT["regions"][0]]}, D, engine="gpu")


# --------------------------------------------------------------------------
# Gaps, constants, idle
# --------------------------------------------------------------------------

GAPS = {"regions": [
    {"start_mm": 10.6, "end_mm": 21.2, "texture": {"kind": "constant", "level": 0.25}},    # 2000..4000
    {"start_mm": 53, "end_mm": 63.6, "texture": {"kind": "constant", "level": 1}},          # 10000..12000
    {"start_mm": 63.6, "end_mm": 74.2, "texture": {"kind": "reference", "name": "square"}},  # 12000..14000
    {"start_mm": 90.1, "end_mm": 91.0, "texture": {"kind": "constant", "level": 0}},        # 17000..17170
]}


def test_gaps_and_constants():
    sc = S.build(S.validate(GAPS, D), D, idle_default=1234)
    assert [x[:2] for x in sc.spans()] == [(2000, 4000), (10000, 12000), (12000, 14000), (17000, 17170)]
    sq = texel.reference_u16("square", 2000)
    want = [1234] * 19200
    for p in range(2000, 4000):
        want[p] = round(0.25 * 65535)                       # 16384 (16383.75 rounds up)
    for p in range(10000, 12000):
        want[p] = 65535
    for p in range(12000, 14000):
        want[p] = sq[p - 12000]
    for p in range(17000, 17170):
        want[p] = 0
    assert [sc.amp(p) for p in range(19200)] == want
    assert want[2000] == 16384
    assert sc.amp(-1) == 1234 and sc.amp(19200) == 1234 and sc.idle == 1234
    (chunks,) = sc.buffers()                                  # only the reference holds samples
    assert [len(b) for b in chunks] == [512, 512, 512, 464]   # in 1 KB chunks
    assert sc.nbytes == 2 * 2000 + 5 * 16
    # the scene's own idle overrides the board's default
    sc2 = S.build(dict(GAPS, idle_amplitude=77), D, idle_default=1234)
    assert sc2.idle == 77 and sc2.amp(0) == 77 and sc2.amp(5000) == 77 and sc2.amp(2000) == 16384
    with pytest.raises(ValueError, match=r"^idle_default: 70000 is out of range \[0, 65535\]$"):
        S.build(GAPS, D, idle_default=70000)


def test_constant_only_scene_holds_no_sample_buffers():
    scene = {"regions": [{"start_mm": i * 6.0, "end_mm": i * 6.0 + 5.0,
                          "texture": {"kind": "constant", "level": i / 15}} for i in range(16)]}
    sc = S.build(scene, D)
    assert sc.buffers() == ()
    assert sc.nbytes == sc.table_bytes == 17 * 4 * 4 and sc.buffer_bytes == 0
    assert all(r["bytes"] == 0 for r in sc.describe()["regions"])
    for i in range(16):
        s = S.to_position(i * 6.0, 5.3)
        assert sc.amp(s) == int(i / 15 * 65535 + 0.5)
        assert sc.amp(s - 1) == 0 or i == 0


# --------------------------------------------------------------------------
# Samples regions (uploads)
# --------------------------------------------------------------------------

def _samples_scene(tex, s_mm=10.6, e_mm=11.13):          # 2000 .. 2100: 100 positions
    return {"regions": [{"start_mm": s_mm, "end_mm": e_mm, "texture": dict(tex, kind="samples")}]}


def test_samples_tile():
    vals = [0.0, 0.1, 0.5, 1.0, 0.33333]
    sc = S.build(_samples_scene({"values": vals}), D)
    q = [int(v * 65535 + 0.5) for v in vals]
    assert q == [0, 6554, 32768, 65535, 21845]
    assert [sc.amp(p) for p in range(2000, 2100)] == [q[i % 5] for i in range(100)]
    # a few values play where they are (K_TILE): no map
    assert sc.spans()[0][2] == S.K_TILE and sc.buffers() == () and sc.buffer_bytes == 10
    # u16 given directly; more values than positions: the first 100
    for count, how in ((300, S.K_TILE), (KS.SMALL, S.K_TILE), (KS.SMALL + 1, S.K_CHUNK)):
        u = list(range(0, 65535, 50))[:count]
        sc = S.build(_samples_scene({"u16": u, "fit": "tile"}), D)
        assert [sc.amp(p) for p in range(2000, 2100)] == u[:100]
        assert sc.source["regions"][0]["texture"] == {"kind": "samples", "u16": tuple(u),
                                                      "fit": "tile"}
        assert sc.spans()[0][2] == how
        if how == S.K_CHUNK:            # more than SMALL values: a map in chunks (fill_chunks)
            assert sum(len(c) for c in sc.buffers()[0]) == 100
        assert sc.buffer_bytes == S.buffer_bytes(_samples_scene({"u16": u, "fit": "tile"}), D) - 32


def test_samples_played_in_place_are_the_maps_value_for_value():
    """A samples region of at most SMALL values plays from them (K_TILE,
    K_STRETCH: kinds/samples.py plan()) what fill_samples' Python loop writes
    into a map, at every position - random values, counts and regions, and
    the hard cases: 1 and 2 positions, as many values as positions, one more
    (a shrinking stretch: a map), SMALL and SMALL + 1 values, and stretches
    over 32,768 and 32,769 positions (the longest in place) and 32,770 (a map)."""
    rnd = random.Random(11)
    big = {"positions": 40000, "dx_um": 1.0}
    cases = []
    for _ in range(120):
        m = rnd.choice([1, 2, 3, 4, 7, 16, 100, KS.SMALL - 1, KS.SMALL, KS.SMALL + 1])
        n = rnd.choice([1, 2, 3, m - 1, m, m + 1, 97, 1000, 19200])
        if n < 1:
            continue
        u = [rnd.choice([0, 65535]) if rnd.random() < 0.3 else rnd.randrange(65536)
             for _ in range(m)]
        cases.append((u, rnd.choice(["tile", "stretch"]), n, D))
    for n in (32768, 32769, 32770):
        cases.append(([0, 65535, 12345], "stretch", n, big))
        cases.append(([65535, 0], "stretch", n, big))
    seen = set()
    for u, fit, n, disp in cases:
        end_mm = n * disp["dx_um"] / 1000.0
        sc = S.build({"regions": [{"start_mm": 0, "end_mm": end_mm, "texture": {
            "kind": "samples", "u16": u, "fit": fit}}]}, disp)
        s, e, how, _ = sc.spans()[0]
        assert (s, e) == (0, n)
        want = array("H", bytes(2 * n))
        KS._loop(tuple(u), 0, len(u), fit, n, want, 0, n)
        assert [sc.amp(p) for p in range(n)] == list(want), (len(u), fit, n, how)
        expect = (S.K_CONST if len(u) == 1 else S.K_CHUNK if len(u) > KS.SMALL
                  else S.K_TILE if fit == "tile" or n == 1
                  else S.K_STRETCH if len(u) <= n <= KS.STRETCH_MAX_N else S.K_CHUNK)
        assert how == expect, (len(u), fit, n, how)
        seen.add(how)
    assert seen == {S.K_CONST, S.K_CHUNK, S.K_TILE, S.K_STRETCH}


def test_describe_rounds_mm_as_round_does_on_micropython():
    """scene._mm on MicroPython (its round(x, 4)'s float operations without
    the pow) is round(x, 4) there, at every 7th position of five displays."""
    res = mpy.run_json(
        "import json\nfrom texel.runtime import scene as S\n"
        "bad = [(p, dx) for dx in (5.3, 1.0, 652.8, 0.001, 13.37) for p in range(0, 20000, 7)"
        " if S._mm(p, dx) != round(p * dx / 1000.0, 4)]\n"
        "print(json.dumps({'bad': bad[:5], 'n': len(bad)}))\n", timeout=120)
    assert res == {"bad": [], "n": 0}


def test_samples_stretch():
    u = [0, 65535, 1000, 40000, 40000]
    sc = S.build(_samples_scene({"u16": u, "fit": "stretch"}), D)
    got = [sc.amp(p) for p in range(2000, 2100)]
    # first value at the first position, last at the last; linear between
    assert got[0] == 0 and got[-1] == 40000
    for i in range(100):
        x = i * (len(u) - 1) / 99
        k = min(int(x), len(u) - 2)
        want = u[k] + (u[k + 1] - u[k]) * (x - k)
        assert abs(got[i] - want) <= 2.5, (i, got[i], want)
    # exact hits where a value lands on a position: 99 = 4 * 24.75 -> none but ends;
    # with 100 positions and 100 values stretch is the identity
    u = [(i * 7919) % 65536 for i in range(100)]
    sc = S.build(_samples_scene({"u16": u, "fit": "stretch"}), D)
    assert [sc.amp(p) for p in range(2000, 2100)] == u
    # one value fills the region; onto one position: the first value
    sc = S.build(_samples_scene({"values": [0.5], "fit": "stretch"}), D)
    assert {sc.amp(p) for p in range(2000, 2100)} == {32768}
    sc = S.build(_samples_scene({"u16": [5, 6, 7], "fit": "stretch"}, 10.6, 10.6053), D)
    assert sc.spans()[0][:2] == (2000, 2001) and sc.amp(2000) == 5
    # shrink: 19200 values onto 100 positions picks interpolated points
    u = [i * 3 for i in range(19200)]
    sc = S.build(_samples_scene({"u16": u, "fit": "stretch"}), D)
    got = [sc.amp(p) for p in range(2000, 2100)]
    assert all(abs(got[i] - 3 * i * 19199 / 99) <= 2.5 for i in range(100))


def test_samples_stretch_full_screen_small_ints():
    # the stretch intermediates stay below 2^30 on a 19,200-position display
    u = [65535, 0]
    sc = S.build({"regions": [{"start_mm": 0, "end_mm": 101.76,
                               "texture": {"kind": "samples", "u16": u, "fit": "stretch"}}]}, D)
    got = [sc.amp(p) for p in range(19200)]
    assert got[0] == 65535 and got[-1] == 0
    assert all(a >= b for a, b in zip(got, got[1:]))             # monotone
    assert max(abs(got[i] - 65535 * (1 - i / 19199)) for i in range(19200)) <= 2.5
    assert 65535 * ((19198 << 14) // 19199) < 2 ** 30


# --------------------------------------------------------------------------
# Memory
# --------------------------------------------------------------------------

FULL_REFERENCE = {"regions": [{"start_mm": 0, "end_mm": 101.76,
                               "texture": {"kind": "reference", "name": "pink"}}]}
FULL_TEXEL = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {
    "kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7}}]}


def _sixteen_small():
    kinds = [{"kind": "texel", "pitch_db": 10, "irregularity_db": -10, "seed": 1},
             {"kind": "reference", "name": "2sin"},
             {"kind": "samples", "u16": [0, 30000, 65535]},
             {"kind": "constant", "level": 0.5}]
    return {"regions": [{"start_mm": 6.0 * i, "end_mm": 6.0 * i + 5.0, "texture": kinds[i % 4]}
                        for i in range(16)]}


SIXTEEN = _sixteen_small()


def test_memory_per_scene():
    figures = {}
    for name, scene in (("split screen", SPLIT), ("full-screen texel", FULL_TEXEL),
                        ("16 small regions", SIXTEEN), ("gaps+constants", GAPS)):
        sc = S.build(scene, D)
        spans = [(s, e, k) for s, e, k, _ in sc.spans()]
        want_buf = (sum(2 * (e - s) for s, e, k in spans if k in (S.K_BUF, S.K_CHUNK))
                    + sum(_plan_bytes(pl) for pl in sc.plans()))
        assert sc.buffer_bytes == want_buf == (
            sum(2 * (len(b) if not isinstance(b, tuple) else sum(len(c) for c in b))
                for b in sc.buffers()) + sum(_plan_bytes(pl) for pl in sc.plans()))
        assert sc.table_bytes == 16 * (len(spans) + 1)
        assert sc.nbytes == want_buf + sc.table_bytes == S.buffer_bytes(scene, D)
        figures[name] = sc.nbytes
    print("\nscene memory (bytes held):", json.dumps(figures))
    assert figures["split screen"] == 2 * 9600 + 8 * 192 + 48 == 20784
    assert figures["full-screen texel"] == 8 * 384 + 32 == 3104      # plan only: no map
    # 16 regions of 5 mm (943 or 944 positions): 4 constants, 4 texel regions
    # played from their plans, 4 reference maps, 4 samples regions of 3 values
    # played where they are (K_TILE: 6 bytes each)
    sc = S.build(SIXTEEN, D)
    lens = [e - s for s, e, k, _ in sc.spans() if k in (S.K_BUF, S.K_CHUNK)]
    texels = [len(pl[0]) for pl in sc.plans() if len(pl) == 4]
    assert [k for _, _, k, _ in sc.spans()].count(S.K_TILE) == 4
    assert len(lens) == 4 and set(lens) <= {943, 944} and len(texels) == 4
    assert figures["16 small regions"] == 2 * sum(lens) + 8 * sum(texels) + 4 * 6 + 17 * 16


def _plan_bytes(pl):
    # a texel plan's two int32 tables, or a few samples' uint16 values (a 5-tuple)
    return 2 * len(pl[0]) if len(pl) == 5 else 8 * len(pl[0])


def test_max_bytes_budget():
    need = S.buffer_bytes(SPLIT, D)
    assert need == 20784
    sc = S.build(SPLIT, D, max_bytes=need)
    assert sc.nbytes == need
    with pytest.raises(ValueError) as ei:
        S.build(SPLIT, D, max_bytes=need - 1)
    assert str(ei.value) == ("scene: needs 20784 bytes (20736 of sample buffers and plans + 48 of "
                             "region table), over the budget of 20783 bytes")
    with pytest.raises(ValueError, match=r"^max_bytes: expected an int"):
        S.build(SPLIT, D, max_bytes=1.5)


def test_memory_error_becomes_value_error(monkeypatch):
    # CPython cannot run out of memory on cue: make every buffer from the second
    # on fail (the second: the reference's second 8-chunk block, then its first
    # 1 KB chunk - kinds.new_chunks). (tests below provoke a real MemoryError under
    # MicroPython.) The region buffers come from compat.u16_one_block.
    from texel import compat
    real = compat.array
    calls = []

    def failing(code, init=()):
        if code == "H":
            calls.append(1)
            if len(calls) >= 2:
                raise MemoryError
        return real(code, init)

    monkeypatch.setattr(compat, "array", failing)
    # the reference's first block, its second (None: kinds._block), its first 1 KB chunk
    with pytest.raises(ValueError, match=r"^scene: out of memory while building \(needs 38448 bytes"):
        S.build(SPLIT, D, engine="int")
    assert len(calls) == 3


# --------------------------------------------------------------------------
# Hypothesis: validate() -> canonical that build() accepts, or ValueError
# --------------------------------------------------------------------------

_scalars = st.one_of(
    st.none(), st.booleans(), st.integers(), st.integers(min_value=-2 ** 300, max_value=2 ** 300),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=50), st.sampled_from(["\n", "'", '"', "__import__('os').system('x')", "\x00", "é"]))
_junk = st.recursive(_scalars, lambda ch: st.one_of(
    st.lists(ch, max_size=6), st.tuples(ch, ch),
    st.dictionaries(st.one_of(st.text(max_size=12), st.integers(), st.none(),
                              st.sampled_from(["kind", "regions", "texture", "start_mm", "u16", "level"])),
                    ch, max_size=5)), max_leaves=25)
_SMALL_MM = 10.6


def _one_in(draw, n):
    # hypothesis favours the ends of a range (0 and n-1): pick a middle value
    return draw(st.integers(0, n - 1)) == n // 2


def _rare(draw, valid, one_in=20):
    """A draw from `valid`, or (about 1 time in one_in) arbitrary junk."""
    return draw(_junk) if _one_in(draw, one_in) else draw(valid)


_opt_texel = {
    "seed": st.integers(min_value=-1, max_value=2 ** 32),
    "texel_samples": st.integers(min_value=0, max_value=3000),
    "quant_db": st.floats(min_value=-0.5, max_value=21),
    "gain": st.floats(min_value=-0.05, max_value=1.05),
    "v": st.integers(min_value=0, max_value=2),
    "band_limit_cpmm": st.one_of(st.none(), st.floats(min_value=0, max_value=100)),
    "length_samples": st.integers(min_value=1, max_value=100),      # always refused
    "bogus": _junk,                                                 # always refused
}


@st.composite
def _texture(draw):
    if _one_in(draw, 12):
        return draw(_junk)
    k = draw(st.integers(0, 8))
    if k < 3:
        t = {"kind": "texel",
             "pitch_db": _rare(draw, st.floats(min_value=-20.5, max_value=20.2)),
             "irregularity_db": _rare(draw, st.floats(min_value=-30.5, max_value=5.5))}
        for key in draw(st.lists(st.sampled_from(sorted(_opt_texel)), max_size=3, unique=True)):
            if key in ("length_samples", "bogus") and not _one_in(draw, 4):
                continue                                    # keep refusals rarer
            t[key] = _rare(draw, _opt_texel[key])
        return t
    if k < 5:
        t = {"kind": "reference",
             "name": _rare(draw, st.sampled_from(texel.reference_names() + ["4SIN", "5sin\n"]))}
    elif k < 7:
        t = {"kind": "constant", "level": _rare(draw, st.floats(min_value=-0.05, max_value=1.05))}
    else:
        t = {"kind": "samples"}
        which = draw(st.integers(0, 10))
        vals = st.lists(st.floats(min_value=-0.01, max_value=1.01), min_size=1, max_size=40)
        u16 = st.lists(st.integers(min_value=-1, max_value=65536), min_size=1, max_size=40)
        if which < 5 or which == 7:                         # 7: both (refused)
            t["values"] = _rare(draw, vals)
        if which >= 5 and which != 8:                       # 8: neither (refused)
            t["u16"] = _rare(draw, u16)
        if draw(st.booleans()):
            t["fit"] = _rare(draw, st.sampled_from(["tile", "stretch", "zoom"]), 10)
    if _one_in(draw, 20):
        t[draw(st.sampled_from(["bogus", "length_samples", "level", "name"]))] = draw(_junk)
    return t


_any_mm = st.one_of(st.floats(min_value=-0.5, max_value=_SMALL_MM + 0.5),
                    st.integers(min_value=-1, max_value=12),
                    st.sampled_from([0, 0.0053, _SMALL_MM, 5.3, 10.6026, 10.6027]))


@st.composite
def _scene_st(draw):
    if _one_in(draw, 10):
        return draw(_junk)
    n = draw(st.integers(1, 5))
    # distinct cut positions (0..2000 on the small display), a little off the
    # sample grid so rounding is exercised
    cuts = sorted(draw(st.lists(st.integers(0, 2000), min_size=2 * n, max_size=2 * n, unique=True)))
    jit = draw(st.sampled_from([0.0, 0.3, -0.3, 0.49]))
    cuts = [max(0.0, (c + jit) * 0.0053) for c in cuts]
    regions = []
    for i in range(n):
        s, e = cuts[2 * i], cuts[2 * i + 1]
        if _one_in(draw, 10):                              # anywhere: may overlap or be empty
            s, e = draw(_any_mm), draw(_any_mm)
        r = {"start_mm": _rare(draw, st.just(s), 30), "end_mm": _rare(draw, st.just(e), 30),
             "texture": draw(_texture())}
        if _one_in(draw, 30):
            r[draw(st.sampled_from(["label", "kind", 1]))] = draw(_junk)
        regions.append(_rare(draw, st.just(r), 40))
    regions = draw(st.permutations(regions))
    scene = {"regions": _rare(draw, st.just(regions), 40)}
    if draw(st.booleans()):
        scene["idle_amplitude"] = _rare(draw, st.integers(min_value=-1, max_value=65536))
    if _one_in(draw, 30):
        scene["bogus"] = draw(_junk)
    return scene


PATH_RE = re.compile(r"^(scene|idle_amplitude|regions)(\[\d+\])?(\.[a-z_0-9]+(\[\d+\])?)*: ")


def check_one(scene, display=SMALL):
    """The property for one input: returns 'ok' or 'err'."""
    before = repr(scene)
    try:
        c = S.validate(scene, display)
    except ValueError as e:
        msg = str(e)
        assert PATH_RE.match(msg), msg
        assert len(msg) < 600, msg
        assert repr(scene) == before
        return "err"
    assert repr(scene) == before
    assert isinstance(c, dict)
    assert S.validate(c, display) == c                       # canonical is a fixed point
    sc = S.build(c, display)
    positions = display["positions"]
    held = 0
    for s, e, kind, val in sc.spans():
        assert 0 <= s < e <= positions
        if kind == S.K_BUF:
            assert len(sc.buffers()[val]) == e - s
            held += 2 * (e - s)
        elif kind == S.K_CHUNK:                  # samples: chunks of 512 (1 KB blocks)
            assert sum(len(c) for c in sc.buffers()[val]) == e - s
            assert max(len(c) for c in sc.buffers()[val]) <= 512
            held += 2 * (e - s)
        elif kind == S.K_PLAN:
            t28, d28, L, g = sc.plans()[val]
            assert len(t28) == len(d28) == (e - s + L - 1) // L
            held += 8 * len(t28)
        elif kind in (S.K_TILE, S.K_STRETCH):   # a few samples, played where they are
            vals = sc.plans()[val][0]
            assert len(vals) <= KS.SMALL + 1
            held += 2 * len(vals)
        assert 0 <= sc.amp(s) <= 65535 and 0 <= sc.amp(e - 1) <= 65535
    assert sc.buffer_bytes == held
    assert max(sc._t) < 2 ** 30 and min(sc._t) >= 0             # board small ints
    for p in (-1, 0, positions // 2, positions - 1, positions):
        v = sc.amp(p)
        assert isinstance(v, int) and 0 <= v <= 65535
    json.dumps(sc.describe())
    return "ok"


@pytest.mark.slow
def test_property_validate_then_build():
    seen = {"ok": 0, "err": 0}

    # the profile tests/conftest.py registers: derandomized unless
    # TEXELPAD_HYPOTHESIS=nightly (then fresh random cases, 25 x as many)
    nightly = os.environ.get("TEXELPAD_HYPOTHESIS") == "nightly"

    @settings(settings.get_profile("texelpad-nightly" if nightly else "texelpad-default"),
              max_examples=800 * (25 if nightly else 1))
    @given(_scene_st())
    def prop(scene):
        seen[check_one(scene)] += 1

    prop()
    print("\nhypothesis cases:", seen)
    assert seen["ok"] + seen["err"] >= 500
    assert seen["ok"] >= 40 and seen["err"] >= 200       # both branches exercised


# --------------------------------------------------------------------------
# The same kind of inputs under MicroPython: the same answers
# --------------------------------------------------------------------------

def _rand_junk(rng, depth=0):
    r = rng.random()
    if depth > 3 or r < 0.6:
        return rng.choice([None, True, False, 0, -1, 7, 65536, 2 ** 70, -(10 ** 30), 0.5, -0.0, 1e300,
                           float("nan"), float("inf"), -float("inf"), "", "x", "\n'\"", "4sin",
                           "texel", "__import__('os')", "é" * 3, 10.6, 123456789])
    if r < 0.8:
        return [_rand_junk(rng, depth + 1) for _ in range(rng.randrange(4))]
    return {rng.choice(["kind", "name", "u16", "a", "start_mm", 3]): _rand_junk(rng, depth + 1)
            for _ in range(rng.randrange(3))}


def _rand_case(rng):
    def maybe(v):
        return _rand_junk(rng) if rng.random() < 0.03 else v

    def texture():
        k = rng.randrange(5)
        if k == 0:
            t = {"kind": "texel", "pitch_db": maybe(rng.uniform(-21, 20)),
                 "irregularity_db": maybe(rng.uniform(-31, 6))}
            for key, gen in (("seed", lambda: rng.randrange(-1, 2 ** 32 + 1)),
                             ("texel_samples", lambda: rng.randrange(0, 500)),
                             ("quant_db", lambda: rng.choice([0, 1, 3, 5, -1])),
                             ("gain", lambda: rng.uniform(0, 1.05)),
                             ("band_limit_cpmm", lambda: rng.choice([None, 20.0, 100]))):
                if rng.random() < 0.4:
                    t[key] = maybe(gen())
            return t
        if k == 1:
            return {"kind": "reference", "name": maybe(rng.choice(texel.reference_names()[:9] + ["x"]))}
        if k == 2:
            return {"kind": "constant", "level": maybe(rng.choice([0, 1, 0.5, rng.random(), 1.5]))}
        if k == 3:
            t = {"kind": "samples", "fit": maybe(rng.choice(["tile", "stretch"]))}
            n = rng.randrange(0, 30)
            if rng.random() < 0.5:
                t["u16"] = maybe([maybe(rng.randrange(0, 65536)) for _ in range(n)])
            else:
                t["values"] = maybe([maybe(rng.random()) for _ in range(n)])
            return t
        return _rand_junk(rng)

    regions = []
    x = 0.0
    for _ in range(rng.randrange(0, 5)):
        s = x + rng.choice([0, 0, 0, 0.3, 0.3, -0.2])
        e = s + rng.uniform(0.01, 2.5)
        x = e
        regions.append(maybe({"start_mm": maybe(round(s, 4)), "end_mm": maybe(round(e, 4)),
                              "texture": texture()}))
    scene = {"regions": maybe(regions)}
    if rng.random() < 0.3:
        scene["idle_amplitude"] = maybe(rng.choice([0, 100, 65535, 65536]))
    return maybe(scene)


def _mp_literal(v):
    """Source text of a value for MicroPython (nan/inf need float())."""
    if isinstance(v, float):
        if v != v:
            return "float('nan')"
        if v in (float("inf"), float("-inf")):
            return "float('%s')" % ("inf" if v > 0 else "-inf")
        return repr(v)
    if isinstance(v, (list, tuple)):
        inner = ", ".join(_mp_literal(x) for x in v)
        return "[%s]" % inner if isinstance(v, list) else "(%s%s)" % (inner, "," if len(v) == 1 else "")
    if isinstance(v, dict):
        return "{%s}" % ", ".join("%s: %s" % (_mp_literal(k), _mp_literal(x)) for k, x in v.items())
    return repr(v)


def _summary(scene, display):
    try:
        c = S.validate(scene, display)
    except ValueError as e:
        return ["err", str(e)]
    except Exception as e:                      # noqa: BLE001 - reported, must not happen
        return ["other", type(e).__name__]
    sc = S.build(c, display)
    h = 0
    for p in range(-2, display["positions"] + 2):
        h = (h * 31 + sc.amp(p)) & 0xFFFFFFF
    return ["ok", sc.nbytes, h, sc.describe()["count"]]


MP_SUMMARY = r"""
import json
from texel.runtime import scene as S
from texel.runtime.kinds import samples as KS
def summary(scene, display):
    try:
        c = S.validate(scene, display)
    except ValueError as e:
        return ["err", str(e)]
    except Exception as e:
        return ["other", type(e).__name__]
    sc = S.build(c, display)
    h = 0
    for p in range(-2, display["positions"] + 2):
        h = (h * 31 + sc.amp(p)) & 0xFFFFFFF
    return ["ok", sc.nbytes, h, sc.describe()["count"]]
"""


def test_random_cases_same_answers_under_micropython(tmp_path):
    rng = random.Random(20261121)
    cases = [_rand_case(rng) for _ in range(400)]
    want = [_summary(c, SMALL) for c in cases]
    assert not [w for w in want if w[0] == "other"]
    n_ok = sum(1 for w in want if w[0] == "ok")
    assert n_ok >= 40 and len(cases) - n_ok >= 150, n_ok
    src = tmp_path / "cases.py"
    src.write_text("CASES = [\n" + ",\n".join(_mp_literal(c) for c in cases) + "]\n", encoding="utf-8")
    code = MP_SUMMARY + f"""
exec(open({str(src)!r}).read())
D = {SMALL!r}
print(json.dumps([summary(c, D) for c in CASES]))
"""
    got = mpy.run_json(code, timeout=600)
    diffs = [(i, want[i], got[i]) for i in range(len(cases)) if got[i] != want[i]]
    assert not diffs, diffs[:5]


# --------------------------------------------------------------------------
# MicroPython: split screen, heap_lock, timing, real MemoryError
# --------------------------------------------------------------------------

def test_split_screen_under_micropython():
    code = HELPERS + r"""
import json, time, gc
import texel
from texel.runtime import scene as S
from texel.runtime.kinds import samples as KS
gc.collect()
t0 = time.ticks_us()
c = S.validate(split(), D)
t1 = time.ticks_us()
sc = S.build(c, D)
t2 = time.ticks_us()
ref = texel.reference_u16("4sin", 9600)
tx = texel.render_u16({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "length_samples": 9600})
left = all(sc.amp(p) == ref[p] for p in range(9600))
right = all(sc.amp(9600 + p) == tx[p] for p in range(9600))
print(json.dumps({"left": left, "right": right, "nbytes": sc.nbytes, "engine": texel.default_engine(),
                  "validate_us": time.ticks_diff(t1, t0), "build_us": time.ticks_diff(t2, t1),
                  "out": [sc.amp(-1), sc.amp(19200), sc.amp(2 ** 30 - 2)],
                  "lens": [[len(c) for c in b] for b in sc.buffers()], "idle": sc.idle}))
"""
    res = mpy.run_json(code)
    print("\nsplit screen on the unix port:", json.dumps(res))
    assert res["left"] and res["right"]
    assert res["engine"] == "int"
    # the reference half in 1 KB chunks, the texel half its plan
    assert res["nbytes"] == 20784 and res["lens"] == [[512] * 18 + [384]]
    assert res["out"] == [0, 0, 0] and res["idle"] == 0


AMP_LOCK = HELPERS + r"""
import json, micropython
from texel.runtime import scene as S
from texel.runtime.kinds import samples as KS
GAPS = %(gaps)r
sc = S.build(GAPS, D, idle_default=321)
sp = S.build(split(), D)
ramp = S.build(%(sixteen)r, D)

def scan(sc, lo, hi):
    micropython.heap_lock()
    try:
        acc = 0
        p = lo
        while p < hi:
            acc = (acc * 31 + sc.amp(p)) & 0xFFFFFFF
            p += 1
        r = 'ok'
    except MemoryError:
        r = 'MemoryError'
    micropython.heap_unlock()
    return r, acc

def scan_bound(amp, lo, hi):
    # the refresh may keep the bound method (made once, outside the IRQ)
    micropython.heap_lock()
    try:
        acc = 0
        p = lo
        while p < hi:
            acc = (acc * 31 + amp(p)) & 0xFFFFFFF
            p += 1
        r = 'ok'
    except MemoryError:
        r = 'MemoryError'
    micropython.heap_unlock()
    return r, acc

def scan_free(sc, lo, hi):
    acc = 0
    for p in range(lo, hi):
        acc = (acc * 31 + sc.amp(p)) & 0xFFFFFFF
    return acc

def edges(sc):
    micropython.heap_lock()
    try:
        v = (sc.amp(-1) + sc.amp(-(2 ** 30)) + sc.amp(2 ** 30 - 2) + sc.amp(19200)) & 0xFFFFFFF
        r = 'ok'
    except MemoryError:
        r = 'MemoryError'
        v = -1
    micropython.heap_unlock()
    return r, v

def control_float(sc):
    micropython.heap_lock()
    try:
        x = sc.amp(2500) / 3          # a float: allocates on the heap
        r = 'ok'
    except MemoryError:
        r = 'MemoryError'
    micropython.heap_unlock()
    return r

def control_list(sc):
    micropython.heap_lock()
    try:
        x = [sc.amp(2500)]
        r = 'ok'
    except MemoryError:
        r = 'MemoryError'
    micropython.heap_unlock()
    return r

out = {}
for name, s in (('gaps', sc), ('split', sp), ('sixteen', ramp)):
    out[name] = scan(s, -5, 19205)
    out[name + '_bound'] = scan_bound(s.amp, -5, 19205)
    out[name + '_free'] = scan_free(s, -5, 19205)
out['edges'] = edges(sc)
out['control_float'] = control_float(sc)
out['control_list'] = control_list(sc)
print(json.dumps(out))
"""


def test_amp_allocation_free_under_heap_lock():
    res = mpy.run_json(AMP_LOCK % {"gaps": GAPS, "sixteen": SIXTEEN})
    for name in ("gaps", "split", "sixteen"):
        assert res[name][0] == "ok", res[name]
        assert res[name + "_bound"][0] == "ok", res[name + "_bound"]
        assert res[name][1] == res[name + "_free"] == res[name + "_bound"][1]
    assert res["edges"] == ["ok", 4 * 321]
    # the lock does catch allocations
    assert res["control_float"] == "MemoryError"
    assert res["control_list"] == "MemoryError"
    # and the CPython scene gives the same checksum
    sc = S.build(GAPS, D, idle_default=321)
    acc = 0
    for p in range(-5, 19205):
        acc = (acc * 31 + sc.amp(p)) & 0xFFFFFFF
    assert acc == res["gaps"][1]


AMP_TIMING = r"""
import json, time
from texel.runtime import scene as S
from texel.runtime.kinds import samples as KS
D = {"positions": 19200, "dx_um": 5.3}

def mk(R):
    w = 101.76 / R
    regs = []
    for k in range(R):
        if k % 2:
            tex = {"kind": "constant", "level": k / 16}
        else:
            tex = {"kind": "samples", "u16": [k * 100, 7, 9]}
        end = (k + 1) * w - (w * 0.1 if k % 3 == 1 else 0)       # a few gaps
        regs.append({"start_mm": k * w, "end_mm": end, "texture": tex})
    return S.build({"regions": regs}, D)

def amp_bsearch(self, pos):
    # the alternative: binary search on the sorted ends
    t = self._t
    lo = 0
    hi = self.count
    while lo < hi:
        mid = (lo + hi) >> 1
        if t[(mid << 2) + 1] <= pos:
            lo = mid + 1
        else:
            hi = mid
    j = lo << 2                    # lo == count: the sentinel row
    s = t[j]
    if pos < s:
        return self.idle
    if t[j + 2] == 3:                 # K_CHUNK
        o = pos - s
        return self._bufs[t[j + 3]][o >> 9][o & 511]
    if t[j + 2] == 4:                 # K_TILE: a few samples (kinds/samples.py plan())
        pl = self._plans[t[j + 3]]
        return pl[0][(pos - s) % pl[1]]
    if t[j + 2]:
        return self._bufs[t[j + 3]][pos - s]
    return t[j + 3]

amp_linear = S.Scene.amp          # the scene's own scan, called like amp_bsearch

def empty(self, pos):
    return 0

def run(f, sc, n, lo, hi):
    t0 = time.ticks_us()
    p = lo
    for _ in range(n):
        f(sc, p)
        p += 7
        if p >= hi:
            p = lo
    return time.ticks_diff(time.ticks_us(), t0)

N = 100000
out = {}
for R in (1, 4, 16):
    sc = mk(R)
    ok = all(amp_bsearch(sc, p) == sc.amp(p) for p in range(-3, 19203))
    last = sc.spans()[-1]
    for label, lo, hi in (("uniform", 0, 19200), ("last", last[0], last[1])):
        best = {}
        for name, f in (("empty", empty), ("linear", amp_linear), ("bsearch", amp_bsearch)):
            best[name] = min(run(f, sc, N, lo, hi) for _ in range(5))
        out["%d %s" % (R, label)] = {"linear_us": (best["linear"] - best["empty"]) / N,
                                     "bsearch_us": (best["bsearch"] - best["empty"]) / N, "same": ok}
print(json.dumps(out))
"""


@pytest.mark.slow
def test_amp_linear_scan_equals_binary_search():
    """The scene's linear region scan and a binary search over the same table
    give the same amplitude everywhere (1, 4 and 16 regions). The times are
    printed for the record (run with -s); they are figures, not a verdict:
    timing comparisons belong in benchmarks (texelpad bench-refresh times
    scene.amp), and on a loaded host two timings can swap."""
    res = mpy.run_json(AMP_TIMING, timeout=300)
    print("\namp() us per call on the unix port:")
    for k in sorted(res, key=lambda s: (int(s.split()[0]), s)):
        print("  %-10s linear %.3f  bsearch %.3f" % (k, res[k]["linear_us"], res[k]["bsearch_us"]))
    assert all(v["same"] for v in res.values())


MEMORY_SCRIPT = HELPERS + r"""
import json, gc
from texel.runtime import scene as S
from texel.runtime.kinds import samples as KS
FULL = %(full)r
gc.collect()
try:
    old = S.build(split(), D)                  # the scene playing now
except ValueError as e:                        # the precondition, not the subject
    print(json.dumps({"no_split": str(e)}))
    raise SystemExit
def digest(sc):
    acc = 0
    for p in range(0, 19200, 3):
        acc = (acc * 31 + sc.amp(p)) & 0xFFFFFFF
    return acc
d0 = digest(old)
res = {}
# 1. over budget: refused before allocating (validation's own small dicts only)
gc.collect()
a0 = gc.mem_alloc()
try:
    S.build(FULL, D, max_bytes=20000)
    res['budget'] = 'built'
except ValueError as e:
    res['budget'] = str(e)
res['budget_alloc'] = gc.mem_alloc() - a0
# 2. a real MemoryError: two full screens do not fit this heap
new = None
try:
    new = S.build(FULL, D)
    res['oom'] = 'built'
except ValueError as e:
    res['oom'] = str(e)
except MemoryError:
    res['oom'] = 'MemoryError escaped'
res['old_same'] = digest(old) == d0
gc.collect()
res['free_after'] = gc.mem_free()
# 3. once the old scene is dropped, the new one may fit (heap fragmentation permitting)
old = None
new = None
gc.collect()
try:
    new = S.build(FULL, D)
    res['after_drop'] = new.nbytes
except ValueError as e:
    res['after_drop'] = str(e)
print(json.dumps(res))
"""


def test_real_memory_error_under_micropython(tmp_path):
    """Real MemoryErrors: with the split screen playing, build a full-screen
    reference (a 38.4 KB map in 38 chunks of 1 KB; a full-screen texel plays
    from its 3 KB plan and always fits - test_full_texel_fits_beside_split_screen)
    on heaps of 112..272 KB, the image compiled as a board loads it. build()
    never lets a MemoryError out (it becomes a ValueError) and the playing
    scene stays intact; on the small heaps the second map finds no room - and
    the message says why: fewer bytes free than it needs, or a largest free
    block (found on the board, compat.largest_free_block) smaller than the
    one block (1 KB) a region needs."""
    code = MEMORY_SCRIPT % {"full": FULL_REFERENCE}
    rows = {}
    # the compiled image, as a board loads it (compiling from source leaves garbage that
    # decides by chance which heaps still have a 19 KB block for the split screen)
    from texelpad import image
    tree = tmp_path / "image"
    image.write_tree(image.build_image(image.TARGETS["unix"], include_main=False), tree)
    for kb in range(112, 273, 8):
        res = mpy.run_json(code, heapsize=f"{kb}k", path=tree / "lib")
        if "no_split" in res:
            # the unix port compiles the package from source: on the smallest
            # heaps the playing split screen itself may not build (a board
            # loads .mpy); such a heap tests nothing here
            assert kb <= 184 and res["no_split"].startswith("scene: out of memory"), (kb, res)
            print("  %d: the split screen itself does not build from source here" % kb)
            continue
        rows[kb] = res
        assert res["budget"] == ("scene: needs 38432 bytes (38400 of sample buffers and plans + 32 of "
                                 "region table), over the budget of 20000 bytes")
        assert res["budget_alloc"] < 4096                 # no 38 KB buffer was made
        assert res["old_same"], kb
        for k in ("oom", "after_drop"):
            v = res[k]
            assert v in ("built", 38432) or re.match(
                r"scene: out of memory while building \(needs 38432 bytes: 38400 of sample buffers "
                r"and plans \+ 32 of region table; (\d+) bytes free, the largest free block (\d+) "
                r"bytes, room for (\d+) blocks of 1024, and a region needs one block of 1024\)"
                r"(; the scene playing \(\d+ bytes\) plays on: to make room, push a small "
                r"scene first \(texelpad push --constant 0\))?$",
                v), (kb, k, v)
            m = re.search(r"; (\d+) bytes free, the largest free block (\d+) bytes, room for "
                          r"(\d+) blocks", str(v))
            if m:               # the message says why: too few bytes, or too few 1 KB pieces
                assert int(m.group(1)) < 38432 or int(m.group(3)) < 38, (kb, k, v)
    print("\nfull-screen reference built while the split screen plays (heap KB: outcome, free after):")
    for kb, res in rows.items():
        print("  %d: %s / after dropping the old: %s" % (kb, res["oom"][-96:], str(res["after_drop"])[-96:]))
    assert sum(1 for r in rows.values() if r["oom"].startswith("scene: out of memory")) >= 3


def test_full_texel_fits_beside_split_screen(tmp_path):
    """A full-screen texel plays from its plan (384 texels x 8 bytes), so a
    new one builds beside the playing split screen even on a Pico-sized
    heap, where a second 38.4 KB map often finds no room."""
    # From the compiled image, as a board loads it: compiling the modules
    # from source leaves garbage that decides by chance (any line added to a
    # module moved it) whether a 19 KB block is left on a 176 KB heap.
    from texelpad import image
    tree = tmp_path / "image"
    image.write_tree(image.build_image(image.TARGETS["unix"], include_main=False), tree)
    code = HELPERS + r"""
import json, gc
from texel.runtime import scene as S
from texel.runtime.kinds import samples as KS
old = S.build(S.validate(split(), D), D)
gc.collect()
new = S.build(S.validate(%(full)r, D), D)
print(json.dumps({"nbytes": new.nbytes, "plans": len(new.plans()), "free": gc.mem_free()}))
""" % {"full": FULL_TEXEL}
    # (the unix port's 64-bit objects and bytecode in RAM make its heap hold less than
    # a Pico's of the same size; 176 KB stopped being enough, by a few hundred bytes of
    # fragmentation, when the device code grew by ~2 KB of bytecode: the Python plan's
    # 3 KB int list found no room with 50 KB free. The Pico builds texel scenes beside
    # playing ones on every push of bench/firmware.py and tests/firmware.) 180 KB in turn
    # stopped being enough when the brush's painting in parts (issue 32: scene.build's
    # focus, app._paint_rest) added its bytecode: at 80b6031 180 KB passed and 176 failed,
    # with it 184 passes and 180 fails, the same way (a 3 KB block with ~50 KB free).
    for kb in (184, 200, 240):
        res = mpy.run_json(code, heapsize=f"{kb}k", path=tree / "lib")
        assert res["nbytes"] == 8 * 384 + 32 and res["plans"] == 1, (kb, res)


def _bytecode_tree(tmp_path):
    """device/texel compiled by mpy-cross as a board's image holds it
    (bytecode: no source compiled at import, whose garbage would fragment a
    small heap as no board's does); native (viper) modules left out, as for
    a port without the emitter."""
    out = tmp_path / "img"
    for src in (mpy.DEVICE / "texel").rglob("*.py"):
        if src in mpy.viper_files() or src.name == "main.py":
            continue
        dst = out / src.relative_to(mpy.DEVICE).with_suffix(".mpy")
        dst.parent.mkdir(parents=True, exist_ok=True)
        p = mpy.mpy_cross(src, dst)
        assert p.returncode == 0, p.stdout + p.stderr
    for data in (mpy.DEVICE / "texel").rglob("*.bin"):
        (out / data.relative_to(mpy.DEVICE)).write_bytes(data.read_bytes())
    for data in (mpy.DEVICE / "texel" / "boards.d").glob("*.json"):
        d = out / data.relative_to(mpy.DEVICE)
        d.parent.mkdir(parents=True, exist_ok=True)
        d.write_bytes(data.read_bytes())
    return out


def test_pico_heap_split_screen_builds(tmp_path):
    """The study's split screen on a Pico-sized heap (180 KB), the modules as
    a board has them (bytecode)."""
    code = HELPERS + r"""
import json, gc
from texel.runtime import scene as S
from texel.runtime.kinds import samples as KS
gc.collect()
sc = S.build(S.validate(split(), D), D)
gc.collect()
print(json.dumps({"nbytes": sc.nbytes, "free": gc.mem_free()}))
"""
    res = mpy.run_json(code, heapsize="180k", path=_bytecode_tree(tmp_path))
    print("\nsplit screen on a 180k heap:", json.dumps(res))
    assert res["nbytes"] == 20784


def test_scene_compiles_for_rp2040(tmp_path):
    src = mpy.DEVICE / "texel" / "runtime" / "scene.py"
    p = mpy.mpy_cross(src, tmp_path / "scene.mpy", "armv6m")
    assert p.returncode == 0, p.stdout + p.stderr
    assert (tmp_path / "scene.mpy").read_bytes()[:2] == b"M\x06"


def test_scene_name_and_notes_kept_and_bounded():
    """A scene's own words: kept in the canonical form, the name shown by
    describe(); bad ones refused by key."""
    reg = [{"start_mm": 0, "end_mm": 10, "texture": {"kind": "constant", "level": 0.5}}]
    c = S.validate({"name": "half", "notes": "why: a test", "regions": reg}, D)
    assert c["name"] == "half" and c["notes"] == "why: a test"
    assert S.validate(c, D) == c
    assert S.build(c, D).describe()["name"] == "half"
    assert "name" not in S.build(S.validate({"regions": reg}, D), D).describe()
    for bad, msg in [({"name": ""}, "name: expected a string of 1 .. 64 characters, got 0 characters"),
                     ({"name": 3}, "name: expected a string of 1 .. 64 characters, got int 3"),
                     ({"name": "x" * 65}, "got 65 characters"),
                     ({"notes": "a" * 2001}, "notes: expected a string of at most 2000 characters")]:
        with pytest.raises(ValueError, match=re.escape(msg)):
            S.validate(dict(bad, regions=reg), D)


def test_a_push_shares_the_playing_scenes_unchanged_reference_and_brush():
    """build(reuse=the playing scene): a reference or brush region of the
    same texture and length shares the playing scene's buffer (not rendered
    again: a slider on the right half of a split screen re-renders the right
    half only), and the scene plays exactly what a fresh build plays."""
    from texel.gen import brush as Bm
    brush = {"k": [2.0] * Bm.K, "lam": [0.5] + [0.03] * (Bm.K - 1)}

    def split(right_pitch, left):
        return S.validate({"regions": [
            {"start_mm": 0, "end_mm": 50.88, "texture": left},
            {"start_mm": 50.88, "end_mm": 101.76,
             "texture": {"kind": "texel", "pitch_db": right_pitch, "irregularity_db": -12.9,
                         "texel_samples": 3, "seed": 7}}]}, D)
    for left in ({"kind": "reference", "name": "4sin"},
                 {"kind": "brush", "brush": brush, "seed": 5}):
        a = S.build(split(6.3, left), D)
        b = S.build(split(9.0, left), D, reuse=a)
        fresh = S.build(split(9.0, left), D)
        assert b.buffers()[0] is a.buffers()[0]                  # shared, not rendered again
        assert b.buffers()[1] is not a.buffers()[1]
        assert [b.amp(p) for p in range(0, 19200, 7)] == [fresh.amp(p) for p in range(0, 19200, 7)]
        # another length or texture: its own buffer
        other = dict(left, seed=6) if left["kind"] == "brush" else dict(left, name="pink")
        c = S.build(split(9.0, other), D, reuse=a)
        assert c.buffers()[0] is not a.buffers()[0]


# --- a region ending at the display's own length, at every float precision --------------

EDGE_DISPLAYS = [(16143, 652816.0989344482),     # 10.5 km: CircuitPython refused its own end
                 (1048576, 1000000.0), (1048576, 1.0), (1, 1000000.0), (19200, 5.3),
                 (777777, 999999.9)]
EDGE_SCRIPT = """
import json
from texel.runtime import scene as S
from texel.runtime.kinds import samples as KS
out = []
for positions, dx_um, end_mm in %s:
    d = {'positions': positions, 'dx_um': dx_um}
    sc = {'regions': [{'start_mm': 0, 'end_mm': end_mm,
                       'texture': {'kind': 'constant', 'level': 0}}]}
    try:
        c, spans, n, dx = S.check(sc, d)
        out.append(['ok', spans])
    except ValueError as e:
        out.append(['refused', str(e)])
print(json.dumps(out))
"""


@pytest.mark.parametrize("name", [mpy.toolchain.UNIX_PORT, *mpy.toolchain.INSTRUMENTS])
def test_a_region_to_the_displays_own_length_is_accepted_at_every_precision(name):
    """The host writes end_mm as the display's length rounded to 0.1 um
    (S._mm); every interpreter accepts it and puts the end on the last
    position - on CircuitPython's 30-bit floats too, where 'length + 1 mm'
    was the length again for a 10.5 km display (found by the build property
    on CircuitPython, tests/runtime/test_scene_property.py)."""
    exe = mpy.toolchain.interpreter(name)
    if exe is None:
        pytest.skip("%s is not on this machine (../shared/instruments)" % name)
    cases = [(p, dx, S._mm(p, dx)) for p, dx in EDGE_DISPLAYS]
    got = mpy.run_json(EDGE_SCRIPT % repr(cases), exe=exe)
    assert got == [["ok", [[0, p]]] for p, _ in EDGE_DISPLAYS], got
