"""A push whose scene does not fit beside the one playing is built in the playing scene's room
(texel.app.MAKE_ROOM, issue 34: on a board without flash maps - the pyboard - 62 of 100 mixed
pushes were refused for memory): the display plays idle while it builds, and status()'s
last_push says made_room. If even that room is too small, the old scene is built again and
plays on, and the push is refused saying so. Real MemoryErrors: the MicroPython unix port on
heaps of several sizes, the virtual board playing the split screen, a full-screen reference
pushed (its 38.4 KB map does not fit beside the split screen's 20 KB on the small heaps)."""
from __future__ import annotations

import pytest

from support import mpy

SCRIPT = r"""
import json, gc
import texel.app as app
SPLIT = {"regions": [
    {"start_mm": 0, "end_mm": 50.88, "texture": {"kind": "reference", "name": "4sin"}},
    {"start_mm": 50.88, "end_mm": 101.76, "texture": {"kind": "texel", "pitch_db": 6.3,
     "irregularity_db": -12.9, "seed": 7}}]}
FULL = {"regions": [{"start_mm": 0, "end_mm": 101.76,
                     "texture": {"kind": "reference", "name": "pink"}}]}
try:
    app.start("virtual", SPLIT, record=64)
except Exception as e:
    print(json.dumps({"no_start": repr(e)}))
    raise SystemExit
def playing():
    sc = app._rt.refresh.scene
    if sc is None:
        return None
    return [r["texture"].get("name", r["texture"]["kind"]) for r in sc.source["regions"]]
app.MAKE_ROOM = %(make_room)r
res = {"before": playing()}
try:
    st = app.push(FULL)
    res["outcome"] = "made_room" if st["last_push"].get("made_room") else "beside"
except ValueError as e:
    res["outcome"] = str(e)
res["after"] = playing()
res["running"] = app.status()["running"]
# the scene playing answers at every position (nothing left half-built)
sc = app._rt.refresh.scene
res["amps"] = [sc.amp(p) for p in (0, 9599, 9600, 19199)] if sc is not None else []
print(json.dumps(res))
"""


_TREE: list = []


def _run(kb: int, make_room: bool) -> dict:
    # the compiled image, as a board loads it (compiling from source fragments the heap)
    if not _TREE:
        import tempfile
        from pathlib import Path
        from texelpad import image
        tree = Path(tempfile.mkdtemp(prefix="make-room-")) / "image"
        image.write_tree(image.build_image(image.TARGETS["unix"], include_main=False), tree)
        _TREE.append(tree / "lib")
    return mpy.run_json(SCRIPT % {"make_room": make_room}, heapsize="%dk" % kb, path=_TREE[0])


def test_a_scene_too_big_beside_the_playing_one_is_built_in_its_room():
    seen = {}
    for kb in range(200, 401, 8):
        res = _run(kb, True)
        if "no_start" in res:
            continue
        out = res["outcome"]
        seen.setdefault(out if out in ("beside", "made_room") else "refused", kb)
        assert res["running"] and res["before"] == ["4sin", "texel"], (kb, res)
        if out in ("beside", "made_room"):
            assert res["after"] == ["pink"], (kb, res)
        elif res["after"] is None:
            # refused, and the old scene no longer fitted either: idle, and it says so
            assert "no longer fits either: the display plays idle" in out, (kb, out)
        else:
            # refused: the old scene was built again and plays, and the refusal says so
            assert "not even in the playing scene's room" in out, (kb, out)
            assert res["after"] == ["4sin", "texel"], (kb, res)
            assert "built again and plays on" in out, (kb, out)
    print("\nfull-screen reference pushed over the split screen, first heap (KB) per outcome: %s"
          % seen)
    assert "made_room" in seen and "beside" in seen, seen
    # without make-room, the heap that made room refuses and keeps the split screen untouched
    res = _run(seen["made_room"], False)
    assert res["outcome"].startswith("scene: out of memory") and "push a small scene first" \
        in res["outcome"], res
    assert res["after"] == ["4sin", "texel"] and res["running"], res


@pytest.mark.parametrize("kb", [256])
def test_the_refresh_plays_idle_not_garbage_while_it_makes_room(kb):
    # (the swap to None is one store: refresh.scene None plays the idle amplitude)
    res = _run(kb, True)
    if "no_start" in res:
        pytest.skip(res["no_start"])
    assert all(0 <= a <= 65535 for a in res["amps"]), res


