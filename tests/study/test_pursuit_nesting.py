"""The pursuit vector's step keeps the remaining square nested (seed 000,
"Guided exploration test": the scaling "ensured that the remaining parameter
space is always a subset of the space in the trial before it"), proved by
enumerating every trial's answers (host/texelpad/study/pursuit.py).

Why it holds: the four directions N, NE, E, SE are unit vectors 45 degrees
apart, so the largest component of p = sum r_k d_k along EACH axis is
1 + 2/sqrt 2 = 1 + sqrt 2 (e.g. v: N + NE - SE), which is what the lab's code
divides by (guided_exploration_test_app, NU-Haptics-Lab/SinglePitchTexel:
pursuitMax = 1 + 2/sqrt(2); center += pursuit*(shrinkAmount/2)/pursuitMax).
The centre then moves at most 0.1 along each axis per trial - half the 0.2 by
which the edge shrinks - so the next square lies inside the last one. The
norm |p| can reach 2.61 (a diagonal step of 0.108), which nesting does not
care about. Pure arithmetic: nothing here depends on the machine's speed."""
from __future__ import annotations

import itertools
import math
import random

import pytest

from texelpad.study.pursuit import DIRECTIONS, STEP, Config, Pursuit

ANSWER_VALUES = (1, -1, 0)        # r_k: the +d_k point, its opposite, unsure
COMBOS = list(itertools.product(ANSWER_VALUES, repeat=len(DIRECTIONS)))   # 3^4 = 81
TOL = 1e-12                       # float rounding of STEP * (1 + sqrt 2) against 0.1


def _pursuit(r: tuple[int, ...]) -> tuple[float, float]:
    return (sum(rk * d[0] for rk, (_, d) in zip(r, DIRECTIONS)),
            sum(rk * d[1] for rk, (_, d) in zip(r, DIRECTIONS)))


def _square(cu: float, cv: float, edge: float) -> tuple[float, float, float, float]:
    h = edge / 2.0
    return cu - h, cu + h, cv - h, cv + h


def _inside(inner, outer) -> bool:
    return (inner[0] >= outer[0] - TOL and inner[1] <= outer[1] + TOL
            and inner[2] >= outer[2] - TOL and inner[3] <= outer[3] + TOL)


def test_the_enumeration_is_complete():
    assert len(COMBOS) == 81 and len(set(COMBOS)) == 81
    names = [n for n, _ in DIRECTIONS]
    assert names == ["N", "NE", "E", "SE"]
    for _, (du, dv) in DIRECTIONS:
        assert math.hypot(du, dv) == pytest.approx(1.0, abs=1e-15)


def test_each_axis_shifts_at_most_half_the_shrink():
    half = Config().edge_step / 2.0                     # 0.1 of the unit square
    shifts = [tuple(abs(c) * STEP for c in _pursuit(r)) for r in COMBOS]
    for r, (su, sv) in zip(COMBOS, shifts):
        assert su <= half + TOL and sv <= half + TOL, r
    # the bound is tight on both axes: 1 + sqrt 2 is the largest component
    assert max(s[0] for s in shifts) == pytest.approx(half, abs=TOL)
    assert max(s[1] for s in shifts) == pytest.approx(half, abs=TOL)
    assert max(abs(_pursuit(r)[1]) for r in COMBOS) == pytest.approx(1 + 2 / math.sqrt(2))
    # ... while the norm goes beyond it: 2.61 (a step of 0.108), e.g. N + NE + E - SE
    norms = [math.hypot(*_pursuit(r)) for r in COMBOS]
    assert max(norms) == pytest.approx(math.sqrt(1 + (1 + math.sqrt(2)) ** 2))
    assert max(norms) > 1 + math.sqrt(2) and max(norms) * STEP == pytest.approx(0.108, abs=5e-4)


def test_the_next_square_lies_inside_the_last_for_any_centre_and_edge():
    cfg = Config()
    rng = random.Random(20)
    centres = [(0.5, 0.5), (0.0, 0.0), (1.0, 1.0), (0.0, 1.0), (-3.0, 7.5)] + \
        [(rng.uniform(-2, 3), rng.uniform(-2, 3)) for _ in range(20)]
    edges = [1.0, 0.8, 0.6, 0.4, cfg.edge_step] + [rng.uniform(cfg.edge_step, 5.0)
                                                   for _ in range(10)]
    for (cu, cv), edge in itertools.product(centres, edges):
        old = _square(cu, cv, edge)
        for r in COMBOS:
            pu, pv = _pursuit(r)
            new = _square(cu + pu * STEP, cv + pv * STEP, edge - cfg.edge_step)
            assert _inside(new, old), (cu, cv, edge, r)


def _answer(q, r: int) -> str:
    """The pick that makes r_k = r for this question (pursuit.Comparison.r)."""
    if r == 0:
        return "unsure"
    return "A" if (r == 1) == q.a_is_plus else "B"


def _walk(answers: list[tuple[int, ...]], clamp: bool, seed: int = 3) -> list[tuple]:
    """The squares (u0, u1, v0, v1) of a whole exploration answered trial by trial."""
    pv = Pursuit(seed=seed, config=Config(clamp_centre=clamp))
    names = [n for n, _ in DIRECTIONS]
    squares = [_square(pv.centre.u, pv.centre.v, pv.edge)]
    for r in answers:
        for _ in DIRECTIONS:
            q = pv.next_comparison()
            pv.answer(_answer(q, r[names.index(q.direction)]))
        squares.append(_square(pv.centre.u, pv.centre.v, pv.edge))
    assert pv.done
    return squares


def test_the_state_machine_nests_every_trial_unclamped():
    """pursuit.py itself, its clamp off: for every answer combination held over
    the five trials, and random walks, each square lies inside the one before."""
    rng = random.Random(5)
    walks = [[r] * 5 for r in COMBOS] + [[rng.choice(COMBOS) for _ in range(5)]
                                          for _ in range(200)]
    for answers in walks:
        squares = _walk(answers, clamp=False)
        assert len(squares) == 6
        for old, new in zip(squares, squares[1:]):
            assert _inside(new, old), answers
        # nested from the unit square: the centre never leaves it ...
        assert _inside(squares[-1], (0.0, 1.0, 0.0, 1.0)), answers
        # ... so from the default start the clamp never acts
        assert _walk(answers, clamp=True) == squares, answers
