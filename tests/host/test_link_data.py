"""The link's frames for the board's standing reader (protocol.staged_frame),
and the answers a board's C core prints (texel.wire.say: each float32 as its
bits, `<bits>j`) read back on the host (protocol.floats_from_bits): every
float32 comes back as the shortest decimal that is that float32 again -
numpy's float32 repr - and nothing else changes."""
import ast
import random
import struct

import numpy as np
import pytest

from texelpad.link.protocol import _f32, floats_from_bits


def _bits(x):
    return struct.unpack("<I", struct.pack("<f", x))[0]


def test_every_float32_comes_back_as_its_shortest_decimal():
    rng = random.Random(5)
    hard = [0, 0x80000000, 1, 0x807FFFFF, 0x00800000, 0x7F7FFFFF, 0xFF7FFFFF, 0x3F800000,
            0x3F800001, 0x4B7FFFFF, 0x4B800000, _bits(0.1), _bits(175.16121), _bits(-12.9)]
    for b in hard + [rng.getrandbits(32) for _ in range(20000)]:
        x = np.frombuffer(struct.pack("<I", b), dtype=np.float32)[0]
        y = _f32(b)
        if np.isnan(x):
            assert y != y
            continue
        assert struct.pack("<f", y) == struct.pack("<I", b)       # the same float32
        assert y == float(str(x))                                   # numpy's shortest


def test_floats_from_bits_walks_an_answer_and_keeps_the_rest():
    line = ("('ok', {'scene': {'regions': [{'pitch_db': %dj, 'start': 0, 'kind': 'texel', "
            "'x': (1, %dj), 'e': [], 't': (%dj,)}]}, 'late': None, 'v': True, 'n': -7})"
            % (_bits(6.3), _bits(-0.0), _bits(float("inf"))))
    got = floats_from_bits(ast.literal_eval(line))
    r = got[1]["scene"]["regions"][0]
    assert r["pitch_db"] == 6.3 and r["start"] == 0 and r["kind"] == "texel" and r["e"] == []
    assert r["x"][0] == 1 and str(r["x"][1]) == "-0.0" and r["t"] == (float("inf"),)
    assert got[1]["late"] is None and got[1]["v"] is True and got[1]["n"] == -7


@pytest.mark.parametrize("bad", ["1.5j", "(1+2j)", "4294967296j", "-3j"])
def test_a_complex_that_is_no_float_s_bits_is_refused(bad):
    with pytest.raises(ValueError, match="not a float's bits"):
        floats_from_bits(ast.literal_eval(bad))


def test_a_frame_is_its_counts_a_json_header_and_the_scenes_json():
    """protocol.staged_frame (texel.wire.stand's frames): "[", the data's byte
    count, ",", the header's, ",", the header - plain JSON: the function, the
    upload slots, the other arguments, where the scene goes, the keyword
    arguments - then the scene's JSON, UTF-8 (counted in bytes, not
    characters), no control byte anywhere (a Ctrl-C would interrupt the board);
    what cannot cross the link is refused as staged_call refuses it."""
    import json

    from texelpad.link.protocol import LiteralError, scene_text, staged_frame
    scene = {"name": "café\nline", "regions": [{"start_mm": 0, "end_mm": 10, "texture": {
        "kind": "constant", "level": 0.5}}]}
    head, data = staged_frame("start", ["pico", scene], 1, {0: 2}, {"realtime": "é"})
    n, h, header = head[1:].split(b",", 2)
    assert head[:1] == b"[" and int(n) == len(data) and int(h) == len(header)
    assert json.loads(header) == ["start", [[0, 2]], ["pico"], 1, {"realtime": "é"}]
    assert not any(b < 0x20 for b in head + data)
    assert data == scene_text(scene).encode("utf-8") and len(data) > len(scene_text(scene))
    assert json.loads(data) == scene
    for bad in ({"regions": [], "x": float("nan")}, {"regions": [], "x": object()}):
        with pytest.raises(LiteralError):
            staged_frame("pushed", [bad], 0)
    with pytest.raises(LiteralError):
        staged_frame("pushed", [scene, float("inf")], 0)
