"""Texel parameter mapping (seed 001's second experiment, "Texel Parameter
Mapping"; ../shared/seeds/001_*.txt §III.B.2, results §IV.B, Fig. 4 and 5),
as a state machine in two phases.

Phase "match": nine trials, one per reference texture of Table I (band-pass
noise, central frequency 1, 4, 20 c/mm x zeta = 1/(2Q) 0.05, 0.5, 5:
texelpad.study.bandpass). The reference plays on the left half of the
display, the texel rendering of two sliders "Pitch" P and "Irregularity" I,
each 0 .. 100, on the right; every slider change re-renders (a fresh texture
seed per change, drawn from the session's seed, so a session replays
exactly). The rendering is seed 001's: a lognormal pitch distribution with
mean mu = 0.75 * 1.04**P c/mm and SD sigma = 3*I/10 c/mm in LINEAR units
(P = 0 -> 0.75, P = 100 -> 37.9 c/mm; I = 100 -> 30 c/mm, I = 0 -> 0),
converted to the generator's pitch_db/irregularity_db by
texel.gen.lognormal.to_db (sigma = 0 plays the generator's narrowest, -30 dB),
texel length 1 mm (1 mm / 5.3 um = 188.7 -> 189 display samples, 1.0017 mm),
frequencies constrained to exceed 1 c/mm ("min_cpmm": 1.0) and no phase
continuity at texel borders ("phase": "reset"). When satisfied the
participant submits: that is the trial's answer (no confidence rating in this
paper).

Phase "rate": 25 of the 81 (reference x rendering of a reference's match)
pairs, side by side, each rated 0 (completely different) .. 10 (identical).

Choices the paper leaves open, recorded in Config (and so in every session
file's header); each is ours:
- trial order: a shuffle drawn from the session's seed, in both phases
  (`shuffle`; False keeps the config's order);
- the sliders start at 50/50 (`start`) and move in steps of 1 (`step`: 101
  positions, a factor 1.04 = 0.17 dB of mean pitch and 0.3 c/mm of SD per
  step); a value between steps is rounded to the nearest step;
- texel length 189 samples (`texel_samples`: the paper's 1 mm on the 5.3 um
  grid); the lower bound and the phase reset are the paper's, Config fields
  (`min_cpmm`, `phase`) so a lab can switch them off; with the bound, a mean
  below 1 c/mm (P < 7.3) at small I plays mostly at the bound (the
  generator's truncation: docs/generator.md, "Seed 001's stimulus");
- no band limit: as on the paper's TPad (same 5.3 um grid), pitches drawn
  above Nyquist (94.34 c/mm) alias - about 5 % of texels at P = I = 100;
- the 25 rated pairs (`ratings`, (reference, match_of) each): the paper says
  only that they "spanned both distribution parameters at each level tested"
  and that some were a reference against its own best match. Our default,
  DEFAULT_RATINGS: the 9 references against their own match; for each zeta
  the lowest- and highest-frequency pair both ways (6, Fig. 5a); for each
  frequency the lowest- and highest-zeta pair both ways (6, Fig. 5b); the
  centre (4 c/mm, 0.5) against the four corners' matches (4) = 25;
- a rating plays the participant's match with a texture seed drawn from the
  session's seed, one per match (the same rendering in every pair it is in);
- the references: seed 0 (`reference_seed`: the device's own bp-<fc>-<zeta>
  realisation), uploaded as 9,600 uint16 samples ("samples", the same on
  every board) or played by the board itself ("board", seed 0 only)
  (`reference_play`); friction levels +-3 SD over 0 .. 1 (bandpass.py).
  "samples" re-uploads the 9,600 values with every slider change (about
  85 ms of bench.lab's 172 ms median per change on the virtual board);
  "board" builds it once per trial and reuses it, but that build takes
  18.9 s on an RP2040 (bench/results/seed001_options.txt);
- summary(): Fig. 4b's "normalized" Irregularity is min-max over the
  participant's nine matches; the self-match statistic's SD is the sample SD.

Answers: phase "match" {"pitch": P, "irregularity": I}; phase "rate" the
similarity, an int 0 .. 10. Pure logic.
"""
from __future__ import annotations

import math
import random
import statistics
from dataclasses import dataclass, field
from typing import Any

from texel.gen.lognormal import to_db
from texel.gen.params import FORMAT_NEW, NYQUIST_CPMM, SEED_MAX

from . import bandpass

