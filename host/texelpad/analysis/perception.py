"""What a sliding fingertip feels of a friction map's spatial spectrum: a small
perceptual model, and the distance the texel encoder minimises
(texelpad.analysis.encoder; docs/encoder.md has the model with its sources
and the tables it produces).

A map is friction reduction in [0, 1], one value per display sample of
DX_MM = 5.3 um (texel.gen.params). What the model keeps of it:

1. Its power spectrum: the one-sided periodogram of the mean-removed,
   Hann-windowed map (the window of texelpad.analysis.spectrum and
   texelpad.study.references), scaled so the bins sum to the map's
   variance. A full-scale sine (0 .. 1) has variance 1/8: FULL_SCALE_POWER.
2. The swipe: a finger sliding at SPEED_MM_S feels f c/mm as a vibration of
   f * SPEED_MM_S Hz (the lab's strip plays f*v Hz too: docs/lab.md).
3. Frequency resolution: power is pooled on a log-frequency axis in a
   Gaussian band of SD RESOLUTION_DECADES (0.1 decade = 1 dB in the papers'
   10*log10 convention): the "band power" at log10 f is the power within
   about +-1 dB of it.
4. Detection: a band is felt when its power exceeds the detection threshold
   at its vibration frequency (threshold_db: the U-shaped curve, flat below
   KNEE_HZ, falling 12 dB/octave to BEST_HZ, rising above), given that a
   full-scale sine at BEST_HZ lies FULL_SCALE_SL_DB above threshold. The
   felt power of a band is E * (1 - exp(-E / E_threshold)): 63 % of it at
   threshold, all of it 10 dB above, ~E^2/E_threshold far below (a weighting
   by sensitivity, never exactly zero, so every texel stays identifiable).
5. Masking, within a channel only (the Pacinian channel above KNEE_HZ, the
   non-Pacinian below; channels do not mask each other): a band more than
   MASKING_DB below the channel's total felt power is masked, by the same
   soft rule.
6. What is compared: the felt power as a distribution over log10 f (the
   texel generator's parameters describe exactly such a distribution,
   log10 f ~ Normal(log10 P, sigma): ../shared/SPEC.md section 1), and its
   level. distance() is the 2-Wasserstein ("earth mover's") distance between
   two such distributions in dB: two pure pitches a and b dB apart are
   |a - b| dB apart; two texels at one pitch, irregularities s1 and s2
   (as spreads 10*sigma in dB) are ~|s1 - s2| dB apart. The level is
   reported beside it (Pattern.level_db), not mixed in: the encoder matches
   it with the gain.

Every constant is explained where it is defined and in docs/encoder.md.
The expected spectrum of a texel rendering is computed analytically
(expected_periodogram; checked against rendered maps in
tests/analysis/test_encoder.py), so a candidate texture costs a few FFTs
and no rendering.

Pure analysis: numpy, scipy.special and texel; never the link, the command
line or a web framework (docs/architecture.md).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Union

import numpy as np
import scipy.fft as sfft
from scipy.special import ndtr

import texel
from texel.gen.params import DX_MM, NYQUIST_CPMM

# --- the model's constants (docs/encoder.md, "The perceptual model") ----------------
# A fingertip exploring a surface for texture slides at about 86 mm/s:
# Smith, Gosselin & Houde (2002), "Deployment of fingertip forces in tactile
# exploration", Exp Brain Res 147:209-218 (mean speed 8.6 cm/s, normal force
# 0.49 N). 1 c/mm is then felt at 86 Hz; the display's Nyquist 94.34 c/mm at
# 8.1 kHz.
SPEED_MM_S = 86.0
# The vibrotactile detection threshold (glabrous skin, large contactor) is flat
# up to ~40 Hz (the non-Pacinian channel), then falls ~12 dB/octave to its
# minimum near 250 Hz (the Pacinian channel): Verrillo (1963), "Effect of
# contactor area on the vibrotactile threshold", J Acoust Soc Am 35:1962-1966;
# Bolanowski, Gescheider, Verrillo & Checkosky (1988), "Four channels mediate
# the mechanical aspects of touch", J Acoust Soc Am 84:1680-1694.
KNEE_HZ = 40.0
BEST_HZ = 250.0
SLOPE_BELOW_DB_PER_OCTAVE = 12.0
# Above 250 Hz the Pacinian threshold rises again; we take the same 12 dB/octave
# (an approximation read off the same curves, which end near 700-1000 Hz: it
# puts the limit of touch for a strong stimulus in the low kHz).
SLOPE_ABOVE_DB_PER_OCTAVE = 12.0
# How far above threshold a full-scale friction modulation (map 0 <-> 1) is at
# 250 Hz. NOT MEASURED for this display: an assumption (docs/encoder.md shows
# the nine references at 30 and 50 dB too). Rationale: the TPaD swings the
# friction coefficient by a large fraction of itself at ~0.5 N normal force,
# lateral forces of ~0.1 N, orders above vibrotactile thresholds (tenths of a
# micrometre near 250 Hz).
FULL_SCALE_SL_DB = 40.0
# Frequency resolution: vibrotactile frequency discrimination has a Weber
# fraction of roughly 0.2-0.3 (LaMotte & Mountcastle (1975), "Capacities of
# humans and monkeys to discriminate vibratory stimuli of different frequency
# and amplitude", J Neurophysiol 38:539-559), i.e. ~0.1 decade; and seed 000
# found 1 dB (0.1 decade) quantization of texel pitches imperceptible (its
# quantization test). One band = a Gaussian of SD 0.1 decade on log10 f.
RESOLUTION_DECADES = 0.1
# Masking acts within a channel, not across (Hamer, Verrillo & Zwislocki
# (1983), "Vibrotactile masking of Pacinian and non-Pacinian channels",
# J Acoust Soc Am 73:1293-1303), and a masker's effect grows with its level
# (Gescheider, Verrillo & Van Doren (1982), "Prediction of vibrotactile
# masking functions", J Acoust Soc Am 72:1421-1426). How far below the
# channel's felt power a band is lost is OUR CHOICE, not a published figure:
# 10 dB. It decides how much the weak harmonics of the square and sawtooth
# waves count (docs/encoder.md: the references without masking).
MASKING_DB = 10.0
# The fingertip's mechanics. The display modulates friction, i.e. the lateral
# FORCE on the finger; what the receptors feel is the skin's displacement. The
# fingertip's tangential impedance is elastic below ~100 Hz (displacement per
# unit force flat) and viscous above (force ~ velocity: displacement per unit
# force falls as 1/f, -6 dB/octave): Wiertlewski & Hayward (2012), "Mechanical
# behavior of the fingertip in the range of frequencies and displacements
# relevant to touch", J Biomech 45:1869-1874. The force threshold is the
# displacement threshold (threshold_db) plus 20*log10(f / 100 Hz) above 100 Hz.
FINGERTIP_CORNER_HZ = 100.0
# Fusion of discrete lines (seed 000, quantization discussion, citing Friesen
# et al.: several discrete frequency components are felt as ONE dominant
# frequency at their weighted mean; noisiness is felt from wide-band content).
# A periodogram bin is a line when it stands LINE_DB above the geometric mean
# of the bins within +-RESOLUTION_DECADES of it: a bin of a noise periodogram
# (exponential, geometric mean 0.56 of its mean) does so with probability
# exp(-31.6 * 0.56) = 2e-8, a spectral line of a sine or a harmonic by tens of
# dB. OUR CHOICE of 15 dB (docs/encoder.md: the calibration's table).
LINE_DB = 15.0
LINE_MIN_BINS = 8               # the floor's window: at least +-8 bins (low frequencies)
# A "difference threshold" on the felt plane (felt pitch, noisiness), in dB:
# the frequency resolution's 0.1 decade (Weber fraction ~0.25, LaMotte &
# Mountcastle 1975, above). Two textures whose felt points are nearer than
# this feel the same (texelpad.study.participant answers "unsure" below it).
JND_DB = 10.0 * RESOLUTION_DECADES

FULL_SCALE_POWER = 0.125        # variance of a full-scale sine map (y+1)/2, y = sin: 1/8
SEGMENT_MAX = 32768             # longest FFT; longer maps: averaged 50 %-overlapped segments
MIN_SAMPLES = 16                # shorter maps have no spectrum to speak of (0.085 mm)

# The log-frequency axis: log10(f / 1 c/mm) from 0.002 c/mm (below any map's
# first bin of interest: a full screen's is 0.0098 c/mm) to 4 bands above
# Nyquist (the bands' tails), 0.01 decade (0.1 dB) steps.
GRID_STEP = 0.01
GRID = np.round(np.arange(-2.7, math.log10(NYQUIST_CPMM) + 0.45, GRID_STEP), 10)
_KERNEL_HALF = 4                # kernel support: +-4 SD

MapLike = Union[np.ndarray, "list[float]"]


@dataclass(frozen=True)
class Model:
    """The model's adjustable constants (defaults: the module's constants,
    with the sources given there). None for masking_db: no masking."""
    speed_mm_s: float = SPEED_MM_S
    full_scale_sl_db: float = FULL_SCALE_SL_DB
    masking_db: float | None = MASKING_DB
    resolution_decades: float = RESOLUTION_DECADES
    slope_above_db_per_octave: float = SLOPE_ABOVE_DB_PER_OCTAVE
    fingertip_corner_hz: float | None = FINGERTIP_CORNER_HZ
    line_db: float | None = LINE_DB

    def __post_init__(self) -> None:
        for name, lo, hi in (("speed_mm_s", 1.0, 10000.0), ("full_scale_sl_db", -20.0, 200.0),
                             ("resolution_decades", 0.02, 1.0),
                             ("slope_above_db_per_octave", 0.0, 60.0)):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and lo <= v <= hi):
                raise ValueError("%s: expected a number in [%g, %g], got %r" % (name, lo, hi, v))
        for name, lo, hi in (("masking_db", 0.0, 200.0), ("fingertip_corner_hz", 1.0, 10000.0),
                             ("line_db", 3.0, 100.0)):
            m = getattr(self, name)
            if m is not None and not (isinstance(m, (int, float)) and math.isfinite(m)
                                      and lo <= m <= hi):
                raise ValueError("%s: expected None or a number in [%g, %g], got %r"
                                 % (name, lo, hi, m))

    def as_dict(self) -> dict[str, Any]:
        return {"speed_mm_s": self.speed_mm_s, "full_scale_sl_db": self.full_scale_sl_db,
                "masking_db": self.masking_db, "resolution_decades": self.resolution_decades,
                "knee_hz": KNEE_HZ, "best_hz": BEST_HZ,
                "slope_below_db_per_octave": SLOPE_BELOW_DB_PER_OCTAVE,
                "slope_above_db_per_octave": self.slope_above_db_per_octave,
                "fingertip_corner_hz": self.fingertip_corner_hz, "line_db": self.line_db,
                "jnd_db": JND_DB}


DEFAULT_MODEL = Model()


def threshold_db(hz: Any, slope_above: float = SLOPE_ABOVE_DB_PER_OCTAVE) -> np.ndarray:
    """Displacement detection threshold at vibration frequency hz (Hz), in dB
    re its minimum at BEST_HZ: flat below KNEE_HZ (31.7 dB), -12 dB/octave
    from KNEE_HZ to BEST_HZ, +slope_above dB/octave above (the constants'
    sources above)."""
    nu = np.maximum(np.asarray(hz, dtype=float), 1e-12)
    below = SLOPE_BELOW_DB_PER_OCTAVE * np.log2(BEST_HZ / np.clip(nu, KNEE_HZ, BEST_HZ))
    above = slope_above * np.log2(np.maximum(nu, BEST_HZ) / BEST_HZ)
    return below + above


def force_threshold_db(hz: Any, model: "Model | None" = None) -> np.ndarray:
    """Detection threshold for the display's lateral-force modulation at hz,
    in dB re its value at BEST_HZ (its minimum): threshold_db plus the
    fingertip's viscous fall of displacement per unit force above
    FINGERTIP_CORNER_HZ (none when model.fingertip_corner_hz is None)."""
    model = DEFAULT_MODEL if model is None else model
    nu = np.maximum(np.asarray(hz, dtype=float), 1e-12)
    t = threshold_db(nu, model.slope_above_db_per_octave)
    fc = model.fingertip_corner_hz
    if fc is not None:
        t = t + 20.0 * (np.log10(np.maximum(nu, fc) / fc) - math.log10(max(BEST_HZ, fc) / fc))
    return t


def skin_band_hz(model: "Model | None" = None) -> tuple[float, float]:
    """The skin's band for this display: the vibration frequencies (Hz) at
    which a full-scale modulation is above the force threshold, i.e.
    force_threshold_db < model.full_scale_sl_db (0.1 Hz .. 100 kHz searched
    on a 1 % grid; the lower end is 0.1 Hz when the threshold is flat
    below KNEE_HZ within reach)."""
    model = DEFAULT_MODEL if model is None else model
    hz = np.logspace(-1, 5, 1201)
    ok = np.nonzero(force_threshold_db(hz, model) < model.full_scale_sl_db)[0]
    if ok.size == 0:
        return (math.nan, math.nan)
    return float(hz[ok[0]]), float(hz[ok[-1]])


# --- spectra -----------------------------------------------------------------------

def as_map(fmap: Any, name: str = "map") -> np.ndarray:
    """fmap as a finite 1-D float64 array of at least MIN_SAMPLES, or ValueError."""
    try:
        x = np.asarray(fmap, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError("%s: expected a sequence of numbers, got %s"
                         % (name, type(fmap).__name__)) from None
    if x.ndim != 1:
        raise ValueError("%s: expected a 1-D map, got shape %s" % (name, x.shape))
    if x.size < MIN_SAMPLES:
        raise ValueError("%s: %d samples is too short to have a spectrum (at least %d, "
                         "%.3g mm)" % (name, x.size, MIN_SAMPLES, MIN_SAMPLES * DX_MM))
    bad = ~np.isfinite(x)
    if bad.any():
        raise ValueError("%s: %d sample%s not finite (the first at %d)"
                         % (name, bad.sum(), " is" if bad.sum() == 1 else "s are",
                            int(np.argmax(bad))))
    return x


@functools.lru_cache(maxsize=16)
def _window(n: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Hann window of n, its autocorrelation W(m) = sum_j w_j w_{j+m}
    (m = 0..n-1) and the periodogram's scale 2 / (n * sum w^2)."""
    w = np.hanning(n) if n > 1 else np.ones(1)
    size = 1 << int(math.ceil(math.log2(2 * n)))
    F = np.fft.rfft(w, size)
    acf = np.fft.irfft(np.abs(F) ** 2, size)[:n]
    return w, acf, 2.0 / (n * float(np.sum(w * w)))


