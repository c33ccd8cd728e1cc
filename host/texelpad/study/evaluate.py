"""Seed 003's Phase 2, "Texture Evaluation": other participants rate the
textures the preference-driven search made (../shared/seeds/003_*.txt,
"Phase 2"), as a state machine the lab's server drives.

What the paper ran: a second group felt the 25 preference-driven textures
(VTp, the final saved texture of each Phase 1 participant and real texture),
the 5 real textures (RT) and 5 data-driven ones (VTd), (a) "all 35 texture
samples in random order" rating roughness (smooth - rough), hardness (soft -
hard) and slipperiness (not slippery - slippery), and (b) "pairs of a real
texture and a corresponding virtual texture (either VTd or VTp_i) in random
order", rating their similarity "completely different" - "completely the
same"; "we randomize the order of the adjective ratings and similarity
comparison steps".

On a friction display (texelpad's choices, recorded in Config and so in
every session header):
- the real texture is the reference texture the search ran on, played on
  the display (the paper's lay beside the device); VTp the texel texture a
  stopped search saved last (study/matches.py from_saved); VTd, the
  data-driven model, is the reference's spectral position as a texel
  texture (study/references.py target_point: `data_driven` true), texelpad's
  stand-in for a model fitted to recordings;
- every texture plays alone on the whole display; in a similarity trial the
  real one and the virtual one are two options felt one at a time;
- each adjective of a texture is its own question, the three in a row (the
  paper's form had them side by side); the scale is not given in the paper:
  `scale` (default 1 .. 5) with the lab's continuous slider (`rating`);
- `steps`: "seeded" (the paper's: which step comes first drawn from the
  session's seed), "adjectives_first" or "similarity_first".
Pure logic.
"""
from __future__ import annotations

import random
from dataclasses import dataclass, field
from typing import Any

from texel.gen.params import FORMAT_NEW

from .free import check_references, rating_of

ADJECTIVES = {"roughness": ("smooth", "rough"), "hardness": ("soft", "hard"),
              "slipperiness": ("not slippery", "slippery")}
STEPS = ("seeded", "adjectives_first", "similarity_first")
SOURCES = ("real", "data", "preference")        # RT, VTd, VTp
TEXTURES_MAX = 100


def _check_texture(k: int, t: Any) -> None:
    keys = {"name", "reference", "texture"}
    if not isinstance(t, dict) or set(t) != keys or not isinstance(t["name"], str) \
            or not t["name"] or not isinstance(t["texture"], dict):
        raise ValueError("textures[%d]: expected {name, reference, texture} (a saved search's "
                         "texture: start the session with matches_from), got %r" % (k, t))
    check_references((t["reference"],))
    import texel
    try:
        texel.validate(dict(t["texture"], v=t["texture"].get("v", FORMAT_NEW)))
    except ValueError as e:
        raise ValueError("textures[%d].texture: %s" % (k, e)) from None


@dataclass(frozen=True)
class Config:
    # the preference-driven textures to evaluate (VTp): None until matches_from fills them
    textures: tuple[dict[str, Any], ...] | None = None
    data_driven: bool = True            # a VTd per reference (docstring)
    adjectives: tuple[str, ...] = tuple(ADJECTIVES)
    steps: str = "seeded"
    scale: tuple[int, int] = (1, 5)
    rating: str = "slider"
    texel_samples: int = 50             # of the VTd textures
    match_source: str = "given"         # the search sessions the textures came from

    def __post_init__(self) -> None:
        if self.textures is not None:
            if not isinstance(self.textures, (list, tuple)) or \
                    not 1 <= len(self.textures) <= TEXTURES_MAX:
                raise ValueError("textures: expected 1 .. %d saved textures, got %r"
                                 % (TEXTURES_MAX, self.textures))
            for k, t in enumerate(self.textures):
                _check_texture(k, t)
            names = [t["name"] for t in self.textures]
            if len(set(names)) != len(names):
                raise ValueError("textures: names must differ, got %r" % (names,))
            object.__setattr__(self, "textures", tuple(self.textures))
        bad = [a for a in self.adjectives if a not in ADJECTIVES]
        if not self.adjectives or bad or len(set(self.adjectives)) != len(self.adjectives):
            raise ValueError("adjectives: expected some of %s, got %r"
                             % (", ".join(ADJECTIVES), self.adjectives))
        if self.steps not in STEPS:
            raise ValueError("steps: expected one of %s, got %r" % (", ".join(STEPS), self.steps))
        if not isinstance(self.data_driven, bool):
            raise ValueError("data_driven: expected true or false, got %r" % (self.data_driven,))
        if self.rating not in ("slider", "buttons"):
            raise ValueError("rating: expected 'slider' or 'buttons', got %r" % (self.rating,))
        lo, hi = self.scale
        if not (type(lo) is int and type(hi) is int and lo < hi):
            raise ValueError("scale: expected two ints lo < hi, got %r" % (self.scale,))


