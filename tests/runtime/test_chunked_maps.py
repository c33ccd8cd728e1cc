"""Issue 32, item 4: no push needs one block of a region's length. A reference
(where the board has no flash map of it) and a texel region rendered whole
(1-4-sample texels, or one texel longer than its region) are written into
1 KB chunks (runtime/kinds/__init__.py new_chunks) and play as K_CHUNK rows:
the same values as the one-block maps, on CPython and on the real
interpreters (the unix port with the C core's x64 native module: its render
a chunk at a time; MicroPython float32: the viper sines and fill)."""
from __future__ import annotations

import json
import shutil
from array import array

import pytest

import texel
from support import mpy
from texel.gen import engine_int, reference as R
from texel.runtime import kinds, scene as S
from texelpad import toolchain
from texelpad.firmware import natmod

D = {"positions": 19200, "dx_um": 5.3}
LENGTHS = (1, 511, 512, 513, 9600, 9601, 19200)


def _chunks(n: int, bits: int = kinds.CHUNK_BITS) -> tuple:
    size = 1 << bits
    return tuple(array("H", bytes(2 * min(size, n - o))) for o in range(0, n, size))


def _flat(chunks) -> list[int]:
    return [v for c in chunks for v in c]


@pytest.mark.parametrize("name", R.STUDY_NAMES + ("bp-4-0.5",))
def test_a_reference_in_chunks_is_its_one_block_map(name):
    for n in LENGTHS if name in R.STUDY_NAMES else (1, 513, 9600):
        ch = _chunks(n)
        assert R.reference_u16(name, n, ch) is ch
        assert _flat(ch) == list(R.reference_u16(name, n)), (name, n)


def test_chunks_that_cannot_hold_the_map_are_refused():
    with pytest.raises(ValueError, match=r"^out: the chunks hold 1024 samples, 1025 needed$"):
        R.reference_u16("4sin", 1025, _chunks(1024))
    odd = (array("H", bytes(1024)), array("H", bytes(10)), array("H", bytes(1024)))
    with pytest.raises(ValueError, match=r"^out: chunk 1 holds 5 values, the first 512$"):
        R.reference_u16("pink", 1200, odd)


def _texel(L: int, n: int, seed: int = 3):
    return texel.make_plan({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": seed,
                            "texel_samples": L, "length_samples": n})


@pytest.mark.parametrize("L", [1, 2, 3, 4, 5, 7, 600, 20000])
@pytest.mark.parametrize("bits", [9, 4])
def test_texels_rendered_into_chunks_are_the_one_block_render(L, bits):
    for n in (1, 15, 512, 1000, 19200):
        plan = _texel(L, n)
        ch = _chunks(n, bits)
        assert engine_int.render_chunks(plan, ch, bits) is ch
        assert _flat(ch) == list(engine_int.render_u16(plan)), (L, n, bits)


def test_a_scene_of_short_texels_and_a_reference_plays_from_chunks():
    scene = {"regions": [
        {"start_mm": 0, "end_mm": 40, "texture": {"kind": "reference", "name": "pink"}},
        {"start_mm": 40, "end_mm": 70, "texture": {"kind": "texel", "pitch_db": 6.3,
                                                   "irregularity_db": -12.9, "seed": 7,
                                                   "texel_samples": 3}},
        {"start_mm": 70, "end_mm": 101.76, "texture": {"kind": "texel", "pitch_db": 6.3,
                                                       "irregularity_db": -12.9, "seed": 8,
                                                       "texel_samples": 9000}}]}
    sc = S.build(S.validate(scene, D), D)
    rows = [sc._t[S.STRIDE * i + 2] for i in range(sc.count) if sc._t[S.STRIDE * i + 1] >
            sc._t[S.STRIDE * i]]
    assert rows == [kinds.K_CHUNK] * 3
    assert all(max(len(c) for c in b) == 512 for b in sc.buffers())
    for (s, e, *_), tex in zip(sc.spans(), [r["texture"] for r in scene["regions"]]):
        if tex["kind"] == "reference":
            want = list(R.reference_u16(tex["name"], e - s))
        else:
            want = list(texel.render_u16(dict({k: v for k, v in tex.items() if k != "kind"},
                                              length_samples=e - s), engine="int"))
        assert [sc.amp(p) for p in range(s, e)] == want, tex
    # asked for an engine, a texel region is one buffer of that engine's render
    sn = S.build(S.validate(scene, D), D, engine="int")
    assert [type(b) for b in sn.buffers()] == [tuple, array, array]