NINE = bandpass.NAMES
# seed 001: mu = (1.04**P) * 0.75 c/mm, sigma = 3*I/10 c/mm (sliders 0 .. 100)
MEAN_BASE_CPMM = 0.75
MEAN_RATIO = 1.04
SD_PER_STEP_CPMM = 0.3
SLIDER = (0.0, 100.0)
PHASES = ("continuous", "reset")
PLAYS = ("samples", "board")


def _default_ratings() -> tuple[tuple[str, str], ...]:
    name = bandpass.name_of
    lo_f, hi_f = bandpass.FC_CPMM[0], bandpass.FC_CPMM[-1]
    lo_z, hi_z = bandpass.ZETAS[0], bandpass.ZETAS[-1]
    pairs = [(r, r) for r in NINE]
    for z in bandpass.ZETAS:            # Fig. 5a: lowest vs highest frequency, zeta equal
        a, b = name(lo_f, z), name(hi_f, z)
        pairs += [(a, b), (b, a)]
    for f in bandpass.FC_CPMM:          # Fig. 5b: lowest vs highest zeta, frequency equal
        a, b = name(f, lo_z), name(f, hi_z)
        pairs += [(a, b), (b, a)]
    centre = name(bandpass.FC_CPMM[1], bandpass.ZETAS[1])
    pairs += [(centre, name(f, z)) for f in (lo_f, hi_f) for z in (lo_z, hi_z)]
    return tuple(pairs)


DEFAULT_RATINGS = _default_ratings()

# The paper's reported numbers (seed 001 §IV.B), for the export's comparison.
PAPER: tuple[dict[str, Any], ...] = (
    {"what": "subjects", "value": 5,
     "source": "seed 001 §IV.B: \"There were 5 subjects for the second experiment, 2 female.\""},
    {"what": "self_similarity_mean", "value": 8.11,
     "source": "seed 001 §IV.B: \"the average similarity rating between each reference signal "
               "and its texel-based best match: 8.11 (standard deviation: 2.76)\""},
    {"what": "self_similarity_sd", "value": 2.76, "source": "seed 001 §IV.B, as above"},
    {"what": "ratings", "value": 25,
     "source": "seed 001 §III.B.2: \"only 25 of the possible 81 comparisons were investigated\""},
    {"what": "fig4a", "value": "at zeta 5 subjects reliably overestimated Pitch",
     "source": "seed 001 §V (Fig. 4a)"},
    {"what": "fig4b", "value": "mean chosen Irregularity increases monotonically with zeta",
     "source": "seed 001 §V (Fig. 4b)"},
    {"what": "fig5a", "value": "highest mean similarity of lowest- vs highest-frequency pairs "
                               "at the highest zeta", "source": "seed 001 §V (Fig. 5a)"},
    {"what": "fig5b", "value": "lowest- vs highest-zeta pairs rated less similar at low "
                               "frequency than at high", "source": "seed 001 §V (Fig. 5b)"},
)


def _is_num(x: Any) -> bool:
    return not isinstance(x, bool) and isinstance(x, (int, float)) and math.isfinite(x)


def _check_int(key: str, x: Any, lo: int, hi: int) -> None:
    if isinstance(x, bool) or not isinstance(x, int) or not lo <= x <= hi:
        raise ValueError("%s: expected an int in %d .. %d, got %r" % (key, lo, hi, x))


