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

The same protocol rates seed 000's similarity matrix (after the guided
exploration: "Then rate 3x3 similarity", SPEC §5; seed 000 Fig. 14c):
design "matrix" pairs every reference with every reference's match (3 x 3
trials at q = levels_db[0], normally 0), so a rendering is rated against the
texture it was tuned to and against the others.

Answers: the similarity rating, an int 1..5. Pure logic.
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from typing import Any

from .free import check_references
from texel.gen.params import FORMAT_NEW, IRREG_DB_MAX, IRREG_DB_MIN, PITCH_DB_MAX, PITCH_DB_MIN, \
    QUANT_DB_MAX

EXEMPLARS = ("4sin", "pink", "sawtooth")


@dataclass(frozen=True)
class Config:
    matches: dict[str, dict[str, float]]
    references: tuple[str, ...] = EXEMPLARS
    levels_db: tuple[float, ...] = (0.0, 1.0, 3.0, 5.0)
    repeats: int = 1
    texel_samples: int = 47
    scale: tuple[int, int] = (1, 5)
    match_source: str = "given"         # "given" or the session id the matches came from
    design: str = "levels"              # "levels": q per reference; "matrix": 3 x 3 pairs

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
        if self.design not in ("levels", "matrix"):
            raise ValueError("design: expected 'levels' or 'matrix', got %r" % (self.design,))
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
        if c.design == "levels":        # (reference, the match of, q)
            trials = [(r, r, float(q)) for r in c.references for q in c.levels_db]
        else:
            trials = [(r, m, float(c.levels_db[0])) for r in c.references for m in c.references]
        trials = trials * c.repeats
        rng.shuffle(trials)
        self._trials = trials

    @property
    def trials(self) -> list[tuple[str, float]]:
        """(reference, q) per trial, in order."""
        return [(r, q) for r, _, q in self._trials]

    @property
    def trial(self) -> int:
        return len(self.ratings)

    @property
    def done(self) -> bool:
        return self.trial >= len(self.trials)

    @property
    def current(self) -> tuple[str, float]:
        """(the reference, q) of the current trial."""
        return self.trials[self.trial]

    @property
    def current_match(self) -> str:
        """Whose match the current rendering is (the reference's own, or in
        the matrix design another's)."""
        return self._trials[self.trial][1]

    def texture(self, v: int = FORMAT_NEW) -> dict[str, Any]:
        """The current trial's rendering: the match, quantized, in format v
        (the config's texture_format: 2 unless it says 1)."""
        ref, match, q = self._trials[self.trial]
        m = self.config.matches[match]
        return {"pitch_db": round(float(m["pitch_db"]), 3),
                "irregularity_db": round(float(m["irregularity_db"]), 3),
                "quant_db": q, "texel_samples": self.config.texel_samples,
                "seed": self.texture_seeds[match], "v": v}

    def answer(self, rating: Any) -> dict[str, Any]:
        if self.done:
            raise ValueError("the quantization test is finished: nothing to answer")
        lo, hi = self.config.scale
        if isinstance(rating, bool) or not isinstance(rating, int) or not lo <= rating <= hi:
            raise ValueError("similarity: expected %d .. %d, got %r" % (lo, hi, rating))
        ref, match, q = self._trials[self.trial]
        entry = {"trial": self.trial, "reference": ref, "match_of": match, "quant_db": q,
                 "similarity": rating}
        self.ratings.append(entry)
        return entry
