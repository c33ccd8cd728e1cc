"""What a protocol's question plays: the scenes the participant feels, as plain
scene dicts for Board.push (pure logic: the board is the web layer's).

Pursuit and search (seeds 000, 003): the reference on the left half of the
display, the option's texel rendering on the right (SPEC §5: "reference on the
left half, texel rendering on the right"); each option is one scene, and the
participant switches between them. Staircase (seed 001): each of the three
textures fills the display with texels of the trial's length; two of them
share a seed. Texel textures are the config's "texture_format": 2 (the
integer plan: the same texture on every board) unless the config says 1 (the
lab's float generator, the exact original); a session's header records it,
and a header without one (sessions before the field) played format 2.
"""
from __future__ import annotations

import random
from typing import Any

from texel.gen.params import FORMAT_NEW



DEFAULT_REFERENCE = {"kind": "reference", "name": "4sin"}


def texture_format(config: dict[str, Any] | None) -> int:
    """The texture format a study config (a session header's "config") asks
    for: its "texture_format", 2 when it has none. ValueError for anything but
    1 or 2."""
    v = (config or {}).get("texture_format", FORMAT_NEW)
    if type(v) is not int or v not in (1, 2):      # not True, not 2.0: "v" is an int
        raise ValueError("texture_format: expected 1 (the lab's float generator, the exact "
                         "original) or 2 (the integer plan, the same texture on every "
                         "board), got %r" % (v,))
    return v


def _total_mm(display: dict[str, Any]) -> float:
    return round(display["positions"] * display["dx_um"] / 1000.0, 6)


def positions(display: dict[str, Any], whole: bool = True) -> int:
    """How many display samples the whole display (or split's right half) holds,
    rounded as the board maps millimetres to positions (texel/runtime/scene.py)."""
    total = _total_mm(display)
    start = 0.0 if whole else round(total / 2, 6)
    at = lambda mm: min(display["positions"], int(mm * 1000.0 / display["dx_um"] + 0.5))  # noqa: E731
    return at(total) - at(start)


def split(reference: dict[str, Any], texel: dict[str, Any], display: dict[str, Any],
          name: str = "") -> dict[str, Any]:
    """Reference on the left half, a rendering on the right half: texel
    parameters (kind "texel" added), or a texture that names its kind (the
    rater's logged sequence as "samples")."""
    total = _total_mm(display)
    half = round(total / 2, 6)
    scene: dict[str, Any] = {"regions": [{"start_mm": 0, "end_mm": half,
                                          "texture": dict(reference)},
                         {"start_mm": half, "end_mm": total,
                          "texture": texel if "kind" in texel else dict(texel, kind="texel")}]}
    if name:
        scene["name"] = name
    return scene


def whole(texture: dict[str, Any], display: dict[str, Any], name: str = "") -> dict[str, Any]:
    """One texture on the whole display (texel parameters get kind "texel")."""
    tex = texture if "kind" in texture else dict(texture, kind="texel")
    scene: dict[str, Any] = {"regions": [{"start_mm": 0, "end_mm": _total_mm(display),
                                          "texture": dict(tex)}]}
    if name:
        scene["name"] = name
    return scene


def staircase_scenes(length_samples: int, trial: int, seed: int, display: dict[str, Any],
                     distribution: dict[str, Any], v: int = FORMAT_NEW,
                     remainder_level: float = 0.0, fit_mm: float | None = None
                     ) -> tuple[list[dict[str, Any]], int]:
    """The three textures of a trial and the index of the odd one: two seeds,
    one shown twice, in an order drawn from (seed, trial). With fit_mm each
    holds as many whole texels as fit in fit_mm and in the display (seed 001)
    and the rest plays the constant remainder_level; without, one texel
    region fills the display."""
    rng = random.Random(seed * 100003 + trial)
    same, odd = rng.randrange(1 << 31), rng.randrange(1 << 31)
    seeds = [same, same, odd]
    rng.shuffle(seeds)
    total = _total_mm(display)
    end = total
    if fit_mm is not None:
        room = min(display["positions"], int(fit_mm * 1000.0 / display["dx_um"] + 1e-9))
        whole = (room // length_samples) * length_samples
        if whole:
            end = round(whole * display["dx_um"] / 1000.0, 6)
    scenes = []
    for k, s in enumerate(seeds):
        regions: list[dict[str, Any]] = [{"start_mm": 0, "end_mm": end, "texture": dict(
            distribution, kind="texel", texel_samples=length_samples, seed=s, v=v)}]
        if end < total:
            regions.append({"start_mm": end, "end_mm": total,
                            "texture": {"kind": "constant", "level": float(remainder_level)}})
        scenes.append({"regions": regions, "name": "texture %d" % (k + 1)})
    return scenes, seeds.index(odd)
