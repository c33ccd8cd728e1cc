"""The texel-length oddity staircase (seed 001, the earlier paper; ../shared/SPEC.md
§5): three textures, two drawn from the same distribution, the participant
picks the odd one; 1-up-3-down on texel length from 26 mm in 2.5 mm steps,
1.25 mm steps after 7 reversals, stop after 10 reversals; 30 s per trial.

1-up-3-down: three correct answers in a row shorten the texels (harder: below
a threshold length, textures drawn from the same distribution cannot be told
apart - seed 001, "decreasing texel length with correct responses"), one
wrong answer lengthens them. It converges on 79.4 % correct (Levitt 1971).
Each of the three textures fills the display with as many texels of the
trial's length as fit (seed 001): two seeds, one of them shown twice. A
reversal is a change of direction; the paper reports a "convergent texel
length" without its formula, so the threshold here is the mean length at the
reversals after the step size changed (8..10), a choice recorded in Config.

The stimulus is seed 001's ("The underlying frequency distribution used was
a lognormal distribution ... mean 4 cycles/mm ... standard deviation 1.2 or
4.3 cycles/mm, depending on whether the subject was given the narrow or wide
Irregularity condition"; "distribution frequencies are constrained to exceed
1 cycle/mm"; its generator has no phase continuity at texel borders - the
borders are the cue under test): `condition` "narrow" (SD 1.2) or "wide"
(4.3), mean `mean_cpmm` 4, both in LINEAR units (texel.gen.lognormal.to_db
gives the generator's pitch_db/irregularity_db of that lognormal),
`min_cpmm` 1 (the generator redraws pitches below it: docs/generator.md) and
`phase` "reset". A config's "distribution" (a texel texture's keys) still
replaces the whole stimulus, as before. Each texture holds as many whole
texels as fit in `fit_mm` (100 mm, seed 001's display) and in the board's
display (the TPaD here: 101.76 mm); `whole_texels` false plays one texel
region over the whole display instead (the design before, and what a
display shorter than one texel plays: the one texel, cut at its end).

Choices recorded in Config: the floor (one step: a length never goes below
it), the threshold rule; `remainder_level`: the display after the last whole
texel (seed 001: "the maximum number of texels for the trial's texel length
that fit in the 100-mm display length") plays this constant friction level,
0 (the lab's apps clear the display with zeros). Pure logic.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from texel.gen.lognormal import to_db
from texel.gen.params import DX_MM, NYQUIST_CPMM

from .finger import FINGER_HZ

CONDITIONS = {"narrow": 1.2, "wide": 4.3}     # seed 001: the lognormal's SD, c/mm


@dataclass(frozen=True)
class Config:
    start_mm: float = 26.0
    step_mm: float = 2.5
    fine_step_mm: float = 1.25
    fine_after_reversals: int = 7
    stop_after_reversals: int = 10
    down_after: int = 3             # correct answers in a row before a step down
    floor_mm: float = 1.25          # never shorter than this
    trial_seconds: float = 30.0
    threshold_from_reversal: int = 8  # mean of the lengths at reversals >= this (1-based)
    condition: str = "narrow"
    mean_cpmm: float = 4.0
    min_cpmm: float | None = 1.0
    phase: str = "reset"
    remainder_level: float = 0.0
    whole_texels: bool = True       # False: one texel region over the whole display (before)
    fit_mm: float = 100.0           # seed 001: the texels that fit in the 100-mm display
    # the finger recorded per trial (seed 001 reports swipe speeds and directions, Fig. 3):
    # the board's telemetry at this many samples per second, in the session (study/finger.py);
    # 0: none (sessions of format /3 and older recorded none)
    finger_hz: int = FINGER_HZ

    def texture(self) -> dict:
        """The texel texture's keys of the staircase's distribution (no
        texel length, no seed: each trial sets them)."""
        p, s = to_db(self.mean_cpmm, CONDITIONS[self.condition])
        out: dict = {"pitch_db": p, "irregularity_db": s}
        if self.min_cpmm is not None:
            out["min_cpmm"] = float(self.min_cpmm)
        if self.phase != "continuous":
            out["phase"] = self.phase
        return out

    def __post_init__(self) -> None:
        if self.condition not in CONDITIONS:
            raise ValueError("condition: expected 'narrow' (SD 1.2 c/mm) or 'wide' (SD 4.3 "
                             "c/mm), got %r" % (self.condition,))
        if isinstance(self.finger_hz, bool) or not isinstance(self.finger_hz, int) \
                or not 0 <= self.finger_hz <= 1000:
            raise ValueError("finger_hz: expected telemetry samples per second 0 (none) .. "
                             "1000, got %r" % (self.finger_hz,))
        if self.phase not in ("continuous", "reset"):
            raise ValueError("phase: expected 'reset' (seed 001) or 'continuous', got %r"
                             % (self.phase,))
        if isinstance(self.remainder_level, bool) or \
                not isinstance(self.remainder_level, (int, float)) \
                or not 0.0 <= self.remainder_level <= 1.0:
            raise ValueError("remainder_level: expected a friction level 0 .. 1, got %r"
                             % (self.remainder_level,))
        if self.min_cpmm is not None and (isinstance(self.min_cpmm, bool) or not isinstance(
                self.min_cpmm, (int, float)) or not 0.01 <= self.min_cpmm <= NYQUIST_CPMM):
            raise ValueError("min_cpmm: expected null or 0.01 .. %.2f c/mm, got %r"
                             % (NYQUIST_CPMM, self.min_cpmm))
        if not isinstance(self.whole_texels, bool):
            raise ValueError("whole_texels: expected true or false, got %r"
                             % (self.whole_texels,))
        if isinstance(self.fit_mm, bool) or not isinstance(self.fit_mm, (int, float)) \
                or not 0 < self.fit_mm <= 10000:
            raise ValueError("fit_mm: expected a length in mm > 0, got %r" % (self.fit_mm,))
        if isinstance(self.mean_cpmm, bool) or not isinstance(self.mean_cpmm, (int, float)):
            raise ValueError("mean_cpmm: expected a number, got %r" % (self.mean_cpmm,))
        self.texture()                  # to_db refuses a mean the generator cannot play
        for name in ("start_mm", "step_mm", "fine_step_mm", "floor_mm", "trial_seconds"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v < 1000:
                raise ValueError("%s: expected a length/time > 0, got %r" % (name, v))
        for name in ("fine_after_reversals", "stop_after_reversals", "down_after",
                     "threshold_from_reversal"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= 100:
                raise ValueError("%s: expected an int 1 .. 100, got %r" % (name, v))


@dataclass
class Staircase:
    config: Config = field(default_factory=Config)
    length_mm: float = 0.0
    run: int = 0                    # correct answers in a row since the last step
    direction: int = 0              # -1 going down (harder), +1 up, 0 not yet moved
    reversals: list[float] = field(default_factory=list)   # lengths at each reversal
    track: list[dict] = field(default_factory=list)        # every answer

    def __post_init__(self) -> None:
        if not self.length_mm:
            self.length_mm = self.config.start_mm

    @property
    def done(self) -> bool:
        return len(self.reversals) >= self.config.stop_after_reversals

    @property
    def step_mm(self) -> float:
        c = self.config
        return c.fine_step_mm if len(self.reversals) >= c.fine_after_reversals else c.step_mm

    def texel_samples(self) -> int:
        """The current texel length in display samples (5.3 um each)."""
        return max(1, int(round(self.length_mm / DX_MM)))

    def answer(self, correct: bool) -> dict:
        """Record one trial's answer at the current length; returns the entry
        (length, correct, the move, reversal or not)."""
        if self.done:
            raise ValueError("the staircase is finished: nothing to answer")
        if not isinstance(correct, bool):
            raise ValueError("correct: expected True or False, got %r" % (correct,))
        c = self.config
        entry = {"trial": len(self.track), "length_mm": self.length_mm, "correct": correct,
                 "step_mm": self.step_mm}
        move = 0
        if correct:
            self.run += 1
            if self.run >= c.down_after:
                move = -1
                self.run = 0
        else:
            move = 1
            self.run = 0
        entry["move"] = move
        entry["reversal"] = False
        if move:
            if self.direction and move != self.direction:
                self.reversals.append(self.length_mm)
                entry["reversal"] = True
            self.direction = move
            if not self.done:
                step = self.step_mm
                self.length_mm = max(c.floor_mm, round(self.length_mm + move * step, 6))
        self.track.append(entry)
        return entry

    def threshold_mm(self) -> float | None:
        """Mean length at the reversals from Config.threshold_from_reversal on
        (None before there are any)."""
        use = self.reversals[self.config.threshold_from_reversal - 1:]
        return sum(use) / len(use) if use else None
