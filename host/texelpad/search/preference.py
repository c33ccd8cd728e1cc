"""Preference-driven texture search (seed 003; ../shared/SPEC.md §7): CMA-ES
driven by choices, over the texel parameter space of this display.

Each iteration asks for lambda = 3 candidates with mirrored sampling (two of
them mirror each other about the mean: `cma`'s CMA_mirrors = 1, unconditional),
sigma0 = 0.15 in a space normalised to [0, 1] per dimension (the `cma`
library's BoundTransform keeps candidates inside). The participant picks the
candidate closest to the target; the pick becomes a ranking - chosen first,
the other two in random order (from the search's own seeded generator) - and
the ranking is CMA-ES's fitness (0, 1, 2). "save" keeps a candidate; the
search stops when the participant says so (stop()).

Dimensions: "pitch" and "irregularity" always (texelpad.space's u, v),
optionally "texel_length" (0..1 -> 0.05 .. 2 mm, log scale) and "level" (the
map's gain 0.2 .. 1). Candidates become format-2 texel parameter sets (the
same texture on every board). The library is `cma` (N. Hansen); nothing of
CMA-ES is written here. Pure logic: no link, no web framework.
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from typing import Any

import cma
import numpy as np

from texel.gen.params import DX_MM, FORMAT_NEW

from ..space import Point, texel_params

DIMENSIONS = ("pitch", "irregularity", "texel_length", "level")
SIGMA0 = 0.15
POPSIZE = 3
TEXEL_MM = (0.05, 2.0)          # texel_length 0..1, log scale
LEVEL = (0.2, 1.0)              # gain


def candidate_params(x: list[float], dims: tuple[str, ...], seed: int = 0,
                     v: int = FORMAT_NEW) -> dict[str, Any]:
    """The texel parameter set of a point of the search space, in format v
    (2 unless the study config's texture_format says 1)."""
    d = dict(zip(dims, x))
    extra: dict[str, Any] = {"seed": seed, "v": v}
    if "texel_length" in d:
        lo, hi = TEXEL_MM
        mm = lo * (hi / lo) ** min(1.0, max(0.0, d["texel_length"]))
        extra["texel_samples"] = max(1, int(round(mm / DX_MM)))
    if "level" in d:
        lo, hi = LEVEL
        extra["gain"] = round(lo + (hi - lo) * min(1.0, max(0.0, d["level"])), 4)
    return texel_params(Point(d["pitch"], d["irregularity"]), **extra)


@dataclass
class PreferenceSearch:
    """ask() -> the iteration's 3 candidates (points in [0, 1]^d); choose(k)
    -> the update. Deterministic for a seed: a session replays exactly."""
    seed: int
    dims: tuple[str, ...] = ("pitch", "irregularity")
    x0: tuple[float, ...] | None = None
    sigma0: float = SIGMA0
    texture_seed: int = 7           # the texel generator's seed of every candidate
    texture_format: int = FORMAT_NEW    # and their format (the config's texture_format)
    saved: list[dict] = field(default_factory=list)
    history: list[dict] = field(default_factory=list)
    stopped: bool = False           # the participant was satisfied

    def __post_init__(self) -> None:
        dims = tuple(self.dims)
        if dims[:2] != ("pitch", "irregularity") or any(d not in DIMENSIONS for d in dims) \
                or len(set(dims)) != len(dims):
            raise ValueError("dims: pitch and irregularity first, then any of texel_length, "
                             "level; got %r" % (dims,))
        self.dims = dims
        x0 = list(self.x0) if self.x0 is not None else [0.5] * len(dims)
        if len(x0) != len(dims) or not all(0.0 <= v <= 1.0 for v in x0):
            raise ValueError("x0: %d numbers in [0, 1], got %r" % (len(dims), self.x0))
        if not 0.0 < self.sigma0 <= 0.5:
            raise ValueError("sigma0: expected (0, 0.5], got %r" % (self.sigma0,))
        self._es = cma.CMAEvolutionStrategy(
            x0, self.sigma0,
            {"popsize": POPSIZE, "seed": self.seed + 1,        # cma: seed 0 means "random"
             "bounds": [0.0, 1.0], "CMA_mirrors": 1, "CMA_mirrormethod": 0,
             "verbose": -9, "tolx": 1e-12, "tolfun": 0.0, "tolflatfitness": 10 ** 9})
        self._rng = random.Random(self.seed)
        self._asked: list[np.ndarray] | None = None
        self._x0 = [float(v) for v in x0]

    @property
    def iteration(self) -> int:
        return len(self.history)

    @property
    def mean(self) -> list[float]:
        """The distribution's mean in the search space ([0, 1]^d: `cma`'s
        mean mapped through its boundary transform, result.xfavorite)."""
        return [float(v) for v in self._es.result.xfavorite]

    @property
    def sigma(self) -> float:
        return float(self._es.sigma)

    def ask(self) -> list[list[float]]:
        """This iteration's candidates (the same list until choose())."""
        if self._asked is None:
            self._asked = [np.asarray(x, dtype=float) for x in self._es.ask()]
        return [[float(v) for v in x] for x in self._asked]

    def candidates(self) -> list[dict[str, Any]]:
        """ask() as texel parameter sets."""
        return [candidate_params(x, self.dims, self.texture_seed, self.texture_format)
                for x in self.ask()]

    @property
    def done(self) -> bool:
        return self.stopped

    def stop(self) -> dict:
        """The participant is satisfied: the search ends (its mean and the
        saved candidates are the result)."""
        self._not_done()
        self.stopped = True
        return {"iteration": self.iteration, "mean": self.mean, "saved": len(self.saved)}

    def _not_done(self) -> None:
        if self.stopped:
            raise ValueError("the search is finished: nothing to answer")

    def choose(self, k: int) -> dict:
        """The participant picked candidate k (0..2): ranking chosen-first, the
        others in random order; CMA-ES's update. Returns the iteration's record."""
        self._not_done()
        xs = self.ask()
        if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k < len(xs):
            raise ValueError("choice: expected 0 .. %d, got %r" % (len(xs) - 1, k))
        others = [i for i in range(len(xs)) if i != k]
        self._rng.shuffle(others)
        ranking = [k] + others
        fitness = [0.0] * len(xs)
        for rank, i in enumerate(ranking):
            fitness[i] = float(rank)
        self._es.tell(self._asked, fitness)
        self._asked = None
        rec = {"iteration": self.iteration, "candidates": xs, "chosen": k, "ranking": ranking,
               "mean_after": self.mean, "sigma_after": self.sigma}
        self.history.append(rec)
        return rec

    def save(self, k: int) -> dict:
        """Keep candidate k of the current iteration."""
        self._not_done()
        xs = self.ask()
        if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k < len(xs):
            raise ValueError("save: expected 0 .. %d, got %r" % (len(xs) - 1, k))
        entry = {"iteration": self.iteration, "x": xs[k],
                 "params": candidate_params(xs[k], self.dims, self.texture_seed,
                                            self.texture_format)}
        self.saved.append(entry)
        return entry

    def step_size(self) -> float:
        """How far the mean moved in the last iteration (0 before any)."""
        if not self.history:
            return 0.0
        before = self.history[-2]["mean_after"] if len(self.history) > 1 else self._x0
        return math.dist(self.history[-1]["mean_after"], before)
