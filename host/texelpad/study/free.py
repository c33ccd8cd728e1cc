"""Free exploration (seed 000, "Free exploration"; ../shared/SPEC.md §5), as a
state machine: nine trials, one per reference texture, in an order drawn from
the session's seed. In each trial the reference plays on the left half of the
display and the texel rendering of two sliders - central pitch and
irregularity - on the right; every slider change re-draws the rendering (a
fresh texture seed per change, drawn from the session's seed, so a session
replays exactly) and is pushed to the board. When satisfied the participant
rates their confidence 1..5 and submits: that is the trial's answer.

The sliders are the lab's app's (free_exploration_and_quantization_test_app,
NU-Haptics-Lab/SinglePitchTexel): pitch linear in log10 P over [-1, 2]
(-10 .. 20 dB), starting at 0.5 (5 dB); irregularity LINEAR IN SIGMA over
0 .. 1 decade, starting at 0.5 decade (-3.010 dB). Choices recorded in Config
(and so in every session file's header):
- `irregularity_slider`: "sigma" (the app's, the default) or "db" (linear in
  dB over `irregularity_db`, the design before the app was read);
- the pitch slider's top, 20 dB, is above the display's Nyquist pitch
  (19.747 dB, texel.gen.params.PITCH_DB_MAX): a setting above it plays at
  Nyquist; the session records both the slider's value and the texture played;
- sigma = 0 (the app's slider end) plays the generator's least irregularity,
  0.001 decade (-30 dB, texel.gen.params.IRREG_DB_MIN): the page sends
  10*log10(max(sigma, 0.001)) dB;
- texel length 50 samples (0.265 mm), the app's `texelLength` (and the
  rater's renderings', study/rater.py); the paper's text says 0.25 mm (47);
- values are kept to 0.001 dB, the format-2 grid (texel.gen.grid), so the
  texture is the same on every board;
- `confidence_input`: "slider" (the app's ConfidenceSlider: continuous over
  1..5, starting at 3, kept to 0.01) or "buttons" (whole numbers).

Answers: {"pitch_db": x, "irregularity_db": y, "confidence": 1..5}. Pure logic.
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from typing import Any

from texel.gen.params import FORMAT_NEW, IRREG_DB_MAX, IRREG_DB_MIN, PITCH_DB_MAX
from texel.gen.reference import STUDY_NAMES as NINE     # the nine, in the golden data's order


SIGMA_START = round(10.0 * math.log10(0.5), 3)      # the app's 0.5 decade: -3.010 dB


@dataclass(frozen=True)
class Config:
    references: tuple[str, ...] = NINE
    pitch_db: tuple[float, float] = (-10.0, 20.0)
    irregularity_db: tuple[float, float] = (IRREG_DB_MIN, 0.0)   # with "sigma": from sigma
    irregularity_slider: str = "sigma"
    sigma: tuple[float, float] = (0.0, 1.0)     # decades, the "sigma" slider's ends
    start: tuple[float, float] = (5.0, SIGMA_START)
    texel_samples: int = 50
    confidence: tuple[int, int] = (1, 5)
    # the app's ConfidenceSlider: continuous over 1..5 from 3 (kept to 0.01); "buttons":
    # whole numbers (the design before)
    confidence_input: str = "slider"

    def __post_init__(self) -> None:
        check_references(self.references)
        if self.confidence_input not in ("slider", "buttons"):
            raise ValueError("confidence_input: expected 'slider' (continuous, the app's) or "
                             "'buttons', got %r" % (self.confidence_input,))
        if self.irregularity_slider not in ("sigma", "db"):
            raise ValueError("irregularity_slider: expected 'sigma' (linear in sigma, the lab's "
                             "app) or 'db', got %r" % (self.irregularity_slider,))
        lo, hi = self.sigma
        if not 0.0 <= lo < hi <= 10.0 ** (IRREG_DB_MAX / 10.0):
            raise ValueError("sigma: expected [low, high] decades within 0 .. %.3g, got %r"
                             % (10.0 ** (IRREG_DB_MAX / 10.0), self.sigma))
        if self.irregularity_slider == "sigma":     # the dB range the sigma slider spans
            derived = (IRREG_DB_MIN, round(10.0 * math.log10(hi), 3))
            if tuple(self.irregularity_db) != derived:
                raise ValueError("irregularity_db: with the sigma slider it is %r (from sigma "
                                 "%r), got %r" % (derived, self.sigma, self.irregularity_db))
        for name in ("pitch_db", "irregularity_db"):
            lo, hi = getattr(self, name)
            if not lo < hi:
                raise ValueError("%s: expected [low, high], got %r" % (name, getattr(self, name)))
        if not (self.pitch_db[0] <= self.start[0] <= self.pitch_db[1]
                and self.irregularity_db[0] <= self.start[1] <= self.irregularity_db[1]):
            raise ValueError("start: %r is outside the sliders' ranges" % (self.start,))

    def sliders(self) -> dict[str, Any]:
        """What the participant's page needs to draw the sliders (no texture
        parameter: the slider's ends and how it maps)."""
        out: dict[str, Any] = {"pitch_db": list(self.pitch_db),
                               "irregularity_db": list(self.irregularity_db),
                               "irregularity_scale": self.irregularity_slider}
        if self.irregularity_slider == "sigma":
            out["sigma"] = list(self.sigma)
        return out