def data_driven(reference: str, texel_samples: int, v: int = FORMAT_NEW) -> dict[str, Any]:
    """The VTd stand-in of a reference: its spectral position as a texel texture."""
    from .references import target_point
    from .space import texel_params
    return texel_params(target_point(reference), texel_samples=texel_samples, seed=0, v=v)


@dataclass
class Evaluate:
    seed: int
    config: Config
    fmt: int = FORMAT_NEW
    ratings: list[dict[str, Any]] = field(default_factory=list)

    def __post_init__(self) -> None:
        c = self.config
        rng = random.Random(self.seed)
        # (a saved texture that does not say its format plays the session's)
        vt = [dict(t, source="preference", texture=dict({"v": self.fmt}, **t["texture"]))
              for t in (c.textures or ())]
        refs = sorted({t["reference"] for t in vt})
        if c.data_driven:
            vt += [{"name": "VTd %s" % r, "reference": r, "source": "data",
                    "texture": data_driven(r, c.texel_samples, self.fmt)} for r in refs]
        rt = [{"name": "RT %s" % r, "reference": r, "source": "real",
               "texture": {"kind": "reference", "name": r}} for r in refs]
        self.textures = rt + vt
        every = list(range(len(self.textures)))
        rng.shuffle(every)              # (a) all textures in random order
        adjectives = [("adjective", k, a) for k in every for a in c.adjectives]
        pairs = list(range(len(rt), len(self.textures)))
        rng.shuffle(pairs)              # (b) real - virtual pairs in random order
        similarity = [("similarity", k, "") for k in pairs]
        first = c.steps if c.steps != "seeded" else \
            ("adjectives_first", "similarity_first")[rng.randrange(2)]
        self.first = first
        self._trials = adjectives + similarity if first == "adjectives_first" \
            else similarity + adjectives

    @property
    def trial(self) -> int:
        return len(self.ratings)

    @property
    def done(self) -> bool:
        return self.trial >= len(self._trials)

    @property
    def plan(self) -> list[dict[str, Any]]:
        """Every trial: step, texture (name, reference, source), adjective."""
        return [{"step": s, "texture": self.textures[k]["name"],
                 "reference": self.textures[k]["reference"],
                 "source": self.textures[k]["source"], "adjective": a}
                for s, k, a in self._trials]

    @property
    def current(self) -> tuple[str, dict[str, Any], str]:
        """(step, the texture entry, adjective or "") of the trial asked now."""
        s, k, a = self._trials[self.trial]
        return s, self.textures[k], a

    def real_of(self, reference: str) -> dict[str, Any]:
        return {"kind": "reference", "name": reference}

    def checked_answer(self, rating: Any) -> float | int:
        if self.done:
            raise ValueError("the evaluation is finished: nothing to answer")
        return rating_of("rating", rating, self.config.scale, self.config.rating)

    def answer(self, rating: Any) -> dict[str, Any]:
        rating = self.checked_answer(rating)
        step, t, a = self.current
        entry = {"trial": self.trial, "step": step, "texture": t["name"],
                 "reference": t["reference"], "source": t["source"], "adjective": a,
                 "rating": rating}
        self.ratings.append(entry)
        return entry
