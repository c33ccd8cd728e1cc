"""The normalised texel space the guided exploration (seed 000, ../shared/SPEC.md
§5) and the preference search (seed 003, SPEC §7) move in, and the texel
parameters a point stands for.

    P     = 10^(4u - 1.5) c/mm   ->  pitch_db        = 40u - 15 dB
    sigma = 10^(3v - 2.5) decades ->  irregularity_db = 30v - 25 dB

u, v in [0, 1]. A texel texture's central pitch ends at Nyquist (19.747 dB,
u = 0.8687; texel.gen.params PITCH_DB_MAX). A point beyond it either becomes
the texture at Nyquist (texel_params: clamped) or plays as the lab's apps
played it - buildFine5 accumulates the phase of any pitch, so its samples
alias - as display samples rendered here (aliased_samples). Which: the
protocol's config field `above_nyquist` ("alias" | "clamp"; the pursuit's
default "alias", the guided app's; the search's "clamp"), recorded in every
session header. Pure logic: no link, no web framework.

Below both of its users: texelpad.search imports it, texelpad.study imports it
(as texelpad.study.space) and the search; neither is imported from here
(docs/architecture.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from texel.gen.params import IRREG_DB_MAX, IRREG_DB_MIN, PITCH_DB_MAX, PITCH_DB_MIN

ABOVE_NYQUIST = ("alias", "clamp")

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


def check_above_nyquist(value: object) -> None:
    if value not in ABOVE_NYQUIST:
        raise ValueError("above_nyquist: expected 'alias' (a point above the display's Nyquist "
                         "pitch plays aliased, as the lab's app) or 'clamp' (it plays at "
                         "Nyquist), got %r" % (value,))


def is_above_nyquist(p: Point) -> bool:
    """Whether the point's pitch (in the unit square) is above what a texel
    texture's pitch_db may be (19.747 dB)."""
    return round(pitch_db(p.clamped().u), 3) > PITCH_DB_MAX


def aliased_samples(p: Point, n: int, **extra) -> dict:
    """The point's texture as n display samples ({"kind": "samples", "fit":
    "tile", "u16": [...]}), its pitch as it stands even above Nyquist: the
    texel generator's own plan and engine (format extra["v"], 2 by default),
    given the parameter set validate() returns for the texture at Nyquist with
    the pitch put back. The plan takes any pitch up to 2^15 c/mm (gen/plan_int.py
    clamps there); every texel's phase steps by more than half a turn, so
    the samples alias as the app's buildFine5 did. For a point at or below
    Nyquist the same samples as its texel texture (a test checks)."""
    import texel
    from texel.gen import engine_int        # (what a board plays: the int engine)
    from texel.gen.plan_numpy import make_plan
    t = texel_params(p, **extra)
    t["pitch_db"] = round(pitch_db(p.clamped().u), 3)
    checked = texel.validate(dict(t, pitch_db=min(t["pitch_db"], PITCH_DB_MAX),
                                  length_samples=n))
    checked["pitch_db"] = t["pitch_db"]
    u16 = engine_int.render_u16(make_plan(checked), None)
    return {"kind": "samples", "fit": "tile", "u16": [int(x) for x in u16]}
