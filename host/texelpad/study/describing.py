"""Scenes as `texelpad lab describe` lists them (texelpad.study.describe;
each protocol's trial list: texelpad.study.protocols): where each region is,
its texture, a long sample array named rather than listed. Pure logic."""
from __future__ import annotations

import json
from typing import Any

from . import scenes as S


def _where(start: float, end: float, total: float) -> str:
    half = round(total / 2, 6)
    if start == 0 and end == total:
        return "whole display"
    if start == 0 and end == half:
        return "left half"
    if start == half and end == total:
        return "right half"
    return "span"


def _texture(t: dict[str, Any], what: str | None) -> dict[str, Any]:
    if t.get("kind") == "samples":
        return {"kind": "samples", "fit": t.get("fit"), "values": len(t.get("u16", ())),
                "what": what or "display samples"}
    return json.loads(json.dumps(t))


def scene(sc: dict[str, Any], display: dict[str, Any], what: str | None = None
          ) -> list[dict[str, Any]]:
    """A scene's regions: where (left half / right half / whole display /
    a span), start and end mm, the texture (a samples array named by `what`)."""
    total = round(display["positions"] * display["dx_um"] / 1000.0, 6)
    return [{"where": _where(r["start_mm"], r["end_mm"], total), "start_mm": r["start_mm"],
             "end_mm": r["end_mm"], "texture": _texture(r["texture"], what)}
            for r in sc["regions"]]


def option(name: str, sc: dict[str, Any], display: dict[str, Any],
            what: str | None = None) -> dict[str, Any]:
    return {"option": name, "regions": scene(sc, display, what)}


def split(name: str, left: dict[str, Any], right: dict[str, Any],
           display: dict[str, Any]) -> dict[str, Any]:
    """An option whose textures are described, not built (they depend on
    answers): the scene's geometry is scenes.split's."""
    sc = S.split({"kind": "reference", "name": "-"}, {"kind": "texel"}, display)
    regs = scene(sc, display)
    regs[0]["texture"], regs[1]["texture"] = left, right
    return {"option": name, "regions": regs}


def whole(name: str, texture: dict[str, Any], display: dict[str, Any]) -> dict[str, Any]:
    """An option of one described texture on the whole display (scenes.whole's
    geometry)."""
    regs = scene(S.whole({"kind": "reference", "name": "-"}, display), display)
    regs[0]["texture"] = texture
    return {"option": name, "regions": regs}
