"""The quantization test (seed 000, "Quantization test"; ../shared/SPEC.md §5):
the participant rates the similarity 1..5 of a reference texture (left half)
and its texel rendering (right half) quantized at q = 0 (off), 1, 3 and 5 dB.
The rendering is the participant's own free-exploration match of that
reference, or a given match (a trained rater's): the config holds the matches
either way, so the session file says exactly what was rendered.

Choices the paper leaves open, recorded in Config: the references are the
three family exemplars (4sin, pink, sawtooth; seed 000 "Family Exemplars"),
each level once per reference (`repeats`), all trials in one order drawn from
the session's seed; the texture seed is the same for a reference's four levels
(only the quantization differs) and is drawn from the session's seed; texel
length 0.25 mm (47 samples) as in the free exploration.

Answers: the similarity rating, an int 1..5. Pure logic.
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from typing import Any

from .free import check_references
from texel.gen.params import IRREG_DB_MAX, IRREG_DB_MIN, PITCH_DB_MAX, PITCH_DB_MIN, QUANT_DB_MAX

EXEMPLARS = ("4sin", "pink", "sawtooth")


@dataclass(frozen=True)
class Config:
    matches: dict[str, dict[str, float]]
    references: tuple[str, ...] = EXEMPLARS
    levels_db: tuple[float, ...] = (0.0, 1.0, 3.0, 5.0)
    repeats: int = 1
    texel_samples: int = 47
    scale: tuple[int, int] = (1, 5)
    match_source: str = "given"         # "given" or the free-exploration session's id

    def __post_init__(self) -> None:
        check_references(self.references)
        if not isinstance(self.matches, dict):
            raise ValueError("matches: expected {reference: {pitch_db, irregularity_db}}")
        for r in self.references:
            m = self.matches.get(r)
            if not isinstance(m, dict) or set(m) != {"pitch_db", "irregularity_db"}:
                raise ValueError("matches: no {pitch_db, irregularity_db} for %r" % (r,))
            for k, lo, hi in (("pitch_db", PITCH_DB_MIN, PITCH_DB_MAX),
                              ("irregularity_db", IRREG_DB_MIN, IRREG_DB_MAX)):
                v = m[k]
                if isinstance(v, bool) or not isinstance(v, (int, float)) \
                        or not math.isfinite(v) or not lo <= v <= hi:
                    raise ValueError("matches: %s of %r must be in %g .. %g, got %r"
                                     % (k, r, lo, hi, v))
        for q in self.levels_db:
            if isinstance(q, bool) or not isinstance(q, (int, float)) \
                    or not (q == 0 or 0.001 <= q <= QUANT_DB_MAX):
                raise ValueError("levels_db: each 0 (off) or 0.001 .. %g dB, got %r"
                                 % (QUANT_DB_MAX, q))
        if isinstance(self.repeats, bool) or not isinstance(self.repeats, int) \
                or not 1 <= self.repeats <= 10:
            raise ValueError("repeats: expected 1 .. 10, got %r" % (self.repeats,))


@dataclass
class Quant:
    seed: int
    config: Config
    ratings: list[dict[str, Any]] = field(default_factory=list)

    def __post_init__(self) -> None:
        rng = random.Random(self.seed)
        c = self.config
        self.texture_seeds = {r: rng.randrange(1 << 32) for r in c.references}
        trials = [(r, float(q)) for r in c.references for q in c.levels_db] * c.repeats
        rng.shuffle(trials)
        self.trials = trials

    @property
    def trial(self) -> int:
        return len(self.ratings)

    @property
    def done(self) -> bool:
        return self.trial >= len(self.trials)

    @property
    def current(self) -> tuple[str, float]:
        return self.trials[self.trial]

    def texture(self) -> dict[str, Any]:
        """The current trial's rendering: the match, quantized (format 2)."""
        ref, q = self.current
        m = self.config.matches[ref]
        return {"pitch_db": round(float(m["pitch_db"]), 3),
                "irregularity_db": round(float(m["irregularity_db"]), 3),
                "quant_db": q, "texel_samples": self.config.texel_samples,
                "seed": self.texture_seeds[ref], "v": 2}

    def answer(self, rating: Any) -> dict[str, Any]:
        if self.done:
            raise ValueError("the quantization test is finished: nothing to answer")
        lo, hi = self.config.scale
        if isinstance(rating, bool) or not isinstance(rating, int) or not lo <= rating <= hi:
            raise ValueError("similarity: expected %d .. %d, got %r" % (lo, hi, rating))
        ref, q = self.current
        entry = {"trial": self.trial, "reference": ref, "quant_db": q, "similarity": rating}
        self.ratings.append(entry)
        return entry
