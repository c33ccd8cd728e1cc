"""Seed 001's reference textures (second experiment, "Texel Parameter
Mapping"; Table I): "white noise filtered using a spectral band-pass with a
defined central frequency and Q-factor", zeta = 1/(2Q), central frequency
1, 4, 20 c/mm x zeta 0.05, 0.5, 5 - all nine permutations.

One generator, not two: the device already renders this family as the named
references "bp-<fc>-<zeta>" (device/texel/gen/reference.py, BANDPASS_FAMILY;
a scene's {"kind": "reference", "name": "bp-4-0.5"} plays it, seed 0). This
module is the protocol's view of it, on the host:

- the filter (our reading of "a spectral band-pass with a defined central
  frequency and Q-factor"; the paper's ref. [3] is not in ../shared/seeds):
  the second-order band-pass H(s) = 2 zeta w0 s / (s^2 + 2 zeta w0 s + w0^2),
  |H(f)| = 1 / sqrt(1 + Q^2 (f/fc - fc/f)^2), gain 1 at fc, -3 dB band
  fc/Q = 2 zeta fc wide (exactly, between the -3 dB points, in the analog
  prototype); run as a biquad by the bilinear transform pre-warped so the
  centre stays at fc: the digital |H| is the analog one at
  tan(pi f dx) / tan(pi fc dx) in place of f / fc (texel.gen.reference.
  bandpass_coefficients; tests/study/test_bandpass.py checks the identity),
  so its -3 dB band is narrower by about sin(2x)/(2x), x = pi fc dx: 0.03 %
  at 1 c/mm, 7 % at 20 c/mm (the test measures both);
- the noise: texel's own Gaussian generator (texel.gen.rng.Rng(seed).normal(),
  the same stream on every runtime), a burn-in of 7 time constants of the
  filter's slowest pole discarded (texel.gen.reference.burn_in_samples), then
  n samples on the display's grid, DX_MM = 5.3 um per sample; n = 9,600 =
  half the display (texel.gen.reference.HALF_SCREEN, 50.88 mm);
- friction levels: v = clip(0.5 + (y - mean) / (6 SD), 0, 1) over the n
  samples: +-3 SD spans 0 .. 1 (about 0.27 % of samples clip); uint16
  q = round(v * 65535);
- seeds: 0 by default (protocol Config.reference_seed), so the uploaded map
  is the device's named reference sample for sample.

    NAMES                          the nine, Table I order (fc outer, zeta inner)
    params_of(name)                -> (fc_cpmm, zeta)
    name_of(fc_cpmm, zeta)         -> name
    reference_map(fc, zeta, seed=0, n=9600)   -> numpy float64 array in [0, 1]
    reference_u16(name, seed=0, n=9600)       -> tuple of ints 0..65535
    reference_texture(name, seed=0)           -> the display's "samples" texture
    board_texture(name)            -> {"kind": "reference", "name": ...} (seed 0)

Pure logic, numpy and texel only.
"""
from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np

from texel.gen import reference as _reference
from texel.gen.params import SEED_MAX
from texel.gen.reference import BANDPASS_FAMILY, HALF_SCREEN

# Table I of seed 001: central frequency (c/mm) x zeta, in the device's order
NAMES: tuple[str, ...] = tuple(name for name, _, _ in BANDPASS_FAMILY)
FC_CPMM: tuple[float, ...] = (1.0, 4.0, 20.0)
ZETAS: tuple[float, ...] = (0.05, 0.5, 5.0)
_PARAMS = {name: (fc, zeta) for name, fc, zeta in BANDPASS_FAMILY}
SD_SPAN = _reference.SD_SPAN            # 6: +-3 SD of the filtered noise span 0 .. 1


def params_of(name: Any) -> tuple[float, float]:
    """(central frequency c/mm, zeta) of one of the nine."""
    if not isinstance(name, str) or name not in _PARAMS:
        raise ValueError("reference: expected one of %s, got %r" % (", ".join(NAMES), name))
    return _PARAMS[name]


def name_of(fc_cpmm: float, zeta: float) -> str:
    """The name of Table I's (fc, zeta) pair."""
    for name, (f, z) in _PARAMS.items():
        if f == fc_cpmm and z == zeta:
            return name
    raise ValueError("(fc_cpmm, zeta): expected fc in %s c/mm and zeta in %s, got (%r, %r)"
                     % (FC_CPMM, ZETAS, fc_cpmm, zeta))


def _check_seed(seed: Any) -> int:
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= SEED_MAX:
        raise ValueError("seed: expected an int in 0 .. %d, got %r" % (SEED_MAX, seed))
    return seed


def _check_n(n: Any) -> int:
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 2 * HALF_SCREEN:
        raise ValueError("n: expected an int in 1 .. %d samples, got %r" % (2 * HALF_SCREEN, n))
    return n


def reference_map(fc_cpmm: float, zeta: float, seed: int = 0, n: int = HALF_SCREEN
                  ) -> np.ndarray:
    """Band-pass noise as friction levels in [0, 1], n samples of DX_MM
    (float64; the device's texel.gen.reference.bandpass in binary64). fc in
    0.01 .. 94 c/mm, zeta in 0.01 .. 10 (the device's ranges: ValueError
    outside them); n up to the full display, 19,200 samples."""
    _check_seed(seed)
    _check_n(n)
    return np.asarray(_reference.bandpass(fc_cpmm, zeta, seed, n), dtype=np.float64)


@lru_cache(maxsize=32)
def reference_u16(name: str, seed: int = 0, n: int = HALF_SCREEN) -> tuple[int, ...]:
    """One of the nine as uint16 levels q = round(v * 65535): what the board
    plays (texel.gen.reference.bandpass_u16, equal to reference_map converted
    sample by sample). Kept (an immutable tuple, 32 maps at most): a trial
    plays its reference at every slider change, and one costs ~0.1 s of
    pure Python (estimate, one run on this machine)."""
    fc, zeta = params_of(name)
    _check_seed(seed)
    _check_n(n)
    return tuple(_reference.bandpass_u16(fc, zeta, seed, n))


def reference_texture(name: str, seed: int = 0) -> dict[str, Any]:
    """The display's "samples" texture of one of the nine on half the display
    (device/texel/runtime/scene.py: "tile" plays value k at position k, one
    value per 5.3 um, so the spatial frequencies are the ones designed; the
    half screen's 9,600 values fill the left half exactly)."""
    return {"kind": "samples", "fit": "tile", "u16": reference_u16(name, seed)}


def board_texture(name: str) -> dict[str, Any]:
    """The same reference rendered by the board itself (seed 0 only; on a
    binary64 board sample for sample reference_texture(name, 0), on a float32
    board its own float's realisation): nothing to upload."""
    params_of(name)
    return {"kind": "reference", "name": name}