@dataclass(frozen=True)
class Config:
    references: tuple[str, ...] = NINE
    ratings: tuple[tuple[str, str], ...] = DEFAULT_RATINGS   # (reference, match_of) pairs
    start: tuple[float, float] = (50.0, 50.0)                # (P, I), ours
    step: float = 1.0                                        # slider resolution, ours
    texel_samples: int = 189                                 # 1 mm / 5.3 um, rounded
    min_cpmm: float | None = 1.0                             # paper; None: no bound
    phase: str = "reset"                                     # paper; "continuous": ours
    scale: tuple[int, int] = (0, 10)
    shuffle: bool = True                                     # ours: seeded trial order
    reference_seed: int = 0                                  # ours: the device's realisation
    reference_play: str = "samples"                          # ours: "samples" | "board"

    def __post_init__(self) -> None:
        refs = self.references
        if not isinstance(refs, tuple) or not refs or len(set(refs)) != len(refs) \
                or any(r not in NINE for r in refs):
            raise ValueError("references: expected distinct names among %s, got %r"
                             % (", ".join(NINE), refs))
        # JSON gives the pairs as lists: kept as tuples (the config is frozen)
        object.__setattr__(self, "ratings", _check_ratings(self.ratings, refs))
        if not _is_num(self.step) or not 0 < self.step <= SLIDER[1]:
            raise ValueError("step: expected a number in (0, %g], got %r" % (SLIDER[1], self.step))
        if not isinstance(self.start, tuple) or len(self.start) != 2 \
                or not all(_is_num(s) and SLIDER[0] <= s <= SLIDER[1] for s in self.start):
            raise ValueError("start: expected (P, I), each %g .. %g, got %r"
                             % (SLIDER[0], SLIDER[1], self.start))
        _check_int("texel_samples", self.texel_samples, 1, 1048576)
        if self.min_cpmm is not None and (not _is_num(self.min_cpmm)
                                          or not 0.01 <= self.min_cpmm < NYQUIST_CPMM):
            raise ValueError("min_cpmm: expected None or a number in 0.01 .. %.2f c/mm, got %r"
                             % (NYQUIST_CPMM, self.min_cpmm))
        if self.phase not in PHASES:
            raise ValueError("phase: expected one of %s, got %r" % (", ".join(PHASES), self.phase))
        lo, hi = self.scale if isinstance(self.scale, tuple) and len(self.scale) == 2 else (1, 0)
        if not (type(lo) is int and type(hi) is int and lo < hi):
            raise ValueError("scale: expected (low, high) ints, low < high, got %r" % (self.scale,))
        if not isinstance(self.shuffle, bool):
            raise ValueError("shuffle: expected true or false, got %r" % (self.shuffle,))
        _check_int("reference_seed", self.reference_seed, 0, SEED_MAX)
        if self.reference_play not in PLAYS:
            raise ValueError("reference_play: expected one of %s, got %r"
                             % (", ".join(PLAYS), self.reference_play))
        if self.reference_play == "board" and self.reference_seed != 0:
            raise ValueError("reference_play: 'board' plays the device's seed-0 reference only, "
                             "got reference_seed %r" % (self.reference_seed,))


def _check_ratings(pairs: Any, refs: tuple[str, ...]) -> tuple[tuple[str, str], ...]:
    # distinct pairs of the references: at most len(refs)**2 of them
    if not isinstance(pairs, (tuple, list)):
        raise ValueError("ratings: expected up to %d [reference, match_of] pairs, got %r"
                         % (len(refs) ** 2, pairs))
    out = []
    for k, p in enumerate(pairs):
        if not isinstance(p, (tuple, list)) or len(p) != 2 or any(x not in refs for x in p):
            raise ValueError("ratings[%d]: expected [reference, match_of], both among the "
                             "references %s, got %r (a lab that runs fewer references "
                             "gives its own ratings)" % (k, ", ".join(refs), p))
        out.append((p[0], p[1]))
    if len(set(out)) != len(out):
        raise ValueError("ratings: a pair is listed twice in %r" % (pairs,))
    return tuple(out)


def slider_values(pitch: float, irregularity: float) -> tuple[float, float]:
    """(mean_cpmm, sd_cpmm) of a slider setting, seed 001's mapping:
    mu = 0.75 * 1.04**P, sigma = 3*I/10, both c/mm."""
    return MEAN_BASE_CPMM * MEAN_RATIO ** pitch, SD_PER_STEP_CPMM * irregularity


def _slider(key: str, x: Any, step: float) -> float:
    if not _is_num(x):
        raise ValueError("%s: expected a number, got %r" % (key, x))
    if not SLIDER[0] <= x <= SLIDER[1]:
        raise ValueError("%s: %r is outside the slider's %g .. %g" % (key, x, *SLIDER))
    # the nearest step (halves up), kept to 1e-6 so 3 steps of 0.1 read 0.3;
    # never past the slider's end when the range is not a whole number of steps
    return min(SLIDER[1], round(math.floor(x / step + 0.5) * step, 6))