def test_the_push_line_says_when_the_display_was_idle():
    from texelpad.cli.board import board_push_time
    lp = {"validate_us": 500, "build_us": 71000, "swap_us": 700}
    assert board_push_time(lp) == ("; on the board's own clock: validate 0.5 + build 71.0 + "
                                   "swap 0.7 = 72.2 ms")
    assert board_push_time(dict(lp, made_room=True)).endswith(
        "; it did not fit beside the scene that played, so the display was idle for the 71.0 "
        "ms of its build")


def test_a_first_try_that_room_follows_does_not_measure_the_heap(monkeypatch):
    """scene.build(words=False) (texel.app._build_beside, when _make_room will
    try again): its OutOfMemory says no more, and the heap is not measured
    (compat.memory_words: trial allocations, each failing one a collection on a
    board); words=True (the try whose message a user reads) measures it."""
    from texel import compat
    from texel.runtime import scene as S
    D = {"positions": 19200, "dx_um": 5.3}
    scene = {"regions": [{"start_mm": 0, "end_mm": 101.76,
                          "texture": {"kind": "constant", "level": 0.5}}]}
    calls = []
    monkeypatch.setattr(compat, "memory_words", lambda *a: calls.append(a) or "W")

    def full(*a, **kw):
        raise MemoryError
    monkeypatch.setattr(S, "_make", full)
    with pytest.raises(S.OutOfMemory, match=r"^scene: out of memory while building$"):
        S.build(scene, D, words=False)
    assert calls == []
    with pytest.raises(S.OutOfMemory, match=r"\(needs \d+ bytes.*W\)"):
        S.build(scene, D)
    assert len(calls) == 1


def test_a_failed_new_chunks_holds_none_of_its_chunks(monkeypatch):
    """kinds.new_chunks empties its list before its MemoryError leaves: a
    reference to its frame that outlives the call (here the traceback; on a
    board a stale stack slot the collector scans) keeps no chunk alive."""
    import weakref
    from texel.runtime import kinds
    made = []
    real = kinds.u16_one_block          # compat's, imported at kinds' top

    def three(n):
        if len(made) == 3:
            raise MemoryError
        a = real(n)
        made.append(weakref.ref(a))
        return a
    monkeypatch.setattr(kinds, "u16_one_block", three)
    monkeypatch.setattr(kinds, "SLAB", 1)
    try:
        kinds.new_chunks(5000)
    except MemoryError as e:
        tb = e.__traceback__                # holds new_chunks' frame
    assert tb is not None and len(made) == 3
    assert [r() for r in made] == [None, None, None]



STALE = r"""
import json, gc
import texel.app as app
from texel.runtime import refresh_fast as rf
try:
    app.start("virtual", {"regions": [{"start_mm": 0, "end_mm": 101.76,
                          "texture": {"kind": "reference", "name": "2sin"}}]}, record=64)
except Exception as e:
    print(json.dumps({"no_start": repr(e)}))
    raise SystemExit
fr = app._rt.refresh
res = {"fast": isinstance(fr, rf.FastRefresh), "threaded": getattr(fr, "threaded", None)}
# what a refresh interrupt's frame can leave on a board's stack: the playing W
stale = [rf._W]
gc.collect()
before = gc.mem_free()
fr.swap(None)
gc.collect()
res["freed"] = gc.mem_free() - before
res["w_words"] = sum(1 for v in stale[0] if v)
print(json.dumps(res))
"""


def test_a_stale_slot_naming_the_dropped_w_keeps_no_map_alive():
    """refresh_fast._wipe: the W, table copy and chunk tables of the generation a swap
    dropped hold raw addresses of its buffers, and MicroPython's collector reads every word
    of a block it reaches. A slot still naming the old W (on a board: a refresh interrupt's
    frame; here a list) kept the full-screen map alive - on the emulated pyboard 1-6 of 60
    reference-over-reference pushes then found no room and played idle. Zeroed, the map goes
    with its scene. The real unix port and its virtual board (one thread: threaded False).
    A 64-bit port's W holds its buffers as 32-bit offsets from a base (refresh_fast W_BASE),
    not pointers, so there the map went anyway: the emulated pyboard
    (test_firmware_pyboard.py) holds a W through a push and a start and checks the room."""
    res = mpy.run_json(STALE)
    assert res["fast"] and res["threaded"] is False, res
    assert res["w_words"] == 0 and res["freed"] >= 38400, res

