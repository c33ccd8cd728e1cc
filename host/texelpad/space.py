"""The normalised texel space the guided exploration (seed 000, ../shared/SPEC.md
§5) and the preference search (seed 003, SPEC §7) move in, and the texel
parameters a point stands for.

    P     = 10^(4u - 1.5) c/mm   ->  pitch_db        = 40u - 15 dB
    sigma = 10^(3v - 2.5) decades ->  irregularity_db = 30v - 25 dB

u, v in [0, 1]. The pitch the display can show ends at Nyquist (19.747 dB,
u = 0.8687): a point beyond it is clamped to Nyquist when it becomes a texture
(docs: the study protocols' configs record this choice). Pure logic: no link,
no web framework.

Below both of its users: texelpad.search imports it, texelpad.study imports it
(as texelpad.study.space) and the search; neither is imported from here
(docs/architecture.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from texel.gen.params import IRREG_DB_MAX, IRREG_DB_MIN, PITCH_DB_MAX, PITCH_DB_MIN

PITCH_DB_PER_U = 40.0
PITCH_DB_AT_0 = -15.0
IRREG_DB_PER_V = 30.0
IRREG_DB_AT_0 = -25.0


@dataclass(frozen=True)
class Point:
    """A point of the unit square (u: pitch, v: irregularity)."""
    u: float
    v: float

    def __post_init__(self) -> None:
        for name, x in (("u", self.u), ("v", self.v)):
            if not isinstance(x, (int, float)) or isinstance(x, bool) or not math.isfinite(x):
                raise ValueError("%s: expected a finite number, got %r" % (name, x))

    def clamped(self) -> "Point":
        return Point(min(1.0, max(0.0, self.u)), min(1.0, max(0.0, self.v)))

    def distance(self, other: "Point") -> float:
        return math.hypot(self.u - other.u, self.v - other.v)


def pitch_db(u: float) -> float:
    return PITCH_DB_AT_0 + PITCH_DB_PER_U * u


def irregularity_db(v: float) -> float:
    return IRREG_DB_AT_0 + IRREG_DB_PER_V * v


def to_point(pitch: float, irregularity: float) -> Point:
    """The point of (pitch_db, irregularity_db)."""
    return Point((pitch - PITCH_DB_AT_0) / PITCH_DB_PER_U,
                 (irregularity - IRREG_DB_AT_0) / IRREG_DB_PER_V)


def texel_params(p: Point, **extra) -> dict:
    """The texel parameter set of a point (clamped to the unit square and to
    what texel.validate allows: pitch at most Nyquist), rounded to 0.001 dB
    so it is a format-2 parameter set as it stands (the texture the board
    plays is then the same on every runtime). extra: texel_samples, seed,
    gain, v ... as given."""
    q = p.clamped()
    out = {"pitch_db": round(min(PITCH_DB_MAX, max(PITCH_DB_MIN, pitch_db(q.u))), 3),
           "irregularity_db": round(min(IRREG_DB_MAX, max(IRREG_DB_MIN, irregularity_db(q.v))), 3)}
    out.update(extra)
    return out
