"""The host refuses, before sending, a scene whose texel region must be planned whole and whose
plan alone is more than the board's free heap (issue 30: `push --texel-samples 1` on a Pico).
The end-to-end case runs on the emulated Pico (tests/host/test_emulated_pico.py, the stock
image after deploy)."""
from __future__ import annotations

import pytest

from texelpad.link.board import check_scene, refuse_what_cannot_fit


def _texel(L: int, v: int = 2, end_mm: float = 101.76) -> dict:
    return {"regions": [{"start_mm": 0, "end_mm": end_mm, "texture": {
        "kind": "texel", "pitch_db": 6, "irregularity_db": -9, "seed": 1, "texel_samples": L,
        "v": v}}]}


# a Pico playing a full-screen 4sin had 67,488 bytes free (the emulated Pico)
PICO = {"mem_free": 67488}


def test_a_full_screen_of_one_sample_texels_is_refused_before_sending_saying_why():
    with pytest.raises(ValueError) as e:
        refuse_what_cannot_fit(check_scene(_texel(1)), PICO)
    assert str(e.value) == (
        "scene: region 0 renders 19200 texels (texel_samples 1): the generator plans them all "
        "first, 12 bytes a texel (230400 bytes) besides its map; texel_samples 5 .. 65535 plays "
        "from the plan instead (8 bytes a texel); the board has 67488 bytes free in all "
        "(refused before sending)")
    # format 1 counts a board's float32 pitch and phase: 16 bytes a texel
    with pytest.raises(ValueError, match=r"16 bytes a texel \(307200 bytes\)"):
        refuse_what_cannot_fit(check_scene(_texel(1, v=1)), PICO)


@pytest.mark.parametrize("scene, free", [
    (_texel(2), 153600),                 # 9,600 texels x 12 = 115,200: may fit, the board decides
    (_texel(1, end_mm=20.0), 67488),     # 3,774 texels x 12 = 45,288
    (_texel(5), 1000),                   # plays from its plan: nothing planned whole
    (_texel(1), None),                   # a status without mem_free: the board decides
])
def test_what_could_fit_is_left_to_the_board(scene, free):
    refuse_what_cannot_fit(check_scene(scene), {} if free is None else {"mem_free": free})
