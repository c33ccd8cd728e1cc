"""Guided exploration by the pursuit vector (seed 000; ../shared/SPEC.md §5),
as a state machine the lab's server (or a simulated participant) drives.

Space: texelpad.study.space (u, v) in [0, 1]^2; start at the centre
(0.5, 0.5) with edge 1. A trial shows 8 points at radius edge/4 from the
centre in the directions N, NE, E, SE and their opposites and asks 4 pairwise
comparisons - direction d_k against -d_k - in random order with a random A/B
side. An answer is which of the two is closer to the reference: r_k = +1 for
the point in direction d_k, -1 for its opposite, 0 for "unsure". Then

    p       = sum_k r_k d_k          (the pursuit vector)
    centre += p * 0.1 / (1 + sqrt 2)
    edge   -= 0.2

and the exploration stops when edge < 0.15: 5 trials, 20 comparisons.

What plays (seed 000: the subject "is able to freely select the current
reference texture and two comparison textures using buttons on the GUI,
causing the TPaD to present the selected texture"; the lab's
guided_exploration_test_app renders A and B afresh for every comparison, each
on the whole display): `presentation` "whole" (the default) plays the
reference, A or B, one at a time on the whole display; "split" plays the
reference on the left half and A or B on the right (the design before the
app was read). `fresh` (default true): each comparison draws new texture
seeds for A and B from the session's seed (feeling A again within a
comparison replays the same rendering, as the app's); false keeps one seed.

Choices the paper leaves open, recorded in every state (Config): the
diagonals are unit vectors (1/sqrt 2, 1/sqrt 2); the centre stays in the unit
square (clamped after each step); the order and the A/B sides come from the
session's seeded random generator, so a session replays exactly; a
reference's row (9,600 samples) on the whole display continues mirrored
(texel.gen.reference), where the app played the row twice.

Points above the display's Nyquist pitch (19.747 dB, u > 0.8687; reachable:
the app's pitch axis runs to 10^2.5 c/mm, 25 dB): `above_nyquist` "alias"
(the default: the app's buildFine5 renders any pitch, and its samples alias)
plays such a point as display samples rendered on the host with the texel
generator's own plan at the point's pitch (texelpad.space.aliased_samples);
"clamp" plays the texel texture at Nyquist (what texelpad did before, and
what sessions of format /3 and older played: study/legacy.py). The end point
a finished exploration gives as a match is the texel texture it plays when
clamped (a match is a texel texture: study/question.py played_db).
"""
from __future__ import annotations

import math
import random
from dataclasses import asdict, dataclass, field

from .space import Point, check_above_nyquist

_R2 = 1.0 / math.sqrt(2.0)
# N, NE, E, SE as unit vectors in (u, v): u = pitch (east), v = irregularity (north)
DIRECTIONS = (("N", (0.0, 1.0)), ("NE", (_R2, _R2)), ("E", (1.0, 0.0)), ("SE", (_R2, -_R2)))
STEP = 0.1 / (1.0 + math.sqrt(2.0))
ANSWERS = (1, -1, 0)       # +1: the point in direction d_k; -1: its opposite; 0: unsure


@dataclass(frozen=True)
class Config:
    start: tuple[float, float] = (0.5, 0.5)
    edge: float = 1.0
    edge_step: float = 0.2
    stop_below: float = 0.15
    radius_per_edge: float = 0.25
    step: float = STEP
    clamp_centre: bool = True
    presentation: str = "whole"     # "whole": one texture at a time; "split": reference | option
    fresh: bool = True              # new texture seeds for every comparison
    above_nyquist: str = "alias"    # "alias": the app's (docstring); "clamp": at Nyquist

    def __post_init__(self) -> None:
        if self.presentation not in ("whole", "split"):
            raise ValueError("presentation: expected 'whole' (one texture at a time on the "
                             "whole display, the lab's) or 'split', got %r" % (self.presentation,))
        if not isinstance(self.fresh, bool):
            raise ValueError("fresh: expected true or false, got %r" % (self.fresh,))
        check_above_nyquist(self.above_nyquist)

    def seeds(self, session_seed: int, trial: int, index: int) -> tuple[int, int]:
        """The texture seeds of A and B in comparison (trial, index)."""
        if not self.fresh:
            return 7, 7
        rng = random.Random((session_seed * 1000003 + trial) * 1000003 + index)
        return rng.randrange(1 << 32), rng.randrange(1 << 32)


