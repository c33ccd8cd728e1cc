"""A stock RP2040's reference maps as files (issue 32, the stock path): `texelpad
deploy` writes the study's nine full-screen maps, as this host renders them
(binary64), beside texel/gen/reference.py (lib/texel/gen/ref/<name>.u16, the
firmware's ROMFS files), and a reference region reads the first n values into its
chunks (gen/reference.py file_u16) instead of rendering them - up to 2.2 s a full
screen on the emulated stock Pico. A file that is not whole, a name or length it
does not hold: the map is rendered, as before. On CPython and on the real
interpreters (the unix port, float64 and float32)."""
from __future__ import annotations

import shutil
from array import array
from pathlib import Path

import pytest

from support import mpy
from texel.gen import reference as R
from texel.runtime import kinds, scene as S
from texelpad import toolchain
from texelpad.firmware.romfs import reference_maps

D = {"positions": 19200, "dx_um": 5.3}


@pytest.fixture(scope="module")
def maps() -> dict[str, bytes]:
    return {Path(p).stem: d for p, d in reference_maps().items()}


def _beside(tmp: Path, files: dict[str, bytes]) -> Path:
    """A gen/ folder with ref/<name>.u16 files: the module path file_u16 reads beside
    (R.map_files lists them again: the tests' monkeypatch puts its None back)."""
    (tmp / "gen" / R.FLASH_DIR).mkdir(parents=True, exist_ok=True)
    # (the stored rows' noise, read beside the module too, for the renders compared)
    shutil.copyfile(R.noise_path(), tmp / "gen" / R.NOISE_FILE)
    for name, data in files.items():
        (tmp / "gen" / R.FLASH_DIR / ("%s.u16" % name)).write_bytes(data)
    return tmp / "gen" / "reference.py"


def _chunks(n: int) -> tuple:
    size = 1 << kinds.CHUNK_BITS
    return tuple(array("H", bytes(2 * min(size, n - o))) for o in range(0, n, size))


def test_the_files_are_the_host_maps_the_firmware_plays(maps):
    assert sorted(maps) == sorted(R.STUDY_NAMES)
    for name, data in maps.items():
        assert len(data) == 2 * R.FLASH_SAMPLES
        assert array("H", data).tolist() == list(R.reference_u16(name, R.FLASH_SAMPLES)), name


@pytest.mark.parametrize("n", [1, 511, 512, 513, 9600, 19200])
def test_a_region_reads_the_first_n_values_into_its_chunks(tmp_path, monkeypatch, maps, n):
    monkeypatch.setattr(R, "__file__", str(_beside(tmp_path, maps)))
    monkeypatch.setattr(R, "_FILES", None)
    for name in R.STUDY_NAMES:
        ch = _chunks(n)
        assert R.file_u16(name, n, ch) is True
        assert [v for c in ch for v in c] == list(R.reference_u16(name, n)), (name, n)
    one = array("H", bytes(2 * n))                  # one buffer, not chunks
    assert R.file_u16("pink", n, one) and list(one) == list(R.reference_u16("pink", n))


def test_no_file_a_cut_file_or_a_map_it_does_not_hold_is_not_read(tmp_path, monkeypatch, maps):
    monkeypatch.setattr(R, "_FILES", None)
    monkeypatch.setattr(R, "__file__", str(_beside(tmp_path, {"pink": maps["pink"][:-2],
                                                              "blue": maps["blue"] + b"\0\0",
                                                              "2sin": maps["2sin"]})))
    for name, n in (("pink", 100), ("blue", 100), ("white", 100), ("2sin", 19201),
                    ("bp-4-0.5", 100)):
        assert R.file_u16(name, n, _chunks(n)) is False, name
    assert R.file_u16("2sin", 19200, _chunks(19200)) is True


def _marked(tmp: Path, monkeypatch, maps, **files: bytes) -> None:
    monkeypatch.setattr(R, "_FILES", None)
    monkeypatch.setattr(R, "__file__", str(_beside(tmp, dict(maps, **files))))


def test_a_scene_plays_what_the_file_holds_else_the_render(tmp_path, monkeypatch, maps):
    """The kind reads the file: a file of 1234s plays 1234s (not what the
    render would); a file cut short is rendered over (nothing half-read plays)."""
    scene = {"regions": [{"start_mm": 0, "end_mm": 40, "texture": {"kind": "reference",
                                                                  "name": "3sin"}},
                         {"start_mm": 40, "end_mm": 101.76, "texture": {"kind": "reference",
                                                                       "name": "pink"}}]}
    _marked(tmp_path, monkeypatch, maps, **{"3sin": array("H", [1234] * 19200).tobytes(),
                                            "pink": maps["pink"][:1000]})
    sc = S.build(S.validate(scene, D), D)
    (s0, e0, *_), (s1, e1, *_) = sc.spans()
    assert {sc.amp(p) for p in range(s0, e0)} == {1234}
    assert [sc.amp(p) for p in range(s1, e1)] == list(R.reference_u16("pink", e1 - s1))


SCRIPT = r"""
import json
from array import array
from texel.gen import reference as R
from texel.runtime import kinds
R.__file__ = %(here)r
def chunks(n):
    size = 1 << kinds.CHUNK_BITS
    return tuple(array("H", bytes(2 * min(size, n - o))) for o in range(0, n, size))
got = {}
for name in R.STUDY_NAMES:
    for n in (1, 513, 9601, 19200):
        ch = chunks(n)
        ok = R.file_u16(name, n, ch)
        flat = []
        for c in ch:
            flat.extend(c)
        got["%%s/%%d" %% (name, n)] = [ok, sum(flat), flat[-1]]
# slab chunks (kinds.SLAB > 1: memoryviews of one block, the firmware's and a stock heap's)
kinds.SLAB = 8
ch = kinds.new_chunks(3000)
got["slab"] = [R.file_u16("blue", 3000, ch), [type(c).__name__ for c in ch][:1],
               sum(sum(c) for c in ch)]
got["cut"] = R.file_u16("white", 10, chunks(10))
print(json.dumps(got))
"""


@pytest.mark.parametrize("exe", ["micropython", "micropython-ulab-f32"])
def test_the_files_are_read_so_on_the_real_interpreters(tmp_path, maps, exe):
    path = toolchain.interpreter(exe)
    if path is None:
        pytest.skip("no %s here (../shared/instruments)" % exe)
    here = _beside(tmp_path, dict(maps, white=maps["white"][:-1]))
    got = mpy.run_json(SCRIPT % {"here": str(here)}, exe=path, timeout=300)
    for name in R.STUDY_NAMES:
        for n in (1, 513, 9601, 19200):
            ok, total, last = got["%s/%d" % (name, n)]
            if name == "white":                     # its file one byte short: not read
                assert ok is False
                continue
            want = array("H", maps[name][:2 * n]).tolist()
            assert [ok, total, last] == [True, sum(want), want[-1]], (name, n)
    blue = array("H", maps["blue"][:6000]).tolist()
    assert got["slab"] == [True, ["memoryview"], sum(blue)]
    assert got["cut"] is False