@dataclass
class Mapping:
    seed: int
    config: Config = field(default_factory=Config)
    matches: list[dict[str, Any]] = field(default_factory=list)    # phase "match", in order
    ratings: list[dict[str, Any]] = field(default_factory=list)    # phase "rate", in order

    def __post_init__(self) -> None:
        rng = random.Random(self.seed)
        c = self.config
        order = list(c.references)
        pairs = list(c.ratings)
        if c.shuffle:
            rng.shuffle(order)
        # one texture seed per match: the same rendering in every pair it is in
        self.rating_seeds = {r: rng.randrange(1 << 32) for r in c.references}
        if c.shuffle:
            rng.shuffle(pairs)
        self.order = order
        self.pairs = pairs

    # --- where the protocol is ---------------------------------------------
    @property
    def phase(self) -> str:
        """"match", "rate" or "done"."""
        if len(self.matches) < len(self.order):
            return "match"
        return "rate" if len(self.ratings) < len(self.pairs) else "done"

    @property
    def done(self) -> bool:
        return self.phase == "done"

    @property
    def trial(self) -> int:
        """The current trial's index within its phase."""
        return len(self.matches) if self.phase == "match" else len(self.ratings)

    @property
    def reference(self) -> str:
        """The reference of the current trial (left half), in either phase."""
        ph = self.phase
        if ph == "match":
            return self.order[len(self.matches)]
        if ph == "rate":
            return self.pairs[len(self.ratings)][0]
        raise ValueError("the mapping is finished: no current reference")

    @property
    def current(self) -> tuple[str, str]:
        """(the reference, whose match the rendering is) of the current rating."""
        if self.phase != "rate":
            raise ValueError("current: only in phase 'rate' (now %r)" % (self.phase,))
        return self.pairs[len(self.ratings)]

    def match_of(self, reference: str) -> dict[str, Any] | None:
        for m in self.matches:
            if m["reference"] == reference:
                return m
        return None

    # --- what plays ---------------------------------------------------------
    def check(self, pitch: Any, irregularity: Any) -> tuple[float, float]:
        """Slider values, checked and on the slider's grid (ValueError says why)."""
        return (_slider("pitch", pitch, self.config.step),
                _slider("irregularity", irregularity, self.config.step))

    def _texel(self, pitch: float, irregularity: float, seed: int, v: int) -> dict[str, Any]:
        c = self.config
        pitch_db, irregularity_db = to_db(*slider_values(pitch, irregularity))
        tex: dict[str, Any] = {"pitch_db": pitch_db, "irregularity_db": irregularity_db,
                               "texel_samples": c.texel_samples}
        if c.min_cpmm is not None:          # texel.gen.params: set keys only
            tex["min_cpmm"] = float(c.min_cpmm)
        if c.phase != "continuous":
            tex["phase"] = c.phase
        tex.update(seed=seed, v=v)
        return tex

    def texture(self, pitch: Any, irregularity: Any, move: int,
                v: int = FORMAT_NEW) -> dict[str, Any]:
        """The texel rendering of a slider setting at the trial's move-th
        change (phase "match"): format v, its own seed (each change re-draws)."""
        if self.phase != "match":
            raise ValueError("texture: only in phase 'match' (now %r)" % (self.phase,))
        p, i = self.check(pitch, irregularity)
        rng = random.Random((self.seed * 1000003 + self.trial) * 1000003 + move)
        return self._texel(p, i, rng.randrange(1 << 32), v)

    def rating_texture(self, v: int = FORMAT_NEW) -> dict[str, Any]:
        """The current rating's rendering: the participant's match of
        current[1], with that match's texture seed."""
        _, of = self.current
        m = self.match_of(of)
        assert m is not None            # the match phase answered every reference
        return self._texel(m["pitch"], m["irregularity"], self.rating_seeds[of], v)

    def reference_texture(self) -> dict[str, Any]:
        """The current reference as the display plays it (config reference_play)."""
        c = self.config
        if c.reference_play == "board":
            return bandpass.board_texture(self.reference)
        return bandpass.reference_texture(self.reference, c.reference_seed)

    # --- answers -------------------------------------------------------------
    def checked_answer(self, a: Any) -> Any:
        """The answer checked and on the grid (ValueError says why; nothing changes)."""
        ph = self.phase
        if ph == "done":
            raise ValueError("the mapping is finished: nothing to answer")
        if ph == "match":
            if not isinstance(a, dict) or set(a) != {"pitch", "irregularity"}:
                raise ValueError("answer: phase 'match' expects {pitch, irregularity} "
                                 "(sliders 0 .. 100), got %r" % (a,))
            p, i = self.check(a["pitch"], a["irregularity"])
            return {"pitch": p, "irregularity": i}
        lo, hi = self.config.scale
        if isinstance(a, bool) or not isinstance(a, int) or not lo <= a <= hi:
            raise ValueError("similarity: phase 'rate' expects an int %d .. %d, got %r"
                             % (lo, hi, a))
        return a

    def answer(self, a: Any) -> dict[str, Any]:
        a = self.checked_answer(a)
        if self.phase == "match":
            entry = dict(self._describe(self.reference, a["pitch"], a["irregularity"]),
                         trial=self.trial)
            self.matches.append(entry)
            return entry
        ref, of = self.current
        m = self.match_of(of)
        assert m is not None
        fc, zeta = bandpass.params_of(ref)
        entry = {"trial": self.trial, "reference": ref, "fc_cpmm": fc, "zeta": zeta,
                 "match_of": of, "self": ref == of, "pitch": m["pitch"],
                 "irregularity": m["irregularity"], "mean_cpmm": m["mean_cpmm"],
                 "sd_cpmm": m["sd_cpmm"], "pitch_db": m["pitch_db"],
                 "irregularity_db": m["irregularity_db"], "seed": self.rating_seeds[of],
                 "similarity": a}
        self.ratings.append(entry)
        return entry

    def _describe(self, ref: str, p: float, i: float) -> dict[str, Any]:
        fc, zeta = bandpass.params_of(ref)
        mean, sd = slider_values(p, i)
        pitch_db, irregularity_db = to_db(mean, sd)
        return {"reference": ref, "fc_cpmm": fc, "zeta": zeta, "pitch": p, "irregularity": i,
                "mean_cpmm": round(mean, 6), "sd_cpmm": round(sd, 6),
                "pitch_db": pitch_db, "irregularity_db": irregularity_db}


