"""The quantization test (seed 000, "Quantization test"; ../shared/SPEC.md §5):
the participant rates the similarity 1..5 of a reference texture (left half)
and a texel rendering (right half).

Design "paper" (the default): the 27 trials of seed 000 and of the lab's app
(free_exploration_and_quantization_test_app, NU-Haptics-Lab/SinglePitchTexel):
- each of the nine references beside the participant's OWN free-exploration
  match (9) and beside the TRAINED RATER's match (9), unquantized;
- the three family exemplars at 1, 3 and 5 dB of quantization (9).
Every rendering is the very pitch sequence that was felt:
- the participant's own match is the texture that played when they submitted
  it in their free exploration (its parameters and seed: the session's
  matches_from takes them from that session's answer records), with quant_db
  added for a quantized trial (the same draws, each texel's log10 pitch
  rounded: texel.gen.plan);
- the rater's is the logged sequence (study/rater.py: 192 texels of 50
  samples), quantized the same way and played as display samples.

Choices recorded in Config (and so in every session file's header):
- `quantized_source`: whose match the 9 quantized trials quantize. The app's
  compareOrder quantizes the rater's rendering in all nine ("rater", the
  default: what ran); Fig. 15's caption speaks of the subjects' own matches
  ("own" plays that reading).
- `order`: "seeded" (default: the 27 in an order drawn from the session's
  seed) or "lab" (the app's fixed compareOrder, the same for every subject,
  lab_order()).
- `lab_rows`: which texture the app's "reference row" r names. The app
  indexes reference_textures and the rater's data by row; the lab's data
  stores its rows in its test order (reference_textures.mat's
  reference_textures_test_order = [8 3 5 2 6 4 7 1 9], rater.TEST_ORDER), so
  "test_order" (the default, the likelier reading) makes row r texture
  TEST_ORDER[r]: the app's free exploration ran triangle, 4sin, pink, 3sin,
  blue, white, square, 2sin, sawtooth and its quantized rows 2, 5, 9 are
  4sin, blue and sawtooth. "family_order" reads row r in the published
  family order (2sin ... sawtooth; rows 2, 5, 9 = 3sin, pink, sawtooth): the
  reading texelpad had before 2026-11-28. Which one the app loaded is not in
  the published code; under either, each reference sits beside the rater's
  rendering of the same texture. The paper names the exemplars 4sin, pink
  and sawtooth: the default design ("seeded") follows the paper, "lab" plays
  the app's rows as they are.
- `rater_rows`: "by_texture", each reference beside the rater's rendering of
  it (rater.pitches). Sessions written before the rater's file was
  relabelled carry what they played ("statistics-2026", "index-2026":
  rater.LEGACY_ROWS, filled in by study/legacy.py) and replay as they ran.
- the rater's rendering starts at a phase drawn from the session's seed (the
  app's buildFine5 draws rand()); own matches given without a seed (a match
  from a guided exploration or a search) take one drawn from the session's
  seed, the same for every trial of that match.
- texel length of a match given without one: 50 samples (the app's).

Designs kept from before the paper's was built: "levels" (the exemplars'
own matches at each of levels_db, 12 trials) and "matrix" (seed 000's 3 x 3
similarity ratings after the guided exploration: every reference against
every reference's match, at q = levels_db[0]).

The matrix design runs as the lab's guided_exploration_test_app ran its nine
rating trials (NU-Haptics-Lab/SinglePitchTexel; the app's code read from the
.mlapp archive): texture A (the match's rendering, 384 texels of
`texelLength = 50` samples) and texture B (the reference row) each on the
whole display, one at a time as the participant presses their buttons
(loadData of 19,200 samples), in the fixed `ratingorder` = [3,1; 2,1; 1,1;
3,2; 2,2; 1,2; 3,3; 2,3; 1,3] ([match, reference], ratingsLog(match,
reference)). So by default:
- `presentation` "whole" (the reference and the rendering, one at a time on
  the whole display; "split": reference left, rendering right, the design
  before, and the quantization app's layout, the default of the other designs);
- `order` "lab": the references' positions 1..3 in the app's ratingorder
  (MATRIX_LAB_ORDER; "seeded" draws it from the session's seed);
- texel_samples 50 (the shipped similarity-matrix config said 47, while the
  guided exploration the matches come from plays 50).
Noticed, not followed: the app builds texture A from the trained rater's
pitches (refPitch), not from the participant's end points the paper's Fig.
14 rates; texelpad plays the participant's matches (matches_from).

Answers: the similarity rating on `scale` (1..5): any number kept to 0.01
with `rating` "slider" (the app's continuous slider, starting at 3), a whole
number with "buttons". Pure logic.
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from typing import Any

from texel.gen.params import FORMAT_NEW, IRREG_DB_MAX, IRREG_DB_MIN, PITCH_DB_MAX, \
    PITCH_DB_MIN, QUANT_DB_MAX, SEED_MAX, TEXEL_MAX
from texel.gen.reference import STUDY_NAMES as NINE

from . import rater
from .free import check_references, rating_of

EXEMPLARS = ("4sin", "pink", "sawtooth")
DESIGNS = ("paper", "levels", "matrix")
SOURCES = ("own", "rater")
# The app's compareOrder (free_exploration_and_quantization_test_app): [source (0 own,
# 1 rater), reference row (1-based), quantization (decades)]; what a row names: lab_rows.
_APP_COMPARE_ORDER = (
    (0, 3, 0), (0, 1, 0), (1, 5, .1), (1, 9, 0), (1, 2, .1), (1, 9, .5), (0, 9, 0), (1, 7, 0),
    (1, 2, 0), (1, 4, 0), (1, 9, .1), (1, 5, .5), (1, 6, 0), (0, 6, 0), (1, 5, .3), (1, 5, 0),
    (1, 8, 0), (0, 8, 0), (0, 7, 0), (0, 4, 0), (0, 2, 0), (1, 1, 0), (1, 2, .3), (1, 9, .3),
    (0, 5, 0), (1, 3, 0), (1, 2, .5))
# the texture each reference row names, per reading (docstring, `lab_rows`)
LAB_ROWS = {"test_order": rater.TEST_ORDER_NAMES, "family_order": NINE}


def lab_order(rows: str = "test_order") -> tuple[tuple[str, str, float], ...]:
    """(reference, source, quant_db) per trial, in the app's order."""
    names = LAB_ROWS[rows]
    return tuple((names[row - 1], SOURCES[src], round(q * 10.0, 3))
                 for src, row, q in _APP_COMPARE_ORDER)


