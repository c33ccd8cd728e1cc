"""A simulated participant for the protocols' tests and benchmarks: it
answers from a distance between textures plus noise.

The model (documented so a figure made with it can be read): a texture is a
point of texelpad.study.space's unit square (u: pitch, v: irregularity; a
search candidate's further dimensions are ignored). The participant holds a
target point; the perceived distance of a texture is its Euclidean distance
to the target plus Gaussian noise of SD `noise` (normalised units: 0.025 is
1 dB of pitch). Comparisons pick the smaller perceived distance, or "unsure"
when the two differ by less than `unsure_below`. The oddity task is a
psychometric function of texel length: P(correct) = 1/3 + 2/3 / (1 +
exp(-(length - threshold) / slope)) - chance (1/3) far below the threshold,
certain far above. In the free exploration it sets the sliders on its target
(plus the noise) with confidence 4; in the quantization test (and the
similarity matrix) it rates similarity 5 - d/4 - q/2, d the distance in dB
between the reference's spectral position (texelpad.study.references) and
the match rendered, q the quantization in dB, plus noise of SD noise*40,
rounded to 1..5 - a model for driving the protocols, not a finding.
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

from .space import Point


@dataclass
class SimulatedParticipant:
    target: Point
    noise: float = 0.0
    unsure_below: float = 0.0
    seed: int = 0
    threshold_mm: float = 6.0
    slope_mm: float = 1.0
    _rng: random.Random = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._rng = random.Random(self.seed)

    def perceived(self, p: Point) -> float:
        d = p.distance(self.target)
        return d + (self._rng.gauss(0.0, self.noise) if self.noise else 0.0)

    def compare(self, a: Point, b: Point) -> str:
        """'A', 'B' or 'unsure': which of the two is closer to the target."""
        da, db = self.perceived(a), self.perceived(b)
        if abs(da - db) < self.unsure_below:
            return "unsure"
        return "A" if da < db else "B"

    def pick(self, candidates: list[list[float]]) -> int:
        """The index of the candidate closest to the target (first two dims)."""
        ds = [self.perceived(Point(x[0], x[1])) for x in candidates]
        return min(range(len(ds)), key=ds.__getitem__)

    def odd_one_out(self, length_mm: float) -> bool:
        """Whether the odd texture is found at this texel length."""
        z = (length_mm - self.threshold_mm) / self.slope_mm
        p = 1.0 / 3.0 + (2.0 / 3.0) / (1.0 + math.exp(-max(-60.0, min(60.0, z))))
        return self._rng.random() < p

    def answer(self, protocol: str, state) -> object:
        """The answer to the protocol state's current question, as
        texelpad.study.protocols.apply takes it."""
        if protocol == "pursuit":
            q = state.next_comparison()
            return self.compare(q.a, q.b)
        if protocol == "staircase":
            return self.odd_one_out(state.length_mm)
        if protocol == "search":
            return {"choose": self.pick(state.ask())}
        if protocol == "free":
            from .space import irregularity_db, pitch_db
            c = state.config
            n = (lambda: self._rng.gauss(0.0, self.noise)) if self.noise else (lambda: 0.0)
            p = min(c.pitch_db[1], max(c.pitch_db[0], pitch_db(self.target.u + n())))
            s = min(c.irregularity_db[1], max(c.irregularity_db[0],
                                               irregularity_db(self.target.v + n())))
            return {"pitch_db": round(p, 3), "irregularity_db": round(s, 3), "confidence": 4}
        if protocol == "quant":
            from .references import position
            ref, q = state.current
            m = state.config.matches[state.current_match]
            p, s = position(ref)
            d = math.hypot(m["pitch_db"] - p, m["irregularity_db"] - s)
            r = 5.0 - d / 4.0 - q / 2.0 + (self._rng.gauss(0.0, self.noise * 40)
                                           if self.noise else 0.0)
            return int(min(5, max(1, round(r))))
        raise ValueError("protocol: unknown %r" % (protocol,))