# --- the export's summary (Fig. 4, Fig. 5, the similarity matrix) --------------
def _normalised(values: list[float]) -> list[float | None]:
    lo, hi = min(values), max(values)
    return [None if hi == lo else round((x - lo) / (hi - lo), 6) for x in values]


def _stats(xs: list[int]) -> dict[str, Any]:
    return {"n": len(xs), "mean": round(statistics.fmean(xs), 4) if xs else None,
            "sd": round(statistics.stdev(xs), 4) if len(xs) > 1 else None, "ratings": xs}


def summary(state: Mapping) -> dict[str, Any]:
    """Fig. 4 and 5's data and the similarity matrix of one participant's
    session (so far). JSON-friendly:
    - fig4a: per zeta, per central frequency, the chosen P (and mean c/mm);
    - fig4b: per central frequency, per zeta, the chosen I, its min-max
      normalisation over the participant's matches, and the SD c/mm;
    - similarity: 9 x 9, rows the reference, columns whose match, Table I
      order (bandpass.NAMES), None where not rated;
    - self: the ratings of a reference against its own match (mean, sample SD);
      fig5a / fig5b: the lowest- vs highest-frequency (zeta equal) and lowest-
      vs highest-zeta (frequency equal) pairs, both ways;
    - paper: PAPER, what seed 001 reports."""
    by_ref = {m["reference"]: m for m in state.matches}
    norm = dict(zip(by_ref, _normalised([m["irregularity"] for m in by_ref.values()]))) \
        if by_ref else {}
    fcs, zetas, name = bandpass.FC_CPMM, bandpass.ZETAS, bandpass.name_of

    def get(ref: str, key: str) -> Any:
        return by_ref[ref][key] if ref in by_ref else None

    fig4a = [{"zeta": z, "fc_cpmm": list(fcs),
              "pitch": [get(name(f, z), "pitch") for f in fcs],
              "mean_cpmm": [get(name(f, z), "mean_cpmm") for f in fcs]} for z in zetas]
    fig4b = [{"fc_cpmm": f, "zeta": list(zetas),
              "irregularity": [get(name(f, z), "irregularity") for z in zetas],
              "irregularity_normalised": [norm.get(name(f, z)) for z in zetas],
              "sd_cpmm": [get(name(f, z), "sd_cpmm") for z in zetas]} for f in fcs]
    rated = {(r["reference"], r["match_of"]): r["similarity"] for r in state.ratings}
    matrix = [[rated.get((a, b)) for b in NINE] for a in NINE]

    def both(a: str, b: str) -> list[int]:
        return [rated[p] for p in ((a, b), (b, a)) if p in rated]

    fig5a = [dict(_stats(both(name(fcs[0], z), name(fcs[-1], z))), zeta=z) for z in zetas]
    fig5b = [dict(_stats(both(name(f, zetas[0]), name(f, zetas[-1]))), fc_cpmm=f) for f in fcs]
    return {"references": list(NINE), "fig4a": fig4a, "fig4b": fig4b, "similarity": matrix,
            "self": _stats([rated[(r, r)] for r in NINE if (r, r) in rated]),
            "fig5a": fig5a, "fig5b": fig5b, "paper": [dict(p) for p in PAPER]}
