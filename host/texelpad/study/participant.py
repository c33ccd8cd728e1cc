"""A simulated participant for the protocols' tests and benchmarks: it
answers from a distance between textures plus noise.

The model (documented so a figure made with it can be read): a texture is a
point of texelpad.study.space's unit square (u: pitch, v: irregularity; a
search candidate's further dimensions are ignored). The participant holds a
target point. How far a texture feels from the target (`feel`):

- "felt" (the default): the distance on the felt plane of
  texelpad.analysis.perception (felt pitch and noisiness, dB; the model
  calibrated on the trained rater's matches, docs/encoder.md) between the
  two textures as the lab renders them (TEXEL_SAMPLES-sample texels, the
  study's half screen), divided by PITCH_DB_PER_U so the units are the
  square's (0.025 = 1 dB). Textures the finger cannot tell apart (two tiny
  irregularities, two pitches far above the skin's band) are near;
- "plane": the Euclidean distance in the unit square - an idealised oracle
  for testing the protocols' geometry, not a model of touch.

Gaussian noise of SD `noise` (the square's units) is added. Comparisons pick
the smaller perceived distance, or "unsure" when the two differ by less than
`unsure_below` (default: one difference threshold, perception.JND_DB, with
"felt"; never with "plane"), as the paper's subjects could. The oddity task
is a psychometric function of texel length: P(correct) = 1/3 + 2/3 / (1 +
exp(-(length - threshold) / slope)) - chance (1/3) far below the threshold,
certain far above. In the free exploration it sets the sliders on its target
(plus the noise) with confidence 4. In the quantization test (and the
similarity matrix) it rates the similarity of the reference and the
rendering the trial plays (the match, quantized) from their felt distance d
(dB): the top of the scale minus d / perception.JND_DB (one step per
difference threshold), plus noise of SD noise*40, rounded and clipped to the
scale - the model's expected similarity, not a finding ("plane": the
reference's spectral position, texelpad.study.references, against the match:
5 - d/4 - q/2).
"""
from __future__ import annotations

import functools
import math
import random
from dataclasses import dataclass, field

from .space import PITCH_DB_PER_U, Point, texel_params

FEELS = ("felt", "plane")
TEXEL_SAMPLES = 50              # the lab's 0.265 mm texels (the quantization test: its config's)
LENGTH_SAMPLES = 9600           # one half of the split display, as the studies show a texture


@functools.lru_cache(maxsize=8192)
def _texture_point(pitch_db: float, irregularity_db: float, quant_db: float,
                   texel_samples: int):
    """The expected felt point of a texture (perception.felt_point), cached:
    the protocols ask for the same textures again and again."""
    from ..analysis import perception
    return perception.felt_point({"pitch_db": pitch_db, "irregularity_db": irregularity_db,
                                  "quant_db": quant_db, "texel_samples": texel_samples,
                                  "gain": 1.0}, LENGTH_SAMPLES)


@functools.lru_cache(maxsize=64)
def _reference_point(name: str):
    from ..analysis import encoder, perception
    return perception.felt_point(encoder.reference_map(name, LENGTH_SAMPLES))


def felt_point(p: Point, quant_db: float = 0.0, texel_samples: int = TEXEL_SAMPLES):
    """The felt point of the texture a point of the square stands for."""
    t = texel_params(p)
    return _texture_point(t["pitch_db"], t["irregularity_db"], float(quant_db),
                          int(texel_samples))