def check_references(refs: tuple[str, ...]) -> None:
    if not refs or any(r not in NINE for r in refs) or len(set(refs)) != len(refs):
        raise ValueError("references: expected distinct names among %s, got %r"
                         % (", ".join(NINE), refs))


def rating_input(scale: tuple[int, int], how: str) -> dict[str, Any]:
    """A rating question's answers (rating_of checks them): the lab's app's
    continuous slider at the middle of the scale to start ("slider"), or one
    button per whole number ("buttons")."""
    lo, hi = scale
    if how == "slider":
        return {"answers": None, "slider": {"range": [lo, hi], "start": (lo + hi) / 2,
                                            "step": 0.01}}
    return {"answers": list(range(lo, hi + 1))}


def rating_of(what: str, x: Any, scale: tuple[int, int], how: str) -> float | int:
    """A rating checked on its scale: a whole number ("buttons") or any number
    kept to 0.01 ("slider"); never a bool (JSON true is not 1)."""
    lo, hi = scale
    if how == "buttons":
        if isinstance(x, bool) or not isinstance(x, int) or not lo <= x <= hi:
            raise ValueError("%s: expected %d .. %d, got %r" % (what, lo, hi, x))
        return x
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) \
            or not lo <= x <= hi:
        raise ValueError("%s: expected a number %d .. %d, got %r" % (what, lo, hi, x))
    return round(float(x), 2)


def _number(what: str, x: Any, lo: float, hi: float) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
        raise ValueError("%s: expected a number, got %r" % (what, x))
    if not lo <= x <= hi:
        raise ValueError("%s: %r is outside the slider's %g .. %g dB" % (what, x, lo, hi))
    return round(float(x), 3)


@dataclass
class Free:
    seed: int
    config: Config = field(default_factory=Config)
    trial: int = 0
    matches: list[dict[str, Any]] = field(default_factory=list)   # one per finished trial

    def __post_init__(self) -> None:
        order = list(self.config.references)
        random.Random(self.seed).shuffle(order)
        self.order = order

    @property
    def done(self) -> bool:
        return self.trial >= len(self.order)

    @property
    def reference(self) -> str:
        return self.order[self.trial]

    def reference_texture(self) -> dict[str, Any]:
        """The current trial's reference as the display plays it."""
        return {"kind": "reference", "name": self.reference}

    def check(self, pitch_db: Any, irregularity_db: Any) -> tuple[float, float]:
        """Slider values, checked and on the 0.001 dB grid."""
        c = self.config
        return (_number("pitch_db", pitch_db, *c.pitch_db),
                _number("irregularity_db", irregularity_db, *c.irregularity_db))

    def texture(self, pitch_db: float, irregularity_db: float, move: int,
                v: int = FORMAT_NEW) -> dict[str, Any]:
        """The texel rendering of the sliders at the trial's move-th change: a
        parameter set of format v (the config's texture_format: 2 unless it
        says 1) with its own seed (each change re-draws)."""
        rng = random.Random((self.seed * 1000003 + self.trial) * 1000003 + move)
        return {"pitch_db": min(PITCH_DB_MAX, pitch_db), "irregularity_db": irregularity_db,
                "texel_samples": self.config.texel_samples,
                "seed": rng.randrange(1 << 32), "v": v}

    def checked_answer(self, a: Any) -> dict[str, Any]:
        """The answer checked and on the grid (ValueError says why)."""
        if self.done:
            raise ValueError("the free exploration is finished: nothing to answer")
        if not isinstance(a, dict) or set(a) != {"pitch_db", "irregularity_db", "confidence"}:
            raise ValueError("answer: expected {pitch_db, irregularity_db, confidence}, got %r"
                             % (a,))
        p, s = self.check(a["pitch_db"], a["irregularity_db"])
        c = rating_of("confidence", a["confidence"], self.config.confidence,
                      self.config.confidence_input)
        return {"pitch_db": p, "irregularity_db": s, "confidence": c}

    def answer(self, a: Any) -> dict[str, Any]:
        a = self.checked_answer(a)
        entry = dict(a, trial=self.trial, reference=self.reference)
        self.matches.append(entry)
        self.trial += 1
        return entry

    def match_of(self, reference: str) -> dict[str, float] | None:
        """The participant's match of a reference (for the quantization test)."""
        for m in self.matches:
            if m["reference"] == reference:
                return {"pitch_db": m["pitch_db"], "irregularity_db": m["irregularity_db"]}
        return None