def segment_length(n: int) -> int:
    """The FFT length used for an n-sample map: the whole map up to
    SEGMENT_MAX (a full screen is 19,200), else SEGMENT_MAX."""
    return min(n, SEGMENT_MAX)


def frequencies(n: int) -> np.ndarray:
    """Bin frequencies (c/mm) of the periodogram of an n-sample map."""
    return np.fft.rfftfreq(segment_length(n), d=DX_MM)


def periodogram(fmap: MapLike) -> tuple[np.ndarray, np.ndarray]:
    """(f in c/mm, power per bin): the one-sided periodogram of the mean-removed,
    Hann-windowed map, scaled so the bins sum to about the map's variance (a
    sine of amplitude a: a^2/2). Maps longer than SEGMENT_MAX: the mean of
    50 %-overlapped segments (Welch)."""
    x = as_map(fmap)
    n = x.size
    m = segment_length(n)
    w, _, scale = _window(m)
    starts = [0] if m == n else list(range(0, n - m + 1, m // 2))
    if starts[-1] + m < n:
        starts.append(n - m)
    acc = np.zeros(m // 2 + 1)
    for s in starts:
        seg = x[s:s + m]
        acc += np.abs(sfft.rfft((seg - seg.mean()) * w)) ** 2
    return frequencies(n), acc * (scale / len(starts))


def _char_fn(pitch_db: float, irregularity_db: float, quant_db: float,
             band_limit: float | None, cmax: int) -> np.ndarray:
    """C(c) = E[exp(2 pi i c DX f)], c = 0..cmax, for one texel pitch f
    (log10 f ~ Normal(pitch_db/10, sigma); quantized to a quant_db/10 decade
    grid; clamped at band_limit c/mm). The phase advance of c samples of one
    texel; aliasing (f above Nyquist) is in it: only f*DX mod 1 matters."""
    mu = pitch_db / 10.0
    s = 10.0 ** (irregularity_db / 10.0)
    q = quant_db / 10.0
    c = np.arange(cmax + 1, dtype=np.float64)
    if q > 0.0:
        j = np.arange(math.floor((mu - 9 * s) / q), math.ceil((mu + 9 * s) / q) + 1)
        if j.size <= 20000:
            # the plan rounds log10 f to q*round(log10 f / q) (half away from zero:
            # ties have probability 0), so grid value j takes the mass of its cell
            pm = np.diff(ndtr((np.concatenate(([j[0] - 0.5], j + 0.5)) * q - mu) / s))
            f = 10.0 ** (j * q)
            if band_limit is not None:
                f = np.minimum(f, band_limit)
            keep = pm > 1e-15
            # einsum, not @: BLAS threads on matrices this small only contend for the cores
            return np.einsum("ij,j->i", np.exp(2j * np.pi * DX_MM * np.outer(c, f[keep])),
                             pm[keep].astype(complex))
        # a grid far finer than the spread is no quantization (QUANT_DB_MIN = 0.001 dB)
    # Continuous: bins of z (log10 f = mu + s z) of width DZ over [-8, 8]; each
    # bin's mass at its mean frequency, spread uniformly over its width in f
    # (the sinc): exact to second order for narrow bins, and -> 0 for a bin whose
    # frequencies span many cycles of phase over c samples (fully aliased).
    dz = 0.05
    z = np.arange(-8.0, 8.0 + dz / 2, dz)
    if band_limit is not None:
        zc = (math.log10(band_limit) - mu) / s
        z = np.unique(np.concatenate((z[z < zc], [min(max(zc, z[0]), z[-1])])))
    cdf = ndtr(z)
    pm = np.diff(cdf)
    a = s * math.log(10.0)               # f = 10^mu * exp(a z)
    # partial expectation: E[f; z0<Z<z1] = 10^mu e^{a^2/2} (Phi(z1-a) - Phi(z0-a))
    fe = 10.0 ** mu * math.exp(min(a * a / 2.0, 700.0)) * np.diff(ndtr(z - a))
    with np.errstate(invalid="ignore", divide="ignore"):
        fmean = np.where(pm > 1e-300, fe / np.maximum(pm, 1e-300), 10.0 ** (mu + s * z[:-1]))
    lo = 10.0 ** (mu + s * z[:-1])
    hi = 10.0 ** (mu + s * z[1:])
    fmean = np.clip(fmean, lo, hi)
    width = hi - lo
    masses = [pm]
    freqs = [fmean]
    widths = [width]
    if band_limit is not None:
        above = 1.0 - cdf[-1]            # every pitch above the limit is played at it
        masses.append(np.array([above]))
        freqs.append(np.array([band_limit]))
        widths.append(np.array([0.0]))
    pm = np.concatenate(masses)
    fm = np.concatenate(freqs)
    wd = np.concatenate(widths)
    keep = pm > 1e-15
    pm, fm, wd = pm[keep] / pm[keep].sum(), fm[keep], wd[keep]
    # exp(2 pi i c DX f) for c = 0, 1, ... as running products of one step per bin
    # (complex exp is the cost here); blocks of 1024 lags bound the memory
    step = np.exp(2j * np.pi * DX_MM * fm)
    pmc = pm.astype(complex)
    wide = DX_MM * wd * cmax > 1e-3          # bins whose sinc differs from 1 by > 2e-6
    out = np.empty(c.size, dtype=complex)
    start = np.ones(fm.size, dtype=complex)
    for s0 in range(0, c.size, 1024):
        rows = min(1024, c.size - s0)
        M = np.empty((rows, fm.size), dtype=complex)
        M[0] = start
        M[1:] = step
        M = np.cumprod(M, axis=0)           # (in place, out=M, is 40x slower)
        start = M[-1] * step
        if wide.any():
            M[:, wide] *= np.sinc(np.outer(c[s0:s0 + rows], DX_MM * wd[wide]))
        out[s0:s0 + rows] = np.einsum("ij,j->i", M, pmc)
    return out


def _acf(C: np.ndarray, L: int, n: int) -> np.ndarray:
    """E[y_j y_{j+m}], m = 0..n-1, of the generator's raw output y = sin(theta)
    (docs/generator.md: theta advances 2 pi f_i DX per sample of texel i, f_i
    independent per texel, start phase uniform), averaged over the position
    of j within its texel. Over a lag that starts r samples before the end of
    j's texel (r uniform in 0..L-1): C(m) if m <= r, else
    C(r) * C(L)^q * C(s) with m - r = qL + s."""
    m = np.arange(n)
    a = C[:min(L, n)]
    if L < n:
        q = np.arange(n // L + 2)
        h = ((C[L] ** q)[:, None] * C[None, :L]).reshape(-1)[:n + 1]
    else:
        h = C[:n + 1] if C.size > n else np.concatenate((C, np.zeros(n + 1 - C.size)))
    h = h.copy()
    h[0] = 0.0
    size = sfft.next_fast_len(n + a.size + 1)
    conv = sfft.ifft(sfft.fft(a, size) * sfft.fft(h, size))[:n]
    first = np.where(m < L, (L - m) * C[np.minimum(m, C.size - 1)], 0.0)
    return 0.5 * np.real(first + conv) / L


def _distribution(params: Mapping[str, Any]) -> dict[str, Any]:
    """params validated as the distribution they draw from: a set without "v"
    is checked as format 1's continuous parameters. Both formats draw the same
    distribution (format 2 on a 0.001 dB grid), and a model evaluated between
    grid points (the encoder's search, a plot's axis) must not be refused
    for a half-way value that only format 2's grid cares about."""
    p = dict(params)
    p.setdefault("v", 1)
    return texel.validate(p)


def expected_periodogram(params: Mapping[str, Any], n: int | None = None
                         ) -> tuple[np.ndarray, np.ndarray]:
    """(f in c/mm, expected power per bin) of periodogram() of a texel
    rendering of `params` (a texture dict; texel.validate checks it) n samples
    long (default its length_samples), over the texture's random draws.

    Analytic: the rendering's autocorrelation from the characteristic function
    of one texel's phase advance (_char_fn, _acf), times the Hann window's
    autocorrelation, Fourier transformed. Treats the texture as stationary
    (texel borders at a random offset) and leaves out the mean's removal,
    which only matters in the first bins. Format 2 ("v": 2) draws the same
    distribution on a 0.001 dB grid: the same expectation."""
    p = dict(params)
    if n is not None:
        p["length_samples"] = int(n)
    p = _distribution(p)
    m = segment_length(p["length_samples"])
    if m < MIN_SAMPLES:
        raise ValueError("length_samples: %d samples is too short to have a spectrum (at "
                         "least %d)" % (m, MIN_SAMPLES))
    L = p["texel_samples"]
    C = _char_fn(p["pitch_db"], p["irregularity_db"], p["quant_db"], p["band_limit_cpmm"],
                 min(L, m))
    R = _acf(C, L, m) * (p["gain"] ** 2 / 4.0)
    _, W, scale = _window(m)
    a = R * W
    S = 2.0 * np.real(sfft.rfft(a, m)) - a[0]
    return frequencies(m), np.maximum(S, 0.0) * scale


def expected_aliased_fraction(params: Mapping[str, Any]) -> float:
    """Expected fraction of a texture's texels drawn above Nyquist (they
    alias; texel.gen.plan counts the drawn ones: Plan.fraction_above_nyquist)."""
    p = _distribution(params)
    cap = p["band_limit_cpmm"]
    if cap is not None and cap <= NYQUIST_CPMM:
        return 0.0
    mu = p["pitch_db"] / 10.0
    s = 10.0 ** (p["irregularity_db"] / 10.0)
    q = p["quant_db"] / 10.0
    nyq = math.log10(NYQUIST_CPMM)
    if q > 0.0:
        # values q*j above log10 Nyquist: j >= floor(nyq/q) + 1; their cells start at j - 1/2
        j = math.floor(nyq / q) + 1
        return float(1.0 - ndtr(((j - 0.5) * q - mu) / s))
    return float(1.0 - ndtr((nyq - mu) / s))


# --- the felt pattern ---------------------------------------------------------------

@functools.lru_cache(maxsize=16)
def _binning(m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each periodogram bin (but DC) of an m-sample segment split between its
    two neighbouring GRID points by linear interpolation on log10 f:
    (bin indices, lower grid index, weight of the upper point)."""
    f = np.fft.rfftfreq(m, d=DX_MM)
    k = np.nonzero(f > 0)[0]
    pos = (np.log10(f[k]) - GRID[0]) / GRID_STEP
    i0 = np.clip(np.floor(pos).astype(np.int64), 0, GRID.size - 2)
    frac = np.clip(pos - i0, 0.0, 1.0)
    return k, i0, frac


@functools.lru_cache(maxsize=8)
def _kernel(resolution: float) -> np.ndarray:
    """The band: exp(-x^2/2) over +-4 SD on GRID steps (peak 1: a pure tone's
    band power at its own frequency is its power)."""
    h = int(round(_KERNEL_HALF * resolution / GRID_STEP))
    x = np.arange(-h, h + 1) * GRID_STEP / resolution
    return np.exp(-0.5 * x * x)


@functools.lru_cache(maxsize=32)
def _thresholds(model: "Model") -> tuple[np.ndarray, np.ndarray]:
    """(band power at threshold on GRID, Pacinian-channel mask on GRID)."""
    hz = model.speed_mm_s * 10.0 ** GRID
    thr = force_threshold_db(hz, model)
    return (FULL_SCALE_POWER * 10.0 ** ((thr - model.full_scale_sl_db) / 10.0),
            hz >= KNEE_HZ)


def line_bins(P: np.ndarray, m: int, line_db: float | None = LINE_DB) -> np.ndarray:
    """Which bins of a periodogram P (power per bin, m-sample segments) are
    spectral lines: at least line_db above the geometric mean of the bins
    within +-RESOLUTION_DECADES of them (at least LINE_MIN_BINS each side).
    A boolean array like P; none when line_db is None. O(n): cumulative sums."""
    P = np.asarray(P, dtype=np.float64)
    if line_db is None or P.size < 3:
        return np.zeros(P.shape, dtype=bool)
    k = np.arange(P.size)
    top = float(P.max())
    logp = np.log(np.maximum(P, top * 1e-30 if top > 0 else 1e-300))
    c = np.concatenate(([0.0], np.cumsum(logp)))
    r = 10.0 ** RESOLUTION_DECADES
    lo = np.clip(np.minimum(np.floor(k / r), k - LINE_MIN_BINS), 1, P.size - 1).astype(np.int64)
    hi = np.clip(np.maximum(np.ceil(k * r), k + LINE_MIN_BINS), 1, P.size - 1).astype(np.int64)
    floor = (c[hi + 1] - c[lo]) / (hi + 1 - lo)
    line = logp > floor + line_db * math.log(10.0) / 10.0
    line[0] = False                                 # DC: the mean, removed
    return line & (P > 0)


@dataclass(frozen=True)
class Pattern:
    """A map as felt: on GRID (log10 f, c/mm), the band power (map units^2:
    power within one resolution band) and the felt power after detection and
    masking. level_db: total felt power in dB re a full-scale sine
    (FULL_SCALE_POWER); sl_db: the strongest band's level above its threshold."""
    band_power: np.ndarray
    felt: np.ndarray
    level_db: float
    sl_db: float
    model: Model = field(default=DEFAULT_MODEL)
    # the part of `felt` that comes from spectral lines (line_bins), on GRID
    line_felt: np.ndarray | None = None

    @property
    def log10_f(self) -> np.ndarray:
        return GRID

    @property
    def empty(self) -> bool:
        return not float(self.felt.sum()) > 0.0

    def distribution(self) -> np.ndarray:
        """The felt power over GRID, summing to 1 (ValueError when nothing is felt)."""
        t = float(self.felt.sum())
        if not t > 0.0 or not math.isfinite(t):
            raise ValueError("nothing to feel: the map has no spectral content")
        return self.felt / t

    def moments_db(self) -> tuple[float, float]:
        """(mean, SD) of the felt distribution over 10*log10 f: dB re 1 c/mm and dB."""
        d = self.distribution()
        mu = float(np.sum(d * GRID))
        sd = math.sqrt(max(float(np.sum(d * (GRID - mu) ** 2)), 0.0))
        return 10.0 * mu, 10.0 * sd

    def felt_point(self) -> "FeltPoint":
        """Where this texture sits on the felt plane (FeltPoint): the felt
        pitch (weighted mean of log f over the felt power) and the felt
        noisiness (the felt power's SD over log f, its lines fused into one
        pitch at their weighted mean, felt with the resolution's width).
        ValueError when nothing is felt."""
        d = self.distribution()
        mu = float(np.sum(d * GRID))
        res = self.model.resolution_decades
        tonal = 0.0
        if self.line_felt is not None:
            tonal = min(1.0, max(0.0, float(self.line_felt.sum()) / float(self.felt.sum())))
        cont = d * (1.0 - tonal) if self.line_felt is None else \
            (self.felt - self.line_felt) / float(self.felt.sum())
        cont = np.maximum(cont, 0.0)
        var = 0.0
        wc = float(cont.sum())
        if wc > 0.0:
            mc = float(np.sum(cont * GRID)) / wc
            var += wc * (float(np.sum(cont * (GRID - mc) ** 2)) / wc + (mc - mu) ** 2)
        if tonal > 0.0:
            assert self.line_felt is not None
            dl = self.line_felt / float(self.felt.sum())
            ml = float(np.sum(dl * GRID)) / max(float(dl.sum()), 1e-300)
            var += tonal * (res * res + (ml - mu) ** 2)
        sd = math.sqrt(max(var, 1e-12))
        return FeltPoint(10.0 * mu, 10.0 * math.log10(sd), self.level_db, tonal)


@dataclass(frozen=True)
class FeltPoint:
    """A texture on the felt plane: pitch_db (10*log10 of the felt weighted
    mean frequency, c/mm), noisiness_db (10*log10 of the fused felt spread,
    decades: -10 dB is a single pitch felt at the resolution's 0.1 decade),
    level_db (felt power re a full-scale sine) and tonal (the fraction of the
    felt power in spectral lines, 0..1)."""
    pitch_db: float
    noisiness_db: float
    level_db: float
    tonal: float

    def distance(self, other: "FeltPoint") -> float:
        """How far apart two textures feel, in dB: the Euclidean distance of
        (pitch, noisiness), both in the papers' dB convention (pitch
        10*log10 c/mm, noisiness 10*log10 decades like the irregularity
        slider). How it relates to w2_db: for Gaussian felt distributions
        W2 = sqrt(dpitch^2 + (10*dsd)^2), sd in decades - the same pitch
        term, the spread counted linearly instead of as a ratio; for two
        textures of one spread both are |dpitch|. The level is not in it
        (the encoder matches it with the gain)."""
        return math.hypot(self.pitch_db - other.pitch_db,
                          self.noisiness_db - other.noisiness_db)

    def as_dict(self) -> dict[str, float | None]:
        return {"pitch_db": round(self.pitch_db, 3),
                "noisiness_db": round(self.noisiness_db, 3),
                "level_db": round(self.level_db, 3) if math.isfinite(self.level_db) else None,
                "tonal": round(self.tonal, 4)}


def pattern_of_spectrum(P: np.ndarray, m: int, model: Model = DEFAULT_MODEL) -> Pattern:
    """The felt pattern of a periodogram P (power per bin, len m//2+1) of
    m-sample segments (periodogram() or expected_periodogram())."""
    k, i0, frac = _binning(m)
    p = P[k]
    raw = np.bincount(i0, weights=p * (1.0 - frac), minlength=GRID.size) \
        + np.bincount(i0 + 1, weights=p * frac, minlength=GRID.size)
    kern = _kernel(model.resolution_decades)
    E = np.convolve(raw[:GRID.size], kern, mode="same")
    lines = line_bins(P, m, model.line_db)
    E_line = None
    if lines.any():
        pl = np.where(lines[k], p, 0.0)
        raw_l = np.bincount(i0, weights=pl * (1.0 - frac), minlength=GRID.size) \
            + np.bincount(i0 + 1, weights=pl * frac, minlength=GRID.size)
        E_line = np.convolve(raw_l[:GRID.size], kern, mode="same")
    e_thr, pac = _thresholds(model)
    ratio = E / e_thr
    felt = E * -np.expm1(-ratio)
    if model.masking_db is not None:
        # total felt power of a channel: band power -> power by the band's width
        per = GRID_STEP / (math.sqrt(2.0 * math.pi) * model.resolution_decades)
        factor = 10.0 ** (-model.masking_db / 10.0)
        out = felt.copy()
        for ch in (pac, ~pac):
            total = float(felt[ch].sum()) * per
            if total > 0.0:
                out[ch] = felt[ch] * -np.expm1(-felt[ch] / (total * factor))
        felt = out
    total = float(felt.sum()) * GRID_STEP / (math.sqrt(2.0 * math.pi) * model.resolution_decades)
    level = 10.0 * math.log10(total / FULL_SCALE_POWER) if total > 0.0 else -math.inf
    sl = 10.0 * math.log10(float(ratio.max())) if float(ratio.max()) > 0.0 else -math.inf
    line_felt = None
    if E_line is not None:
        with np.errstate(invalid="ignore", divide="ignore"):
            share = np.where(E > 0.0, np.clip(E_line / np.maximum(E, 1e-300), 0.0, 1.0), 0.0)
        line_felt = felt * share
    return Pattern(E, felt, level, sl, model, line_felt)


def map_pattern(fmap: MapLike, model: Model = DEFAULT_MODEL) -> Pattern:
    """The felt pattern of a friction map (DX_MM per sample)."""
    x = as_map(fmap)
    _, P = periodogram(x)
    return pattern_of_spectrum(P, segment_length(x.size), model)


def texel_pattern(params: Mapping[str, Any], n: int | None = None,
                  model: Model = DEFAULT_MODEL) -> Pattern:
    """The expected felt pattern of a texel texture rendered n samples long
    (default: its length_samples)."""
    _, P = expected_periodogram(params, n)
    length = n if n is not None else _distribution(params)["length_samples"]
    return pattern_of_spectrum(P, segment_length(int(length)), model)


# --- the distance -------------------------------------------------------------------

_P = (np.arange(1000) + 0.5) / 1000.0        # quantile levels for W2


def _quantiles(d: np.ndarray) -> np.ndarray:
    """Quantile function of a distribution on GRID (each point's mass spread
    uniformly over its cell), at the levels _P, in decades."""
    cdf = np.concatenate(([0.0], np.cumsum(d + 1e-15)))
    cdf /= cdf[-1]
    edges = np.concatenate((GRID - GRID_STEP / 2, [GRID[-1] + GRID_STEP / 2]))
    return np.interp(_P, cdf, edges)


def w2_db(a: Pattern, b: Pattern) -> float:
    """2-Wasserstein distance between two felt distributions, in dB
    (10 * decades): sqrt of the mean squared difference of their quantile
    functions on the 10*log10 f axis."""
    qa = _quantiles(a.distribution())
    qb = _quantiles(b.distribution())
    return 10.0 * math.sqrt(float(np.mean((qa - qb) ** 2)))


def as_pattern(x: Any, n: int | None = None, model: Model = DEFAULT_MODEL) -> Pattern:
    """A Pattern from a Pattern, a texel texture dict (expected pattern, n
    samples long: default its length_samples) or a friction map."""
    if isinstance(x, Pattern):
        return x
    if isinstance(x, Mapping):
        return texel_pattern(x, n, model)
    return map_pattern(x, model)


def distance(a: Any, b: Any, model: Model = DEFAULT_MODEL, n: int | None = None) -> float:
    """How different two textures feel, in dB (w2_db of their felt patterns).
    a, b: friction maps (arrays in [0, 1], DX_MM per sample), texel texture
    dicts (their expected pattern; n = the length to render them at, default
    the map's length when the other is a map, else length_samples) or
    Patterns. 0 = the same felt spectrum; two pure pitches d dB apart: d.
    For the lab's simulated participant and brush comparison too."""
    if n is None:
        for x in (a, b):
            if not isinstance(x, (Pattern, Mapping)):
                n = int(np.asarray(x).size)
                break
    return w2_db(as_pattern(a, n, model), as_pattern(b, n, model))


def felt_point(x: Any, n: int | None = None, model: Model = DEFAULT_MODEL) -> FeltPoint:
    """The FeltPoint of a friction map, a texel texture dict (its expected
    pattern, n samples long: default its length_samples) or a Pattern."""
    return as_pattern(x, n, model).felt_point()


def felt_distance(a: Any, b: Any, model: Model = DEFAULT_MODEL, n: int | None = None) -> float:
    """How different two textures feel, in dB on the felt plane
    (FeltPoint.distance): maps, texture dicts, Patterns or FeltPoints (n as
    in distance()). Below JND_DB they feel the same. The distance the lab's
    simulated participant, `texelpad brush compare` and the quantization
    test's expected similarity use."""
    if n is None:
        for x in (a, b):
            if not isinstance(x, (Pattern, Mapping, FeltPoint)):
                n = int(np.asarray(x).size)
                break
    pa = a if isinstance(a, FeltPoint) else felt_point(a, n, model)
    pb = b if isinstance(b, FeltPoint) else felt_point(b, n, model)
    return pa.distance(pb)
