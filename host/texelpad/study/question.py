"""A question as the lab asks it (texelpad.study.questions: the protocols'
own, texelpad.study.protocols) and what every protocol's asking shares: the
reference and texture format a session's header names, points in dB, the
scene of a slider setting. Pure logic."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

from . import scenes as S
from .space import Point, irregularity_db, pitch_db, texel_params


@dataclass
class Question:
    public: dict[str, Any]
    options: list[dict[str, Any]] = field(default_factory=list)
    detail: dict[str, Any] = field(default_factory=dict)
    odd: int | None = None          # the staircase's odd texture (never public)

    @property
    def done(self) -> bool:
        return bool(self.public["done"])


def reference_of(header: dict[str, Any]) -> dict[str, Any]:
    return header["config"].get("reference") or S.DEFAULT_REFERENCE


def format_of(header: dict[str, Any]) -> int:
    """The texel textures' format: the config's texture_format (2 unless it
    says 1; a header from before the field played format 2)."""
    return S.texture_format(header.get("config"))


def db_of(p: Point) -> dict[str, float]:
    return {"pitch_db": round(pitch_db(p.u), 3), "irregularity_db": round(irregularity_db(p.v), 3)}


def mean_of(st: Any) -> dict[str, Any]:
    m = st.mean
    return dict(db_of(Point(m[0], m[1])), x=m)


def slider_scene(st: Any, header: dict[str, Any], display: dict[str, Any], a: Any, b: Any,
                 move: int) -> tuple[dict[str, Any], tuple[float, float]]:
    """The scene of a sliding protocol (the free exploration; the mapping's
    first phase) for a slider setting - its reference left, the rendering
    right - and the setting as kept (free: 0.001 dB; mapping: the slider's
    step). ValueError for a value off the sliders."""
    p, s = st.check(a, b)
    return S.split(st.reference_texture(), st.texture(p, s, move, format_of(header)),
                   display, name="rendering"), (p, s)


def js(x: Any) -> str:
    try:
        return json.dumps(x, sort_keys=True)
    except (TypeError, ValueError):
        return repr(x)


def played_db(p: Point) -> dict[str, float]:
    """The point as the display plays it, in dB (clamped: texelpad.study.space):
    where a guided exploration or a search ended."""
    t = texel_params(p)
    return {"pitch_db": t["pitch_db"], "irregularity_db": t["irregularity_db"]}
