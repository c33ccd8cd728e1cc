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
map's gain 0.2 .. 1; texelpad's own: seed 003 searches a GAN's latent space,
docs/lab.md).

Seed 003's choices, and where texelpad differs (recorded fields):
- `cma_update`: seed 003's Algorithm 1 (line 8) adapts C and sigma "by
  rank-one update" - "rank_one" (the default): `cma` with CMA_active off and
  no rank-mu term (CMA_rankmu 0), the evolution path's rank-one update alone;
  "positive": CMA_active off, `cma`'s rank-mu term kept (weights [1, 0, 0]);
  "active": `cma`'s default active update (weights [1, 0, -1.67]: the
  candidate ranked last pushes C away), what texelpad ran before (sessions
  of format /3 and older: study/legacy.py).
- `level_slider`: seed 003's participants "used a slider to freely adjust
  the friction of the virtual textures" - of all three at once - while
  comparing. On this display the friction level is the map's gain: true
  (the default) shows a slider from LEVEL[0] to LEVEL[1] that starts at
  `level_start` and keeps its setting across iterations; every choose or
  save answer carries the level that played ({"choose": k, "level": g}), so
  the state - and Table I's count of tunings - replays from the answers.
  Not with "level" among the CMA dimensions (one or the other). Candidates become format-2 texel parameter sets (the
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
UPDATES = ("rank_one", "positive", "active")    # cma_update (docstring)
# the `cma` options of each update
_UPDATE_OPTIONS: dict[str, dict[str, Any]] = {"rank_one": {"CMA_active": False, "CMA_rankmu": 0.0},
                   "positive": {"CMA_active": False},
                   "active": {"CMA_active": True}}
SIGMA0 = 0.15
POPSIZE = 3
TEXEL_MM = (0.05, 2.0)          # texel_length 0..1, log scale
LEVEL = (0.2, 1.0)              # gain


def check_level(g: Any) -> float:
    """A friction level (the map's gain) of the slider, or ValueError."""
    lo, hi = LEVEL
    if isinstance(g, bool) or not isinstance(g, (int, float)) or not math.isfinite(g) \
            or not lo <= g <= hi:
        raise ValueError("level: expected the friction slider's %g .. %g, got %r" % (lo, hi, g))
    return round(float(g), 4)


def candidate_params(x: list[float], dims: tuple[str, ...], seed: int = 0,
                     v: int = FORMAT_NEW, level: float | None = None) -> dict[str, Any]:
    """The texel parameter set of a point of the search space, in format v
    (2 unless the study config's texture_format says 1); level: the friction
    slider's gain (the slider's, not a dimension)."""
    d = dict(zip(dims, x))
    extra: dict[str, Any] = {"seed": seed, "v": v}
    if level is not None:
        extra["gain"] = check_level(level)
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
    cma_update: str = "rank_one"    # seed 003's (docstring); "positive", "active"
    level_slider: bool = True       # seed 003's friction slider (docstring)
    level_start: float = 1.0        # where the slider starts (the map's full gain)
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
        if self.cma_update not in UPDATES:
            raise ValueError("cma_update: expected 'rank_one' (seed 003's), 'positive' or "
                             "'active' (cma's default), got %r" % (self.cma_update,))
        if not isinstance(self.level_slider, bool):
            raise ValueError("level_slider: expected true or false, got %r"
                             % (self.level_slider,))
        if self.level_slider and "level" in dims:
            raise ValueError("level_slider: the friction level is either the participant's "
                             "slider or a CMA dimension ('level' in dims), not both")
        self.level_start = check_level(self.level_start)
        self.level = self.level_start if self.level_slider else None
        self.tunings = 0                # iterations whose answer moved the slider (Table I)
        self._tuned = -1                # the last iteration counted
        opts: dict[str, Any] = {"popsize": POPSIZE, "seed": self.seed + 1,  # cma: 0 = random
                                "bounds": [0.0, 1.0], "CMA_mirrors": 1, "CMA_mirrormethod": 0,
                                "verbose": -9, "tolx": 1e-12, "tolfun": 0.0,
                                "tolflatfitness": 10 ** 9}
        opts.update(_UPDATE_OPTIONS[self.cma_update])
        self._es = cma.CMAEvolutionStrategy(x0, self.sigma0, opts)
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
        """ask() as texel parameter sets (at the slider's level)."""
        return [candidate_params(x, self.dims, self.texture_seed, self.texture_format,
                                 self.level)
                for x in self.ask()]

    def _tune(self, level: Any) -> None:
        """The slider's level an answer carries; an iteration that moved it
        counts once (a save, then a choose, at two levels: one tuning)."""
        if self.set_level(level) and self._tuned != self.iteration:
            self.tunings += 1
            self._tuned = self.iteration

    def set_level(self, level: Any) -> bool:
        """The slider's level an answer carries (None: unchanged): whether it
        moved. ValueError for a level without a slider or out of range."""
        if level is None:
            return False
        if not self.level_slider:
            raise ValueError("level: this search has no friction slider (level_slider false)")
        g = check_level(level)
        moved = g != self.level
        self.level = g
        return moved

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

    def choose(self, k: int, level: Any = None) -> dict:
        """The participant picked candidate k (0..2), at the slider's level:
        ranking chosen-first, the others in random order; CMA-ES's update.
        Returns the iteration's record."""
        self._not_done()
        xs = self.ask()
        if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k < len(xs):
            raise ValueError("choice: expected 0 .. %d, got %r" % (len(xs) - 1, k))
        if level is not None:
            check_level(level)
        self._tune(level)
        others = [i for i in range(len(xs)) if i != k]
        self._rng.shuffle(others)
        ranking = [k] + others
        fitness = [0.0] * len(xs)
        for rank, i in enumerate(ranking):
            fitness[i] = float(rank)
        self._es.tell(self._asked, fitness)
        self._asked = None
        rec = {"iteration": self.iteration, "candidates": xs, "chosen": k, "ranking": ranking,
               "mean_after": self.mean, "sigma_after": self.sigma, "level": self.level}
        self.history.append(rec)
        return rec

    def save(self, k: int, level: Any = None) -> dict:
        """Keep candidate k of the current iteration (at the slider's level)."""
        self._not_done()
        xs = self.ask()
        if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k < len(xs):
            raise ValueError("save: expected 0 .. %d, got %r" % (len(xs) - 1, k))
        if level is not None:
            check_level(level)
        self._tune(level)
        entry = {"iteration": self.iteration, "x": xs[k],
                 "params": candidate_params(xs[k], self.dims, self.texture_seed,
                                            self.texture_format, self.level)}
        self.saved.append(entry)
        return entry

    def step_size(self) -> float:
        """How far the mean moved in the last iteration (0 before any)."""
        if not self.history:
            return 0.0
        before = self.history[-2]["mean_after"] if len(self.history) > 1 else self._x0
        return math.dist(self.history[-1]["mean_after"], before)