@dataclass
class SimulatedParticipant:
    target: Point
    noise: float = 0.0
    unsure_below: float | None = None
    seed: int = 0
    threshold_mm: float = 6.0
    slope_mm: float = 1.0
    feel: str = "felt"
    # the finger (study/finger.py simulated): swipe speed, and rightward only (lifted back)
    swipe_mm_s: float = 90.0
    one_way: bool = False
    _rng: random.Random = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if self.feel not in FEELS:
            raise ValueError("feel: expected one of %s, got %r" % (", ".join(FEELS), self.feel))
        self._rng = random.Random(self.seed)
        if self.feel == "felt":
            from ..analysis.perception import JND_DB
            self._jnd = JND_DB / PITCH_DB_PER_U
            self._target_point = felt_point(self.target)

    def distance(self, p: Point) -> float:
        """How far p feels from the target, without noise (the square's units)."""
        if self.feel == "plane":
            return p.distance(self.target)
        return felt_point(p).distance(self._target_point) / PITCH_DB_PER_U

    def perceived(self, p: Point) -> float:
        d = self.distance(p)
        return d + (self._rng.gauss(0.0, self.noise) if self.noise else 0.0)

    def compare(self, a: Point, b: Point) -> str:
        """'A', 'B' or 'unsure': which of the two is closer to the target."""
        da, db = self.perceived(a), self.perceived(b)
        unsure = self.unsure_below
        if unsure is None:
            unsure = self._jnd if self.feel == "felt" else 0.0
        if abs(da - db) < unsure:
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

    def finger(self, seconds: float, rate_hz: int, display: dict, start_us: int = 0) -> list:
        """This participant's finger for `seconds` as the board's telemetry
        records it: (t_us, position or -1, amplitude) at rate_hz."""
        from .finger import simulated
        return simulated(seconds, rate_hz, display["dx_um"], display["positions"],
                         self.swipe_mm_s, self.one_way, start_us)

    def jitter(self, scale: float) -> float:
        """Noise of SD noise*scale (the square's units times scale), or 0."""
        return self._rng.gauss(0.0, self.noise * scale) if self.noise else 0.0

    def answer(self, protocol: str, state) -> object:
        """The answer to the protocol state's current question, as
        texelpad.study.protocols.apply takes it: the protocol says which of
        this participant's judgements it asks (its simulate)."""
        from . import protocols
        return protocols.get(protocol).simulate(self, state)

    def map_answer(self, state) -> object:
        """Seed 001's mapping, scripted (not a model of people: the target is
        not used): phase "match" sets the lognormal's mean to the reference's
        central frequency and its SD to the band's width 2 zeta fc (each on the
        slider's grid, clipped to it, plus noise in slider steps); phase "rate"
        rates 10 for a reference against its own match and 4 otherwise (plus
        noise), on the config's scale."""
        from . import bandpass
        from .mapping import MEAN_BASE_CPMM, MEAN_RATIO, SD_PER_STEP_CPMM, SLIDER
        if state.phase == "match":
            fc, zeta = bandpass.params_of(state.reference)
            p = math.log(fc / MEAN_BASE_CPMM) / math.log(MEAN_RATIO) + self.jitter(100.0)
            i = 2.0 * zeta * fc / SD_PER_STEP_CPMM + self.jitter(100.0)
            lo, hi = SLIDER
            return {"pitch": round(min(hi, max(lo, p))), "irregularity": round(min(hi, max(lo, i)))}
        ref, of = state.current
        lo, hi = state.config.scale
        return int(min(hi, max(lo, round((10 if ref == of else 4) + self.jitter(100.0)))))

    def rate(self, state) -> int:
        """The similarity rating of the quantization test's current trial
        (module docstring: the expected similarity, plus noise)."""
        lo, hi = state.config.scale
        ref, q = state.current
        if self.feel == "felt":
            from ..analysis.perception import JND_DB
            t = state.texture()
            if t.get("kind") == "samples":      # the rater's logged sequence (study/rater.py)
                import numpy as np
                from ..analysis import perception
                felt = perception.felt_point(np.asarray(t["u16"], dtype=float) / 65535.0)
            else:
                felt = _texture_point(float(t["pitch_db"]), float(t["irregularity_db"]),
                                      float(t["quant_db"]), int(t["texel_samples"]))
            d = felt.distance(_reference_point(ref))
            r = hi - d / JND_DB
        else:
            from .references import position
            if getattr(state, "current_source", "own") == "rater":
                from .rater import match
                m = match(state.current_match)
            else:
                m = state.config.matches[state.current_match]
            p, s = position(ref)
            r = 5.0 - math.hypot(m["pitch_db"] - p, m["irregularity_db"] - s) / 4.0 - q / 2.0
        if self.noise:
            r += self._rng.gauss(0.0, self.noise * 40)
        return int(min(hi, max(lo, round(r))))