@dataclass(frozen=True)
class Comparison:
    """One question: A and B are the two points of direction `direction`;
    `a_is_plus` says whether A is the +d_k point (the side was drawn)."""
    trial: int
    index: int                  # 0..3 within the trial
    direction: str
    a: Point
    b: Point
    a_is_plus: bool

    def r(self, picked: str) -> int:
        """The answer as r_k: picked "A", "B" or "unsure"."""
        if picked == "unsure":
            return 0
        if picked not in ("A", "B"):
            raise ValueError("answer: expected 'A', 'B' or 'unsure', got %r" % (picked,))
        return 1 if (picked == "A") == self.a_is_plus else -1


@dataclass
class Pursuit:
    """The exploration's state. next_comparison() -> the question to ask (or
    None when done); answer(picked) records it and, after the trial's fourth,
    moves the centre."""
    seed: int
    config: Config = field(default_factory=Config)
    centre: Point = None        # type: ignore[assignment]
    edge: float = 0.0
    trial: int = 0
    answers: list[int] = field(default_factory=list)   # r_k of the current trial, by direction
    history: list[dict] = field(default_factory=list)  # one entry per finished trial
    _order: list[tuple[int, bool]] = field(default_factory=list)

    def __post_init__(self) -> None:
        if self.centre is None:
            self.centre = Point(*self.config.start)
        if not self.edge:
            self.edge = self.config.edge
        self._rng = random.Random(self.seed)
        self._new_trial()

    # --- the protocol -----------------------------------------------------------------
    @property
    def done(self) -> bool:
        return self.edge < self.config.stop_below - 1e-12

    def points(self) -> list[tuple[str, Point, Point]]:
        """(direction, +d point, -d point) of the current trial."""
        r = self.edge * self.config.radius_per_edge
        c = self.centre
        return [(name, Point(c.u + r * du, c.v + r * dv), Point(c.u - r * du, c.v - r * dv))
                for name, (du, dv) in DIRECTIONS]

    def next_comparison(self) -> Comparison | None:
        if self.done:
            return None
        k, a_is_plus = self._order[len(self._asked())]
        name, plus, minus = self.points()[k]
        a, b = (plus, minus) if a_is_plus else (minus, plus)
        return Comparison(self.trial, len(self._asked()), name, a, b, a_is_plus)

    def answer(self, picked: str) -> dict:
        """Record the answer to next_comparison(); returns the trial's summary
        when this answer finished a trial, else {}."""
        q = self.next_comparison()
        if q is None:
            raise ValueError("the exploration is finished: nothing to answer")
        k = self._order[q.index][0]
        self.answers[k] = q.r(picked)
        self._answered.append(k)
        if len(self._answered) < len(DIRECTIONS):
            return {}
        return self._finish_trial()

    # --- internals --------------------------------------------------------------------
    def _asked(self) -> list[int]:
        return self._answered

    def _new_trial(self) -> None:
        ks = list(range(len(DIRECTIONS)))
        self._rng.shuffle(ks)
        self._order = [(k, self._rng.random() < 0.5) for k in ks]
        self.answers = [0] * len(DIRECTIONS)
        self._answered: list[int] = []

    def pursuit_vector(self) -> tuple[float, float]:
        pu = sum(r * d[0] for r, (_, d) in zip(self.answers, DIRECTIONS))
        pv = sum(r * d[1] for r, (_, d) in zip(self.answers, DIRECTIONS))
        return pu, pv

    def _finish_trial(self) -> dict:
        pu, pv = self.pursuit_vector()
        before = self.centre
        c = Point(before.u + pu * self.config.step, before.v + pv * self.config.step)
        if self.config.clamp_centre:
            c = c.clamped()
        entry = {"trial": self.trial, "centre_before": asdict(before), "edge": self.edge,
                 "r": dict(zip((n for n, _ in DIRECTIONS), self.answers)),
                 "pursuit": [pu, pv], "centre_after": asdict(c)}
        self.history.append(entry)
        self.centre = c
        self.edge = round(self.edge - self.config.edge_step, 12)
        self.trial += 1
        if not self.done:
            self._new_trial()
        return entry