SCRIPT = r"""
import json
from array import array
import texel
from texel import compat
from texel.gen import reference as R, engine_int
from texel.runtime import kinds, scene as S
def chunks(n, bits=9):
    size = 1 << bits
    return tuple(array("H", bytes(2 * min(size, n - o))) for o in range(0, n, size))
def flat(ch):
    out = []
    for c in ch:
        out.extend(c)
    return out
bad = []
for name in R.STUDY_NAMES:
    for n in (1, 513, 9601, 19200):
        ch = chunks(n)
        R.reference_u16(name, n, ch)
        if flat(ch) != list(R.reference_u16(name, n)):
            bad.append([name, n])
for L in (1, 2, 3, 4, 7, 20000):
    for n in (15, 1000, 19200):
        for bits in (9, 4):
            p = texel.make_plan({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 3,
                                 "texel_samples": L, "length_samples": n})
            ch = chunks(n, bits)
            engine_int.render_chunks(p, ch, bits)
            if flat(ch) != list(engine_int.render_u16(p)):
                bad.append([L, n, bits])
print(json.dumps({"bad": bad, "c": bool(compat.core()), "fill": engine_int.ENGINE,
                  "int_sines": bool(R._int_sines())}))
"""


@pytest.fixture(scope="module")
def x64_core(tmp_path_factory):
    """_texelcore.mpy for x64 built from this checkout (None where it cannot be)."""
    if natmod.missing("x64"):
        return None
    d = tmp_path_factory.mktemp("natmod")
    shutil.copyfile(natmod.build("x64", d), d / "_texelcore.mpy")
    return d


@pytest.mark.parametrize("exe", ["micropython", "micropython-ulab-f32"])
def test_chunks_on_the_real_interpreters(exe, x64_core):
    path = toolchain.interpreter(exe)
    if path is None:
        pytest.skip("no %s here (../shared/instruments)" % exe)
    kw = {"extra_path": str(x64_core)} if exe == "micropython" and x64_core else {}
    got = mpy.run_json(SCRIPT, exe=path, timeout=600, **kw)
    print("\n%s: %s" % (exe, json.dumps(got)))
    assert got["bad"] == []
    if exe == "micropython-ulab-f32":
        assert got["int_sines"] and got["fill"] == "viper"
    elif x64_core:
        assert got["c"] and got["fill"] == "c"


# --- maps in blocks of SLAB chunks (kinds.SLAB: 8 on the texelpad firmware) -------------------

SLAB_SCENE = ('{"regions": [{"start_mm": 0, "end_mm": 40, "texture": {"kind": "samples",'
              ' "values": [0, 1], "fit": "stretch"}},'
              ' {"start_mm": 40, "end_mm": 70, "texture": {"kind": "reference", "name": "pink"}},'
              ' {"start_mm": 70, "end_mm": 101.76, "texture": {"kind": "texel", "pitch_db": 6.3,'
              ' "irregularity_db": -12.9, "seed": 8, "texel_samples": 3}}]}')


def test_a_map_in_slabs_plays_what_its_1_kb_chunks_play(monkeypatch):
    """kinds.SLAB > 1 (the firmware: 5 allocations for a full screen, not 38):
    the chunks are memoryviews of bigger blocks and every position plays the
    same value; a block the heap has no room for turns the rest into 1 KB
    chunks (one MemoryError)."""
    scene = json.loads(SLAB_SCENE)
    one = S.build(S.validate(scene, D), D)
    monkeypatch.setattr(kinds, "SLAB", 8)
    slab = S.build(S.validate(scene, D), D)
    views = [c for b in slab.buffers() if type(b) is tuple for c in b]
    assert views and all(type(c) is memoryview and len(c) <= 512 for c in views)
    assert [slab.amp(p) for p in range(D["positions"])] == \
        [one.amp(p) for p in range(D["positions"])]
    real = kinds.u16_one_block          # compat's, imported at kinds' top
    asked = []

    def tight(n):
        asked.append(n)
        if n > 512:
            raise MemoryError
        return real(n)
    monkeypatch.setattr(kinds, "u16_one_block", tight)
    ch = kinds.new_chunks(3000)
    assert [len(c) for c in ch] == [512] * 5 + [440] and all(type(c) is array for c in ch)
    assert asked[0] == 3000 and max(asked[1:]) == 512