def lab_exemplars(rows: str = "test_order") -> tuple[str, ...]:
    """The app's quantized references (its rows 2, 5, 9), per reading."""
    names = LAB_ROWS[rows]
    return tuple(names[r - 1] for r in (2, 5, 9))


# the guided app's ratingorder: (match, reference) rows, 1-based positions in `references`
MATRIX_LAB_ORDER = ((3, 1), (2, 1), (1, 1), (3, 2), (2, 2), (1, 2), (3, 3), (2, 3), (1, 3))
PRESENTATIONS = ("whole", "split")
LAB_ORDER = lab_order()
LAB_EXEMPLARS = lab_exemplars()         # 4sin, blue, sawtooth (test order)
RATINGS = ("slider", "buttons")
MATCH_KEYS = {"pitch_db", "irregularity_db"}


MATCH_OPTIONAL = {"seed", "texel_samples", "v"}


def _check_number(what: str, v: Any, lo: float, hi: float) -> None:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
            or not lo <= v <= hi:
        raise ValueError("%s must be in %g .. %g, got %r" % (what, lo, hi, v))


def check_match(r: str, m: Any) -> None:
    """A match: {pitch_db, irregularity_db} and, when it is the texture felt,
    its seed, texel_samples and format v."""
    if not isinstance(m, dict) or not MATCH_KEYS <= set(m) or set(m) - MATCH_KEYS - MATCH_OPTIONAL:
        raise ValueError("matches: %r needs {pitch_db, irregularity_db} (and optionally seed, "
                         "texel_samples), got %r" % (r, m))
    _check_number("matches: pitch_db of %r" % r, m["pitch_db"], PITCH_DB_MIN, PITCH_DB_MAX)
    _check_number("matches: irregularity_db of %r" % r, m["irregularity_db"], IRREG_DB_MIN,
                  IRREG_DB_MAX)
    if "v" in m and (type(m["v"]) is not int or m["v"] not in (1, 2)):
        raise ValueError("matches: v of %r must be 1 or 2 (the texture format felt), got %r"
                         % (r, m["v"]))
    for k, hi in (("seed", SEED_MAX), ("texel_samples", TEXEL_MAX)):
        if k in m and (isinstance(m[k], bool) or not isinstance(m[k], int)
                       or not (k == "seed" or m[k] >= 1) or not 0 <= m[k] <= hi):
            raise ValueError("matches: %s of %r must be an int in %d .. %d, got %r"
                             % (k, r, 0 if k == "seed" else 1, hi, m[k]))


