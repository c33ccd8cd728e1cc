"""The data we have for the paper's comparison (docs/brush.md, "Fits and the paper's comparison"): seed 002
recorded ten rightward fingertip swipes on each of eleven real textures with a
tribometer; those recordings are not public. We have friction *maps* and make
noisy *swipes* of them.

Textures (TEXTURES, in this order; each a full screen of SCREEN_SAMPLES =
19,200 samples of 5.3 um = 101.76 mm, values in the display's [0, 1]):
- the matching study's nine references (../shared/SPEC.md §2; texel.reference:
  the closed forms continued past the half screen, the stored noise rows
  mirrored - device/texel/gen/reference.py says how; its first 9,600 samples
  are the rows of ../shared/golden/reference_textures.csv);
- two Single-Pitch Texel renderings (texel.render, texture format 2 - the
  integer plan, bit-identical on every runtime - seeds fixed in TEXEL_PARAMS):
  a near-periodic one (pitch 6 dB = 3.98 c/mm, irregularity -20 dB = 0.01
  decade) and an irregular fine one (15 dB = 31.6 c/mm, -5 dB = 0.32 decade).
Eleven textures, as in the paper's Table I, ten swipes each: 110 swipes.

The swipe model (SwipeModel; a fingertip swiping across the display as the
paper's tribometer recorded it, resampled to position):
1. length: `length_samples` = 9,600 samples (50.88 mm, 197 windows): the
   study's half screen; the paper kept "only the constant-velocity sections".
2. start: uniform over the positions where the whole (warped) swipe fits on
   the texture (real-valued, in samples).
3. slow warp: the finger covers 1 + e(s) map samples per recorded sample,
   e a Gaussian process - white noise smoothed by a Gaussian of SD
   `warp_corr_mm` = 10 mm, centred and scaled to SD `warp_sd` = 3 % over the
   swipe (clipped to >= -0.5: a finger never goes backwards). It stands for
   what a position recording misplaces slowly: the skin's stretch between
   the encoder's carriage (clamped to the nail in seed 002 Fig. 2) and the
   contact, changing with speed and force. Over 10 mm a 3 % warp moves
   features by ~0.3 mm, a window's worth.
4. the display: friction at position p is the map entry under it, map[floor
   p] (the refresh sets the amplitude from "the map entry at the finger's
   position", ../shared/SPEC.md §3: a zero-order hold, no interpolation).
5. gain: the whole swipe times g = exp(N(0, `gain_sd` = 0.05)) (normal force
   and skin moisture change the friction level from swipe to swipe).
6. noise: additive white Gaussian friction noise of SD `noise_sd` = 0.02
   (2 % of the display's range; force-sensor noise). In the transform that
   is a Rayleigh floor with sigma = noise_sd * sqrt(3 / (2 W)) ~ 0.0025 per
   wavenumber (W = 96: the periodic Hann's sum; transform.py), so m_k ~
   0.003 where a texture has nothing.
   The recording is not clipped (a tribometer's friction is not bounded by
   the display's range).
Not modelled: the fingertip's own mechanical filtering and the sensor's
low-pass (seed 002 filtered force at 2 kHz), the backward swipes.

Seeding: swipe j of texture i under seed s draws from
numpy.random.default_rng(SeedSequence(s, spawn_key=(i, j))) - independent
streams, and a texture's swipes do not change when textures are added after
it. The texel renderings use texel's own seeds (TEXEL_PARAMS).

Pure logic: texel, numpy, scipy (docs/architecture.md).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.ndimage import gaussian_filter1d

import texel
from texel.gen.params import DX_MM
from texel.gen.reference import STUDY_NAMES

SCREEN_SAMPLES = 19200          # the TPaD's full screen, 101.76 mm (../shared/SPEC.md §1)
# Two texel parameter sets (texel.gen.params keys): names say pitch and irregularity in dB
TEXEL_PARAMS = {
    "texel-p6-i-20": {"pitch_db": 6.0, "irregularity_db": -20.0, "seed": 2016, "v": 2},
    "texel-p15-i-5": {"pitch_db": 15.0, "irregularity_db": -5.0, "seed": 2016, "v": 2},
}
TEXTURES = tuple(STUDY_NAMES) + tuple(TEXEL_PARAMS)
SWIPES_PER_TEXTURE = 10         # seed 002 §III-B: "ten cycles of back-and-forth scanning"


@dataclass(frozen=True)
class SwipeModel:
    """The noise model of a fingertip swipe (module docstring)."""
    length_samples: int = 9600      # 50.88 mm: 197 windows
    warp_sd: float = 0.03           # SD of the local speed ratio e(s) (3 %)
    warp_corr_mm: float = 10.0      # SD of the Gaussian smoothing the warp, mm
    gain_sd: float = 0.05           # SD of ln(gain)
    noise_sd: float = 0.02          # additive Gaussian friction noise, map units

    def __post_init__(self):
        if not (isinstance(self.length_samples, int) and self.length_samples >= 2):
            raise ValueError("length_samples: expected an int >= 2, got %r"
                             % (self.length_samples,))
        for name in ("warp_sd", "warp_corr_mm", "gain_sd", "noise_sd"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError("%s: expected a finite number >= 0, got %r" % (name, v))


@dataclass
class Swipe:
    texture: str
    index: int                      # 0 .. n_per_texture - 1
    friction: np.ndarray = field(repr=False)   # length_samples, one per 5.3 um
    start_mm: float = 0.0           # where on the texture the swipe began
    gain: float = 1.0
    stretch: float = 1.0            # map samples covered / recorded samples (the warp's mean)


@functools.lru_cache(maxsize=None)
def _texture(name: str, length_samples: int) -> np.ndarray:
    if name in TEXEL_PARAMS:
        p = dict(TEXEL_PARAMS[name], length_samples=length_samples)
        m = np.asarray(texel.render(p, engine="numpy"), dtype=float)
    else:
        m = np.asarray(texel.reference(name, length_samples), dtype=float)
    m.setflags(write=False)
    return m


def texture(name: str, length_samples: int = SCREEN_SAMPLES) -> np.ndarray:
    """The map of texture `name` (one of TEXTURES, or any name texel.reference
    knows), length_samples long, read-only and cached."""
    if name not in TEXTURES and name not in texel.reference_names():
        raise ValueError("texture: unknown %r (known: %s)" % (name, ", ".join(TEXTURES)))
    return _texture(name, int(length_samples))


def textures(names=TEXTURES, length_samples: int = SCREEN_SAMPLES) -> dict[str, np.ndarray]:
    return {n: texture(n, length_samples) for n in names}


def swipe(fmap, rng: np.random.Generator, model: SwipeModel = SwipeModel()) -> Swipe:
    """One noisy swipe of the map `fmap` (5.3 um samples) under `model`,
    drawing from `rng` (the draws, in order: warp noise, start, gain,
    friction noise). texture and index are left for the caller to fill in."""
    t = np.asarray(fmap, dtype=float)
    n = model.length_samples
    if model.warp_sd > 0:
        e = gaussian_filter1d(rng.standard_normal(n), model.warp_corr_mm / DX_MM, mode="reflect")
        e -= e.mean()
        sd = float(e.std())
        e = e * (model.warp_sd / sd) if sd > 0 else e
        speed = np.maximum(1.0 + e, 0.5)
    else:
        speed = np.ones(n)
    # map position (samples) of recorded sample s, relative to the start
    adv = np.concatenate(([0.0], np.cumsum(speed[:-1])))
    extent = float(adv[-1])
    room = t.size - 1 - extent
    if room < 0:
        raise ValueError("swipe: the texture has %d samples; a warped swipe of %d samples "
                         "covers %.0f" % (t.size, n, extent + 1))
    start = float(rng.uniform(0.0, room))
    gain = float(np.exp(rng.normal(0.0, model.gain_sd))) if model.gain_sd > 0 else 1.0
    idx = np.minimum(np.floor(start + adv).astype(np.int64), t.size - 1)
    f = gain * t[idx]
    if model.noise_sd > 0:
        f = f + rng.normal(0.0, model.noise_sd, n)
    return Swipe(texture="", index=0, friction=f, start_mm=start * DX_MM, gain=gain,
                 stretch=extent / max(n - 1, 1))


def make_swipes(n_per_texture: int = SWIPES_PER_TEXTURE, seed: int = 0, names=TEXTURES,
                model: SwipeModel = SwipeModel(),
                length_samples: int = SCREEN_SAMPLES) -> list[Swipe]:
    """n_per_texture swipes of each texture in `names` (textures in order,
    swipes in order within each), seeded as the module docstring says."""
    if not (isinstance(n_per_texture, int) and n_per_texture >= 1):
        raise ValueError("n_per_texture: expected an int >= 1, got %r" % (n_per_texture,))
    out = []
    for i, name in enumerate(names):
        t = texture(name, length_samples)
        for j in range(n_per_texture):
            rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(i, j)))
            s = swipe(t, rng, model)
            s.texture, s.index = name, j
            out.append(s)
    return out