SLAB_SCRIPT = r"""
from texel.runtime import kinds
sc_txt = %(scene)s
kinds.SLAB = 1
one = S.build(S.validate(sc_txt, disp), disp)
kinds.SLAB = 8
slab = S.build(S.validate(sc_txt, disp), disp)
views = [type(c).__name__ for b in slab.buffers() if type(b) is tuple for c in b]
same = all(one.amp(p) == slab.amp(p) for p in range(19200))
seq = raw_script(6000, 3)
rp, dp, cp = make("py", seq)
rv, dv, cv = make("viper", seq)
rp.swap(one)
rv.swap(slab)
mism = 0
for k in range(len(seq)):
    cp[0] = cv[0] = k * 120
    rp.step()
    rv.step()
    if (rp.pos, rp.amp, rp.duty) != (rv.pos, rv.amp, rv.duty) or dp[-1] != dv[-1]:
        mism += 1
from texel import compat
print(json.dumps({"views": sorted(set(views)), "same": same, "mism": mism,
                  "positions": len(set(dp)), "c": bool(compat.core())}))
"""


@pytest.mark.parametrize("with_c", [False, True], ids=["viper", "c-core"])
def test_slabs_through_the_fast_refresh_on_the_unix_port(with_c, x64_core):
    """The unix port: a scene built in slabs (memoryview chunks: their
    addresses through uctypes.addressof, their values by the C core's fill)
    plays through the fused refresh - viper, or the C core's x64 build - what
    the Python refresh plays from 1 KB chunks, refresh by refresh."""
    from test_refresh_viper import COMMON, SCENE_A, SCENE_B
    if with_c and not x64_core:
        pytest.skip("no x64 native module here")
    code = (COMMON % {"cfg": "{}", "scene_a": SCENE_A, "scene_b": SCENE_B}
            + SLAB_SCRIPT % {"scene": SLAB_SCENE})
    got = mpy.run_json(code, timeout=600, **({"extra_path": str(x64_core)} if with_c else {}))
    assert got["views"] == ["memoryview"] and got["same"] is True
    assert got["mism"] == 0 and got["positions"] > 10
    assert got["c"] is with_c


BLOCK = r"""
import gc, json
from texel.runtime import kinds
out = {}
gc.collect()
# garbage until no 8 KB block is free without a collection (the collector held off)
gc.disable()
junk = [None] * 400
try:
    for i in range(400):
        junk[i] = bytearray(400)
except MemoryError:
    pass
junk = None
gc.enable()
out["none_while_garbage"] = kinds._block(4096) is None
out["still_enabled"] = gc.isenabled()
ch = kinds.new_chunks(4096)                 # 1 KB chunks instead, collecting as they need
out["chunks"] = [type(c).__name__ for c in ch]
ch = None
gc.collect()
b = kinds._block(4096)
out["block_after_collect"] = b is not None and len(b) == 4096
b = None
gc.disable()                                # a user's choice stays
kinds._block(4096)
out["user_disable_kept"] = not gc.isenabled()
gc.enable()
print(json.dumps(out))
"""


def test_a_block_is_tried_without_a_collection():
    """kinds._block (new_chunks' 8-chunk blocks, kinds.SLAB): on the real unix port, a
    heap whose free room is garbage gives no block (the allocator's collection is held
    off for the try: on a stock Pico a failed try collected first, ~24 ms), new_chunks'
    1 KB chunks follow, the collector is on again after, a block comes once the garbage
    is collected, and a program's own gc.disable() is left as it was."""
    got = mpy.run_json(BLOCK, heapsize="96k")
    assert got == {"none_while_garbage": True, "still_enabled": True,
                   "chunks": ["array"] * 8, "block_after_collect": True,
                   "user_disable_kept": True}, got
