"""Free exploration (seed 000, "Free exploration"; ../shared/SPEC.md §5), as a
state machine: nine trials, one per reference texture, in an order drawn from
the session's seed. In each trial the reference plays on the left half of the
display and the texel rendering of two sliders - central pitch and
irregularity - on the right; every slider change re-draws the rendering (a
fresh texture seed per change, drawn from the session's seed, so a session
replays exactly) and is pushed to the board. When satisfied the participant
rates their confidence 1..5 and submits: that is the trial's answer.

Choices the paper leaves open, recorded in Config (and so in every session
file's header):
- the pitch slider spans -10 .. 20 dB (SPEC §5); the display ends at Nyquist
  (19.747 dB, texel.gen.params.PITCH_DB_MAX), so a setting above it plays at
  Nyquist; the session records both the slider's value and the texture played;
- the irregularity slider spans sigma = 0.001 .. 1 decade, -30 .. 0 dB (SPEC
  §5: "sigma 0 .. 1 decade"; 0.001 decade is the generator's least,
  texel.gen.params.IRREG_DB_MIN);
- both sliders start in the middle of their range (5 dB, -15 dB);
- texel length 0.25 mm (seed 000) = 47 display samples of 5.3 um (0.249 mm);
- values are kept to 0.001 dB, the format-2 grid (texel.gen.grid), so the
  texture is the same on every board.

Answers: {"pitch_db": x, "irregularity_db": y, "confidence": 1..5}. Pure logic.
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from typing import Any

from texel.gen.params import FORMAT_NEW, PITCH_DB_MAX
from texel.gen.reference import STUDY_NAMES as NINE     # the nine, in the golden data's order


@dataclass(frozen=True)
class Config:
    references: tuple[str, ...] = NINE
    pitch_db: tuple[float, float] = (-10.0, 20.0)
    irregularity_db: tuple[float, float] = (-30.0, 0.0)
    start: tuple[float, float] = (5.0, -15.0)
    texel_samples: int = 47
    confidence: tuple[int, int] = (1, 5)

    def __post_init__(self) -> None:
        check_references(self.references)
        for name in ("pitch_db", "irregularity_db"):
            lo, hi = getattr(self, name)
            if not lo < hi:
                raise ValueError("%s: expected [low, high], got %r" % (name, getattr(self, name)))
        if not (self.pitch_db[0] <= self.start[0] <= self.pitch_db[1]
                and self.irregularity_db[0] <= self.start[1] <= self.irregularity_db[1]):
            raise ValueError("start: %r is outside the sliders' ranges" % (self.start,))


def check_references(refs: tuple[str, ...]) -> None:
    if not refs or any(r not in NINE for r in refs) or len(set(refs)) != len(refs):
        raise ValueError("references: expected distinct names among %s, got %r"
                         % (", ".join(NINE), refs))


def _number(what: str, x: Any, lo: float, hi: float) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
        raise ValueError("%s: expected a number, got %r" % (what, x))
    if not lo <= x <= hi:
        raise ValueError("%s: %r is outside the slider's %g .. %g dB" % (what, x, lo, hi))
    return round(float(x), 3)


@dataclass
class Free:
    seed: int
    config: Config = field(default_factory=Config)
    trial: int = 0
    matches: list[dict[str, Any]] = field(default_factory=list)   # one per finished trial

    def __post_init__(self) -> None:
        order = list(self.config.references)
        random.Random(self.seed).shuffle(order)
        self.order = order

    @property
    def done(self) -> bool:
        return self.trial >= len(self.order)

    @property
    def reference(self) -> str:
        return self.order[self.trial]

    def check(self, pitch_db: Any, irregularity_db: Any) -> tuple[float, float]:
        """Slider values, checked and on the 0.001 dB grid."""
        c = self.config
        return (_number("pitch_db", pitch_db, *c.pitch_db),
                _number("irregularity_db", irregularity_db, *c.irregularity_db))

    def texture(self, pitch_db: float, irregularity_db: float, move: int,
                v: int = FORMAT_NEW) -> dict[str, Any]:
        """The texel rendering of the sliders at the trial's move-th change: a
        parameter set of format v (the config's texture_format: 2 unless it
        says 1) with its own seed (each change re-draws)."""
        rng = random.Random((self.seed * 1000003 + self.trial) * 1000003 + move)
        return {"pitch_db": min(PITCH_DB_MAX, pitch_db), "irregularity_db": irregularity_db,
                "texel_samples": self.config.texel_samples,
                "seed": rng.randrange(1 << 32), "v": v}

    def checked_answer(self, a: Any) -> dict[str, Any]:
        """The answer checked and on the grid (ValueError says why)."""
        if self.done:
            raise ValueError("the free exploration is finished: nothing to answer")
        if not isinstance(a, dict) or set(a) != {"pitch_db", "irregularity_db", "confidence"}:
            raise ValueError("answer: expected {pitch_db, irregularity_db, confidence}, got %r"
                             % (a,))
        p, s = self.check(a["pitch_db"], a["irregularity_db"])
        lo, hi = self.config.confidence
        c = a["confidence"]
        if isinstance(c, bool) or not isinstance(c, int) or not lo <= c <= hi:
            raise ValueError("confidence: expected %d .. %d, got %r" % (lo, hi, c))
        return {"pitch_db": p, "irregularity_db": s, "confidence": c}

    def answer(self, a: Any) -> dict[str, Any]:
        a = self.checked_answer(a)
        entry = dict(a, trial=self.trial, reference=self.reference)
        self.matches.append(entry)
        self.trial += 1
        return entry

    def match_of(self, reference: str) -> dict[str, float] | None:
        """The participant's match of a reference (for the quantization test)."""
        for m in self.matches:
            if m["reference"] == reference:
                return {"pitch_db": m["pitch_db"], "irregularity_db": m["irregularity_db"]}
        return None