@dataclass(frozen=True)
class Config:
    matches: dict[str, dict[str, Any]] | None = None   # the participant's own (matches_from)
    design: str = "paper"
    references: tuple[str, ...] = ()        # () = the design's: paper the nine, else EXEMPLARS
    exemplars: tuple[str, ...] = EXEMPLARS      # paper: the quantized ones
    levels_db: tuple[float, ...] = ()       # () = paper (1, 3, 5); levels (0, 1, 3, 5); matrix (0,)
    quantized_source: str = "rater"
    order: str = ""                     # "" = the design's: matrix "lab", else "seeded"
    presentation: str = ""              # "" = the design's: matrix "whole", else "split"
    lab_rows: str = "test_order"        # what the app's reference rows name (docstring)
    rater_rows: str = "by_texture"      # (older sessions: rater.LEGACY_ROWS, study/legacy.py)
    repeats: int = 1
    texel_samples: int = 50
    scale: tuple[int, int] = (1, 5)
    # the app's DifferentSlider / SimilaritySlider: continuous over the scale, at 3 to start
    # (kept to 0.01); "buttons": whole numbers, one button each (the design before)
    rating: str = "slider"
    match_source: str = "given"         # "given" or the session ids the matches came from

    def __post_init__(self) -> None:
        if self.design not in DESIGNS:
            raise ValueError("design: expected one of %s, got %r" % (", ".join(DESIGNS),
                                                                      self.design))
        if not self.references:
            object.__setattr__(self, "references", NINE if self.design == "paper" else EXEMPLARS)
        if not self.order:
            object.__setattr__(self, "order", "lab" if self.design == "matrix" else "seeded")
        if not self.presentation:
            object.__setattr__(self, "presentation",
                               "whole" if self.design == "matrix" else "split")
        if not self.levels_db:
            object.__setattr__(self, "levels_db", {"paper": (1.0, 3.0, 5.0),
                                                   "levels": (0.0, 1.0, 3.0, 5.0),
                                                   "matrix": (0.0,)}[self.design])
        self._check_lists()
        if self.matches is not None:
            if not isinstance(self.matches, dict):
                raise ValueError("matches: expected {reference: {pitch_db, irregularity_db}}")
            for r in self.references:
                if r not in self.matches:
                    raise ValueError("matches: no match of %r (the participant's own: start the "
                                     "session with matches_from)" % (r,))
                check_match(r, self.matches[r])
        if isinstance(self.repeats, bool) or not isinstance(self.repeats, int) \
                or not 1 <= self.repeats <= 10:
            raise ValueError("repeats: expected 1 .. 10, got %r" % (self.repeats,))
        if isinstance(self.texel_samples, bool) or not isinstance(self.texel_samples, int) \
                or not 1 <= self.texel_samples <= TEXEL_MAX:
            raise ValueError("texel_samples: expected an int 1 .. %d, got %r"
                             % (TEXEL_MAX, self.texel_samples))

    def _check_lists(self) -> None:
        check_references(self.references)
        for q in self.levels_db:
            if isinstance(q, bool) or not isinstance(q, (int, float)) \
                    or not (q == 0 or 0.001 <= q <= QUANT_DB_MAX):
                raise ValueError("levels_db: each 0 (off) or 0.001 .. %g dB, got %r"
                                 % (QUANT_DB_MAX, q))
        if self.quantized_source not in SOURCES:
            raise ValueError("quantized_source: expected 'rater' (the app's) or 'own' (Fig. "
                             "15's caption), got %r" % (self.quantized_source,))
        if self.rating not in RATINGS:
            raise ValueError("rating: expected 'slider' (continuous, the app's) or 'buttons', "
                             "got %r" % (self.rating,))
        if self.rater_rows not in rater.ROWS + rater.LEGACY_ROWS:
            raise ValueError("rater_rows: expected 'by_texture' (each reference beside the "
                             "rater's rendering of it), got %r" % (self.rater_rows,))
        if self.lab_rows not in LAB_ROWS:
            raise ValueError("lab_rows: expected 'test_order' (the app's rows in the lab's "
                             "test order, the default) or 'family_order', got %r"
                             % (self.lab_rows,))
        if self.order not in ("seeded", "lab"):
            raise ValueError("order: expected 'seeded' or 'lab' (the app's fixed order), got %r"
                             % (self.order,))
        if self.presentation not in PRESENTATIONS:
            raise ValueError("presentation: expected 'whole' (the reference and the rendering "
                             "one at a time on the whole display, the guided app's) or 'split' "
                             "(reference left, rendering right), got %r" % (self.presentation,))
        if self.design == "paper":
            check_references(self.exemplars)
            if any(e not in self.references for e in self.exemplars):
                raise ValueError("exemplars: each must be among the references, got %r"
                                 % (self.exemplars,))
            if 0 in self.levels_db:
                raise ValueError("levels_db: the paper's design quantizes at 1, 3, 5 dB (its "
                                 "unquantized trials are the 18); 0 is not a level here")
        if self.order == "lab" and self.repeats != 1:
            raise ValueError("repeats: order 'lab' plays the app's %s trials once, got %r"
                             % ("9" if self.design == "matrix" else "27", self.repeats))
        if self.order == "lab" and self.design == "matrix":
            if len(self.references) != 3:
                raise ValueError("order 'lab' plays the guided app's nine rating trials: three "
                                 "references, got %d" % len(self.references))
        elif self.order == "lab" and (self.design != "paper" or tuple(self.references) != NINE
                                    or tuple(self.exemplars) != lab_exemplars(self.lab_rows)
                                    or tuple(self.levels_db) != (1.0, 3.0, 5.0)):
            raise ValueError("order 'lab' plays the app's 27 trials as they were: design "
                             "'paper', the nine references, exemplars %s (lab_rows %r), "
                             "levels 1, 3, 5 dB"
                             % (", ".join(lab_exemplars(self.lab_rows)), self.lab_rows))

    def trials(self, rng: random.Random) -> list[tuple[str, str, str, float]]:
        """(reference, whose match, source, quant_db) per trial, in order."""
        if self.design == "paper":
            if self.order == "lab":
                return [(r, r, self.quantized_source if q else s, q) for r, s, q in lab_order(self.lab_rows)]
            t = [(r, r, s, 0.0) for s in SOURCES for r in self.references]
            t += [(e, e, self.quantized_source, float(q)) for e in self.exemplars
                  for q in self.levels_db]
        elif self.design == "levels":
            t = [(r, r, "own", float(q)) for r in self.references for q in self.levels_db]
        else:
            q = float(self.levels_db[0])
            if self.order == "lab":     # the guided app's ratingorder, nothing drawn
                refs = self.references
                return [(refs[r - 1], refs[m - 1], "own", q) for m, r in MATRIX_LAB_ORDER]
            t = [(r, m, "own", q) for r in self.references for m in self.references]
        t = t * self.repeats
        rng.shuffle(t)
        return t


@dataclass
class Quant:
    seed: int
    config: Config
    ratings: list[dict[str, Any]] = field(default_factory=list)

    def __post_init__(self) -> None:
        rng = random.Random(self.seed)
        c = self.config
        # (drawn first, then the order, then the phases: the draws of the sessions
        # before the paper's design, which replay as they ran - study/legacy.py)
        self.texture_seeds = {r: rng.randrange(1 << 32) for r in c.references}
        self._trials = c.trials(rng)
        # the rater's renderings' start phases (buildFine5's rand()), one per trial
        self._phases = [rng.randrange(1 << 24) / float(1 << 24) for _ in self._trials]

    @property
    def trials(self) -> list[tuple[str, float]]:
        """(reference, q) per trial, in order."""
        return [(r, q) for r, _, _, q in self._trials]

    @property
    def plan(self) -> list[dict[str, Any]]:
        """Every trial as a dict: reference, match_of, source, quant_db."""
        return [{"reference": r, "match_of": m, "source": s, "quant_db": q}
                for r, m, s, q in self._trials]

    @property
    def phases(self) -> list[float]:
        """Each trial's start phase (cycles) of the rater's rendering."""
        return list(self._phases)

    @property
    def trial(self) -> int:
        return len(self.ratings)

    @property
    def done(self) -> bool:
        return self.trial >= len(self._trials)

    @property
    def current(self) -> tuple[str, float]:
        """(the reference, q) of the current trial."""
        return self.trials[self.trial]

    @property
    def current_match(self) -> str:
        """Whose match the current rendering is (the reference's own, or in
        the matrix design another's)."""
        return self._trials[self.trial][1]

    @property
    def current_source(self) -> str:
        """"own" (the participant's match) or "rater" (the trained rater's)."""
        return self._trials[self.trial][2]

    def own_texture(self, match_of: str, q: float, v: int = FORMAT_NEW) -> dict[str, Any]:
        """The participant's match of `match_of` as the texel texture felt,
        quantized at q."""
        if self.config.matches is None:
            raise ValueError("matches: this quantization test has no matches of the "
                             "participant's own (start it with matches_from)")
        m = self.config.matches[match_of]
        return {"pitch_db": round(float(m["pitch_db"]), 3),
                "irregularity_db": round(float(m["irregularity_db"]), 3),
                "quant_db": q, "texel_samples": m.get("texel_samples", self.config.texel_samples),
                "seed": m.get("seed", self.texture_seeds[match_of]), "v": m.get("v", v)}

    def texture(self, v: int = FORMAT_NEW) -> dict[str, Any]:
        """The current trial's rendering: the participant's match as a texel
        texture of format v, or the rater's logged sequence as display
        samples ({"kind": "samples", "fit": "tile", "u16": ...})."""
        ref, match, source, q = self._trials[self.trial]
        if source == "rater":
            return {"kind": "samples", "fit": "tile",
                    "u16": rater.rendering(match, q, self._phases[self.trial],
                                           self.config.rater_rows)}
        return self.own_texture(match, q, v)

    def checked_answer(self, rating: Any) -> float | int:
        """The rating checked on the scale (ValueError says why)."""
        if self.done:
            raise ValueError("the quantization test is finished: nothing to answer")
        return rating_of("similarity", rating, self.config.scale, self.config.rating)

    def answer(self, rating: Any) -> dict[str, Any]:
        rating = self.checked_answer(rating)
        ref, match, source, q = self._trials[self.trial]
        entry = {"trial": self.trial, "reference": ref, "match_of": match, "source": source,
                 "quant_db": q, "similarity": rating}
        self.ratings.append(entry)
        return entry
