# The Tactile Paintbrush (seed 002, ../shared/seeds/002_*.txt; docs/brush.md):
# a texture as a "brush" - per wavenumber of a space-frequency transform, the
# Weibull distribution (shape k, scale lam) of the spectral magnitudes across
# windows - painted onto a region by drawing magnitudes per window, seeded
# phases, inverse transform and overlap-add.
#
# Geometry, adapted from the paper's (1 mm windows every 0.25 mm, wavenumbers
# 0 = mean .. 100 = 10 um, on a 5 um recording) to the display's 5.3 um sample:
#   WINDOW = 188 samples = 0.9964 mm (a multiple of 4, so HOP = WINDOW / 4
#            exactly and the periodic Hann window overlap-adds to a constant:
#            sum over the 4 overlapping windows of w = 2 at every sample)
#   HOP    = 47 samples = 0.2491 mm
#   K      = 95 wavenumbers: k cycles per window, k = 0 (the window's mean
#            friction) .. 94 (wavelength 2 samples = 10.6 um: the display's
#            Nyquist); wavelength = 0.9964 mm / k
# Magnitudes (the analysis, host/texelpad/brush/transform.py): with the
# periodic Hann window w[n] = 0.5 - 0.5 cos(2 pi n / WINDOW) and W = sum w =
# WINDOW / 2, m_0 = |sum x w| / W and m_k = 2 |sum x w e^(-2 pi i k n / WINDOW)| / W
# for k >= 1, so a sinusoid of amplitude A at wavenumber k >= 1 gives m_k = A
# and a constant c gives m_0 = c.
import math

from .plan_int import exp2_m
from .plan_int_tables import table

WINDOW = 188
HOP = 47
K = 95
FORMAT = "texelpad-brush/1"

# --- tables (tools/gen_brush_tables.py writes them; tests/brush/test_paint.py
# checks them against its formulas): literals, so every runtime has the same
# numbers (a float32 board could round a cosine the other way; it has no gamma).
# COS[j] = round(16384 cos(2 pi j / WINDOW)), Q14; COS[j + 94] = -COS[j].
COS = (
    16384, 16375, 16347, 16302, 16238, 16156, 16056, 15938, 15802, 15648, 15477, 15289, 15084,
    14862, 14623, 14368, 14097, 13810, 13508, 13190, 12858, 12512, 12151, 11777, 11390, 10990,
    10578, 10154, 9719, 9272, 8816, 8350, 7874, 7389, 6897, 6396, 5889, 5374, 4854, 4329, 3798,
    3263, 2725, 2184, 1640, 1094, 547, 0, -547, -1094, -1640, -2184, -2725, -3263, -3798, -4329,
    -4854, -5374, -5889, -6396, -6897, -7389, -7874, -8350, -8816, -9272, -9719, -10154, -10578,
    -10990, -11390, -11777, -12151, -12512, -12858, -13190, -13508, -13810, -14097, -14368,
    -14623, -14862, -15084, -15289, -15477, -15648, -15802, -15938, -16056, -16156, -16238,
    -16302, -16347, -16375, -16384, -16375, -16347, -16302, -16238, -16156, -16056, -15938,
    -15802, -15648, -15477, -15289, -15084, -14862, -14623, -14368, -14097, -13810, -13508,
    -13190, -12858, -12512, -12151, -11777, -11390, -10990, -10578, -10154, -9719, -9272, -8816,
    -8350, -7874, -7389, -6897, -6396, -5889, -5374, -4854, -4329, -3798, -3263, -2725, -2184,
    -1640, -1094, -547, 0, 547, 1094, 1640, 2184, 2725, 3263, 3798, 4329, 4854, 5374, 5889,
    6396, 6897, 7389, 7874, 8350, 8816, 9272, 9719, 10154, 10578, 10990, 11390, 11777, 12151,
    12512, 12858, 13190, 13508, 13810, 14097, 14368, 14623, 14862, 15084, 15289, 15477, 15648,
    15802, 15938, 16056, 16156, 16238, 16302, 16347, 16375)
# HANN[n] = 256 - round(256 cos(2 pi n / WINDOW)) for n < 94 and 256 + the
# same for n + 94: the periodic Hann window in Q9 (512 = 1.0), rounded in
# pairs so the four windows over any sample sum to exactly 1024 (= 2.0):
# overlap-add has no seams at all.
HANN = (
    0, 0, 1, 1, 2, 4, 5, 7, 9, 11, 14, 17, 20, 24, 28, 32, 36, 40, 45, 50, 55, 61, 66, 72, 78,
    84, 91, 97, 104, 111, 118, 126, 133, 141, 148, 156, 164, 172, 180, 188, 197, 205, 213, 222,
    230, 239, 247, 256, 265, 273, 282, 290, 299, 307, 315, 324, 332, 340, 348, 356, 364, 371,
    379, 386, 394, 401, 408, 415, 421, 428, 434, 440, 446, 451, 457, 462, 467, 472, 476, 480,
    484, 488, 492, 495, 498, 501, 503, 505, 507, 508, 510, 511, 511, 512, 512, 512, 511, 511,
    510, 508, 507, 505, 503, 501, 498, 495, 492, 488, 484, 480, 476, 472, 467, 462, 457, 451,
    446, 440, 434, 428, 421, 415, 408, 401, 394, 386, 379, 371, 364, 356, 348, 340, 332, 324,
    315, 307, 299, 290, 282, 273, 265, 256, 247, 239, 230, 222, 213, 205, 197, 188, 180, 172,
    164, 156, 148, 141, 133, 126, 118, 111, 104, 97, 91, 84, 78, 72, 66, 61, 55, 50, 45, 40, 36,
    32, 28, 24, 20, 17, 14, 11, 9, 7, 5, 4, 2, 1, 1, 0)
# The painting compensation (docs/brush.md, "Painting"): a re-analysed
# window sees a weighted sum of the neighbouring windows' draws (weights
# 0.0028 0.0625 0.2472 0.3750 0.2472 0.0625 0.0028, sum of squares S2 = 0.2707),
# so each window draws with shape COMP_K and scale lam * COMP_LAM at the
# brush's shape k (log-spaced grid of 57 points, 0.05 .. 1000; linear in log k
# between them): the analysed magnitude then has the brush's mean and
# coefficient of variation.
COMP_GRID = 57
COMP_K_LO = 0.05
COMP_K_HI = 1000.0
COMP_K = (
    0.05, 0.056431055, 0.0666306734, 0.0785148023, 0.0922975268, 0.108194279, 0.126410951,
    0.147132708, 0.170519703, 0.196720428, 0.225910157, 0.25835127, 0.294463028, 0.334889049,
    0.380559347, 0.432751828, 0.493160617, 0.563976214, 0.647978056, 0.748635813, 0.870213239,
    1.01786931, 1.19775655, 1.41712533, 1.68445182, 2.00961248, 2.40412632, 2.88148004,
    3.45754459, 4.15108838, 4.98439365, 5.98398711, 7.18150227, 8.61469775, 10.3286625,
    12.3772463, 14.8247603, 17.748003, 21.2386743, 25.4062562, 30.3814488, 36.3202707,
    43.4089532, 51.8697809, 61.9680628, 74.0204516, 88.404874, 105.572381, 126.061292,
    150.514074, 179.69749, 214.526638, 256.09365, 305.701934, 364.907048, 435.565476, 519.892841)
COMP_LAM = (
    1.0, 0.0627727459, 0.0729120598, 0.0844849391, 0.0976304136, 0.112485592, 0.129196637,
    0.147963373, 0.169131676, 0.193306303, 0.221411826, 0.254639219, 0.294275205, 0.341454811,
    0.396877162, 0.460515158, 0.531363871, 0.607304962, 0.685183162, 0.761161213, 0.831327135,
    0.892402637, 0.942319649, 0.98046523, 1.00754058, 1.02514582, 1.03528454, 1.0399521,
    1.04088193, 1.03944265, 1.03663875, 1.03316427, 1.02947297, 1.02584456, 1.02243883,
    1.01933644, 1.01656778, 1.01413279, 1.01201401, 1.01018507, 1.00861587, 1.00727581,
    1.00613561, 1.00516825, 1.00434941, 1.00365756, 1.00307386, 1.00258201, 1.00216796,
    1.00181967, 1.0015269, 1.00128093, 1.00107437, 1.00090097, 1.00075546, 1.00063337,
    1.00053097)
# LOG2[i] = round(log2(1 + i/256) 2^24), i = 0 .. 256 (the Weibull draws'
# logarithms in Q24 octaves: magnitudes(); linear between entries, with the
# 12-bit weight: within 4.1e-6 octave); LOG2_LN2 = round(log2(ln 2) 2^24).
LOG2 = (
    0, 94364, 188362, 281996, 375270, 468185, 560745, 652952, 744810, 836320, 927485, 1018309,
    1108793, 1198939, 1288752, 1378232, 1467383, 1556207, 1644705, 1732882, 1820738, 1908277,
    1995500, 2082410, 2169009, 2255299, 2341283, 2426963, 2512340, 2597417, 2682196, 2766679,
    2850868, 2934766, 3018374, 3101694, 3184728, 3267478, 3349946, 3432134, 3514044, 3595678,
    3677038, 3758124, 3838941, 3919488, 3999768, 4079782, 4159533, 4239023, 4318251, 4397222,
    4475935, 4554394, 4632599, 4710552, 4788255, 4865709, 4942916, 5019878, 5096595, 5173071,
    5249305, 5325300, 5401057, 5476578, 5551864, 5626916, 5701737, 5776327, 5850688, 5924821,
    5998727, 6072409, 6145867, 6219103, 6292118, 6364913, 6437490, 6509850, 6581994, 6653924,
    6725641, 6797146, 6868440, 6939525, 7010402, 7081072, 7151536, 7221795, 7291852, 7361706,
    7431359, 7500812, 7570066, 7639123, 7707984, 7776649, 7845119, 7913397, 7981483, 8049377,
    8117082, 8184598, 8251926, 8319067, 8386022, 8452793, 8519380, 8585785, 8652008, 8718050,
    8783912, 8849596, 8915102, 8980431, 9045584, 9110562, 9175366, 9239998, 9304457, 9368745,
    9432863, 9496811, 9560591, 9624203, 9687648, 9750928, 9814042, 9876993, 9939780, 10002404,
    10064867, 10127170, 10189312, 10251295, 10313120, 10374787, 10436298, 10497652, 10558852,
    10619897, 10680789, 10741528, 10802114, 10862550, 10922835, 10982970, 11042956, 11102794,
    11162484, 11222028, 11281425, 11340677, 11399784, 11458748, 11517568, 11576245, 11634780,
    11693175, 11751428, 11809542, 11867517, 11925353, 11983051, 12040612, 12098037, 12155325,
    12212479, 12269497, 12326382, 12383133, 12439752, 12496238, 12552593, 12608817, 12664911,
    12720875, 12776710, 12832416, 12887994, 12943445, 12998770, 13053968, 13109041, 13163988,
    13218811, 13273511, 13328087, 13382540, 13436871, 13491080, 13545168, 13599135, 13652983,
    13706711, 13760320, 13813810, 13867183, 13920438, 13973576, 14026597, 14079503, 14132294,
    14184969, 14237530, 14289978, 14342312, 14394532, 14446641, 14498638, 14550523, 14602297,
    14653961, 14705514, 14756958, 14808293, 14859519, 14910637, 14961648, 15012551, 15063347,
    15114037, 15164621, 15215099, 15265473, 15315742, 15365906, 15415967, 15465925, 15515779,
    15565531, 15615181, 15664730, 15714177, 15763523, 15812769, 15861915, 15910962, 15959909,
    16008758, 16057508, 16106160, 16154714, 16203172, 16251532, 16299796, 16347964, 16396036,
    16444013, 16491896, 16539683, 16587377, 16634976, 16682482, 16729896, 16777216)
LOG2_LN2 = -8871228
# --- end of tables

# --- a brush on the board -------------------------------------------------------------
# The brush a scene region carries (the host's document adds its geometry,
# name and source; host/texelpad/brush/document.py):
#   {"k": [K shapes], "lam": [K scales], "range": [a0, a1]}
# k, lam: Weibull shape and scale of the magnitude at each wavenumber, in the
# recording's friction units; range: the friction a0 plays as amplitude 0 and
# a1 as amplitude 1 (a friction recording maps high friction to low amplitude:
# a0 > a1 then; a map already in amplitude units has [0, 1], the default).
K_MIN = 0.05            # shape: below this the draws span > 10^26: no texture
K_MAX = 1000.0          # shape: 1000 is a constant magnitude to 0.1 %
LAM_MAX = 1000.0        # scale, in friction units (a range of 1e-3 .. 1e3 is allowed)
RANGE_MAX = 1e6
MAG_CLIP = 16384        # a magnitude's amplitude, Q13: clipped at 2.0 (twice full scale)
MEAN_CLIP = 32768       # the mean's amplitude, Q13: clipped to [-4, 4]
Q13 = 8192


def _num(path, v, lo, hi):
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError("%s: expected a number, got %r" % (path, v))
    v = float(v)
    if not (v == v) or v in (float("inf"), float("-inf")):
        raise ValueError("%s: %r is not finite" % (path, v))
    if not lo <= v <= hi:
        raise ValueError("%s: %r is outside %r .. %r" % (path, v, lo, hi))
    return v


def validate(brush, path="brush"):
    """The brush checked (a new dict: k, lam, range as floats); ValueError
    naming the key path of the first problem. Geometry keys, when present,
    must be this display's (window, hop, wavenumbers)."""
    if not isinstance(brush, dict):
        raise ValueError("%s: expected an object with k, lam (and range)" % path)
    for key in brush:
        if key not in ("k", "lam", "range", "window", "hop", "wavenumbers", "format", "name",
                       "source", "dx_um", "seed"):
            raise ValueError("%s: unknown key %r" % (path, key))
    for key, want in (("window", WINDOW), ("hop", HOP), ("wavenumbers", K)):
        if key in brush and brush[key] != want:
            raise ValueError("%s.%s: this display paints with %s = %d, got %r"
                             % (path, key, key, want, brush[key]))
    out = {}
    for key, lo, hi in (("k", K_MIN, K_MAX), ("lam", 0.0, LAM_MAX)):
        v = brush.get(key)
        if not isinstance(v, (list, tuple)):
            raise ValueError("%s.%s: expected a list of %d numbers" % (path, key, K))
        if len(v) != K:
            raise ValueError("%s.%s: expected %d numbers (wavenumbers 0 .. %d), got %d"
                             % (path, key, K, K - 1, len(v)))
        out[key] = [_num("%s.%s[%d]" % (path, key, i), x, lo, hi) for i, x in enumerate(v)]
    r = brush.get("range", [0.0, 1.0])
    if not isinstance(r, (list, tuple)) or len(r) != 2:
        raise ValueError("%s.range: expected [a0, a1]" % path)
    r = [_num("%s.range[%d]" % (path, i), x, -RANGE_MAX, RANGE_MAX) for i, x in enumerate(r)]
    if r[0] == r[1]:
        raise ValueError("%s.range: a0 and a1 must differ, got %r" % (path, r))
    out["range"] = r
    return out


def region_texture(path, tex):
    """A scene's brush region checked (texel.runtime.scene calls it for
    kind "brush"; seed 002): the brush by key path (path.brush.lam[3]: ...)
    and the seed it is painted with. The canonical texture."""
    if "brush" not in tex:
        raise ValueError("%s: missing required key 'brush' ({k, lam, range}: docs/brush.md)"
                         % path)
    b = validate(tex["brush"], path + ".brush")
    seed = tex.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= 0xFFFFFFFF:
        raise ValueError("%s.seed: expected an int in [0, 4294967295], got %r"
                         % (path, seed if isinstance(seed, (int, float, str)) else type(seed)))
    return {"kind": "brush", "brush": b, "seed": seed}


def windows(n):
    """How many windows paint n samples: they start at (j - 3) * HOP so that
    every sample of the region lies under four (overlap-add is whole there)."""
    return (n + HOP - 1) // HOP + 3


def phases(rng, ph):
    """The start phase of each wavenumber k = 1 .. K-1 (a COS index 0 ..
    WINDOW-1: (high 16 bits of one draw * WINDOW) >> 16), drawn once per
    painting. Window j plays wavenumber k from ph[k] + j k HOP (advance()):
    each wavenumber is one continuous wave along the region whose amplitude
    the windows' magnitudes set - windows join without seams, and a window's
    re-analysis sees its own magnitude (docs/brush.md: the round trip)."""
    ph[0] = 0
    for k in range(1, K):
        hi, lo = rng.next_hi_lo()
        ph[k] = (hi * WINDOW) >> 16
    # Nyquist (k = 94): cos(pi n + phi) sampled is cos(phi) (-1)^n, so only a
    # sign: phase 0 or pi (the draw's top bit); magnitudes() halves its
    # magnitude, since the analysis reads A (-1)^n as 2A (transform.py)
    ph[K - 1] = (WINDOW // 2) if ph[K - 1] >= WINDOW // 2 else 0


def advance(ph):
    """The phases one window (HOP samples) further along: + k HOP mod WINDOW."""
    for k in range(1, K):
        j = ph[k] + k * HOP
        ph[k] = j % WINDOW


def compensated(brush):
    """Per wavenumber the integer constants of its draws (floats only here,
    once per painting: 95 values):
      invk[k]  round(4096 / k') - the compensated shape's inverse in Q12
               (COMP_K interpolated linearly in log k), at least 1
      ll[k]    round(log2(lam' * |scale|) * 2^24) - the compensated scale in
               Q13 amplitude, as Q24 octaves (LL_NONE: scale 0)
    and (sign of the range, the mean's offset -a0 * scale in Q13)."""
    lo = math.log(COMP_K_LO)
    step = (math.log(COMP_K_HI) - lo) / (COMP_GRID - 1)
    a0, a1 = brush["range"]
    scale = Q13 / (a1 - a0)
    amp = abs(scale)
    invk = array_i(K)
    ll = array_i(K)
    lam_fix = leakage(brush["lam"])
    for k in range(K):
        x = (math.log(brush["k"][k]) - lo) / step
        i = int(x)
        if i > COMP_GRID - 2:
            i = COMP_GRID - 2
        if i < 0:
            i = 0
        t = x - i
        t = 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)
        kp = COMP_K[i] + t * (COMP_K[i + 1] - COMP_K[i])
        q = int(4096.0 / kp + 0.5)
        invk[k] = 1 if q < 1 else (INVK_MAX if q > INVK_MAX else q)
        lam = brush["lam"][k] * lam_fix[k] * \
            (COMP_LAM[i] + t * (COMP_LAM[i + 1] - COMP_LAM[i])) * amp
        if lam * 4.0 < 1.0 / 65536.0:       # below 2^-18 of a Q13 unit: never a unit
            ll[k] = LL_NONE
        else:
            lam = lam if lam < LAM_AMP_MAX else LAM_AMP_MAX
            ll[k] = int(math.log(lam) / math.log(2.0) * 16777216.0 + 0.5) if lam >= 1.0 \
                else -int(-math.log(lam) / math.log(2.0) * 16777216.0 + 0.5)
    off = -a0 * scale
    off = int(off + 0.5) if off >= 0 else -int(-off + 0.5)
    off = MEAN_CLIP * 4 if off > MEAN_CLIP * 4 else (-MEAN_CLIP * 4 if off < -MEAN_CLIP * 4
                                                       else off)
    return invk, ll, (1 if scale > 0 else -1), off


def leakage(lams):
    """Per wavenumber the factor on lam that undoes the Hann analysis' leak:
    a re-analysed window reads at k the wave at k plus 1/4 of the power of
    its neighbours k - 1 and k + 1 (the periodic Hann window is the kernel
    [-1/4, 1/2, -1/4] across bins; the phases are independent), so the
    painted powers A >= 0 solve A_k + (A_{k-1} + A_{k+1}) / 4 = lam_k^2 over
    k = 1 .. K-1 as nearly as non-negative powers can: projected
    Gauss-Seidel, LEAK_SWEEPS sweeps (the system is diagonally dominant: each
    sweep shrinks the error at least twofold; a lone line keeps its power,
    its neighbours stay 0). The factor is sqrt(A_k) / lam_k (1 where lam_k =
    0, and for the mean, k = 0, which the analysis takes out first). Floats,
    once per painting. It matches mean powers, not shapes - a neighbour's
    leak adds its own randomness (docs/brush.md: the round trip)."""
    n = K - 1
    p = [lams[i + 1] * lams[i + 1] for i in range(n)]
    a = p[:]
    for _ in range(LEAK_SWEEPS):
        for i in range(n):
            v = p[i] - 0.25 * ((a[i - 1] if i > 0 else 0.0) + (a[i + 1] if i < n - 1 else 0.0))
            a[i] = v if v > 0.0 else 0.0
    out = [1.0] * K
    for i in range(n):
        lam = lams[i + 1]
        if lam > 0.0:
            out[i + 1] = math.sqrt(a[i]) / lam
    return out


LEAK_SWEEPS = 16


def array_i(n):
    from array import array
    return array("i", bytes(4 * n))


INVK_MAX = 81920            # 1/k' <= 20 (k' >= 0.05): Q12
LAM_AMP_MAX = 131072.0      # lam' at most 16 x full scale (Q13): draws beyond clip anyway
LL_NONE = -(1 << 29)        # log2 of a zero scale: every draw rounds to 0


def log2_q24(v):
    """round-ish(log2(v) * 2^24) for 1 <= v < 2^30: the top bit's position,
    then LOG2 between the 256 points of [1, 2) (12-bit weight): within 4.1e-6
    octave (measured over every v < 5,000 and 20,000 random ones: 68 Q24
    units; tests/brush/test_paint.py). Small ints only."""
    n = 0
    w = v
    if w >= 65536:
        w >>= 16
        n += 16
    if w >= 256:
        w >>= 8
        n += 8
    if w >= 16:
        w >>= 4
        n += 4
    if w >= 4:
        w >>= 2
        n += 2
    if w >= 2:
        n += 1
    m = v << (29 - n)                       # [2^29, 2^30)
    i = (m >> 21) & 0xFF
    t = LOG2
    lo = t[i]
    return (n << 24) + lo + (((t[i + 1] - lo) * ((m >> 9) & 0xFFF)) >> 12)


def weibull_q(hi, lo, invk, ll, tab):
    """A magnitude of lam' (-ln u)^(1/k') as a Q24 octave z = log2(the Q13
    value), from the 32-bit draw (hi, lo) - all in small ints:
      u    = (x3 + 0.5) / 2^29, x3 = the draw's top 29 bits
      a    = log2(1/u) in Q24 = 30 * 2^24 - log2(2 x3 + 1)          (> 0)
      L    = log2(-ln u) = log2(a) - 24 + log2(ln 2)                (Q24)
      y    = L / k' = L * invk (Q12), in 12-bit limbs of L in Q20
      z    = ll + y
    Returns z, or None for a magnitude that rounds to 0 (y below -2^25 / 16
    octaves... far below a unit)."""
    if ll == LL_NONE:
        return None
    x3 = (hi << 13) | (lo >> 3)
    a = 503316480 - log2_q24(2 * x3 + 1)    # 30 * 2^24
    if a < 1:
        a = 1
    L = (log2_q24(a) - 402653184 + LOG2_LN2) >> 4      # 24 * 2^24; Q20
    hp = (L >> 12) * invk
    if hp < -33554432:                      # y < -32 octaves: 0
        return None
    if hp > 33554432:
        hp = 33554432
    return ll + (hp << 4) + (((L & 0xFFF) * invk) >> 8)


def round_exp2(z, emax, tab):
    """round(2^(z / 2^24)) for a Q24 z, saturated at 2^emax (emax <= 16)."""
    e = z >> 24
    if e >= emax:
        return 1 << emax
    if e < -2:
        return 0
    return (exp2_m(z & 0xFFFFFF, tab) + (1 << (27 - e))) >> (28 - e)


def magnitudes(rng, mag, comp, tab):
    """One window's magnitudes in Q13 amplitude, one draw per wavenumber
    k = 0 .. K-1 in order: Weibull by its inverse CDF with the compensated
    shape and scale (compensated()), in integers (weibull_q, round_exp2:
    the same on every runtime once comp is); the mean (k = 0) through the
    range's sign and offset; clipped (MEAN_CLIP, MAG_CLIP)."""
    invk, ll, sign, off = comp
    for k in range(K):
        hi, lo = rng.next_hi_lo()
        z = weibull_q(hi, lo, invk[k], ll[k], tab)
        if k == 0:
            v = 0 if z is None else round_exp2(z, 16, tab)
            v = sign * v + off
            mag[0] = MEAN_CLIP if v > MEAN_CLIP else (-MEAN_CLIP if v < -MEAN_CLIP else v)
        else:
            mag[k] = 0 if z is None else round_exp2(z, 14, tab)     # 2^14 = MAG_CLIP
    mag[K - 1] = (mag[K - 1] + 1) >> 1          # Nyquist: phases() says why


def frame_py(mag, ph, frame):
    """frame[n] = mag[0] + sum_k (mag[k] * COS[(ph[k] + k n) mod WINDOW]) >> 14,
    n = 0 .. WINDOW-1: the window's signal in Q13 amplitude. Every term is
    below 2^14 and the sum below 2^21 (small ints everywhere)."""
    cos = COS
    m0 = mag[0]
    for n in range(WINDOW):
        frame[n] = m0
    for k in range(1, K):
        m = mag[k]
        if not m:
            continue
        j = ph[k]
        for n in range(WINDOW):
            frame[n] += (m * cos[j]) >> 14
            j += k
            if j >= WINDOW:
                j -= WINDOW


_V = None                   # the viper loops and their tables (_viper())
FBIAS = 1 << 21             # brush_viper.py: frame values held + FBIAS
RBIAS = 1 << 23             # ... the ring of partial sums + RBIAS
MBIAS = 1 << 16             # ... the mean magnitude + MBIAS


def _viper():
    """(module brush_viper, cosp array, hann array, log2 array) or None where
    the port has no native emitter."""
    global _V
    if _V is None:
        from ..compat import native
        if native("texel.gen.brush_viper", "frame") is None:
            _V = False
        else:
            from array import array
            import texel.gen.brush_viper as mod
            _V = (mod, array("i", [c + 16384 for c in COS]), array("i", HANN),
                  array("i", LOG2))
    return _V or None


def frame_viper():
    """The viper frame as frame(mag, ph, out) with frame_py's integers (for
    tests: biases mag[0] in and the output out), or None without viper."""
    v = _viper()
    if v is None:
        return None
    mod, cosp = v[0], v[1]

    def frame(mag, ph, out):
        m0 = mag[0]
        mag[0] = m0 + MBIAS
        mod.frame(mag, ph, out, cosp)
        mag[0] = m0
        for i in range(WINDOW):
            out[i] -= FBIAS
    return frame


def frame_numpy():
    """frame_py's integers with numpy (the host: CPython), or None."""
    from ..compat import numpy_mod as np
    if np is None:
        return None
    cos = np.array(COS, dtype=np.int64)
    kk = np.arange(1, K, dtype=np.int64)[:, None]
    nn = np.arange(WINDOW, dtype=np.int64)[None, :]
    step = (kk * nn) % WINDOW

    def frame(mag, ph, out):
        m = np.frombuffer(mag, dtype=np.int32).astype(np.int64)
        p = np.frombuffer(ph, dtype=np.int32).astype(np.int64)
        idx = (p[1:, None] + step) % WINDOW
        f = m[0] + ((m[1:, None] * cos[idx]) >> 14).sum(axis=0)
        np.frombuffer(out, dtype=np.int32)[:] = f
    return frame


def best_frame():
    """The fastest Python-path frame: numpy (CPython), else frame_py (where
    viper exists, paint() runs the whole window in viper instead)."""
    return frame_numpy() or frame_py


def prepare():
    """The painter's tables made now (plan_int's 6 KB table, the viper
    loops' arrays): kept once made; scene.build calls this before it takes
    a region's chunks, while the heap still has blocks that size."""
    table()
    _viper()


def paint(brush, seed, n, out=None, frame=None, viper=None):
    """The region's map: n samples of uint16 amplitude (0..65535) painted
    from a validated brush and a seed, into out (an array('H') of n, upload
    Chunks, or a new array). Windows overlap-add with the Q9 Hann window
    (HANN: the four windows over a sample sum to 1024 exactly), the Q13 sum
    halved, clipped to [0, 1] and scaled to uint16. Memory beyond out:
    WINDOW-long work arrays (the ring of partial sums), whatever n is.

    viper: None (the default) runs every per-window loop in viper where the
    port has it (brush_viper.py), else the Python loops with `frame`
    (best_frame() by default: numpy or frame_py); False forces the Python
    loops. All paths give the same integers."""
    from array import array
    from .rng import Rng
    if out is None:
        out = array("H", bytes(2 * n))
    v = _viper() if viper is None or viper else None
    if viper and v is None:
        raise ValueError("viper: this port has no native emitter")
    rng = Rng(seed)
    mag = array_i(K)
    ph = array_i(K)
    phases(rng, ph)
    comp = compensated(brush)
    tab = table()
    start = -3 * HOP
    if v is not None:
        return _paint_viper(v, rng, comp, tab, mag, ph, n, out)
    if frame is None:
        frame = best_frame()
    buf = array_i(WINDOW)
    ring = array_i(WINDOW)       # partial sums, indexed by position mod WINDOW
    hann = HANN
    for _ in range(windows(n)):
        magnitudes(rng, mag, comp, tab)
        frame(mag, ph, buf)
        advance(ph)
        for i in range(WINDOW):
            ring[(start + i) % WINDOW] += (buf[i] * hann[i]) >> 9
        # the first HOP samples of this window are whole now: emit them
        for i in range(HOP):
            p = start + i
            r = p % WINDOW
            if 0 <= p < n:
                val = ring[r] >> 1
                out[p] = 0 if val <= 0 else (65535 if val >= Q13 else (val * 65535 + 4096) >> 13)
            ring[r] = 0
        start += HOP
    return out


def _paint_viper(v, rng, comp, tab, mag, ph, n, out):
    """paint()'s loop with every per-window step in viper."""
    from array import array
    mod, cosp, hann, log2t = v
    invk, ll, sign, off = comp
    llo = array_i(K)
    for k in range(K):
        llo[k] = ll[k] + (1 << 29)
    st = array("H", (rng.a_hi, rng.a_lo, rng.b_hi, rng.b_lo, rng.c_hi, rng.c_lo,
                     rng.d_hi, rng.d_lo))
    buf = array_i(WINDOW)
    ring = array_i(WINDOW)
    for i in range(WINDOW):
        ring[i] = RBIAS
    tmp = array("H", bytes(2 * HOP))
    chunked = not isinstance(out, array)
    start = -3 * HOP
    for _ in range(windows(n)):
        mod.magnitudes(st, invk, llo, mag, tab, log2t, sign, off)
        mod.frame(mag, ph, buf, cosp)
        advance(ph)
        r0 = start % WINDOW
        mod.ola(buf, hann, ring, r0)
        mod.emit(ring, r0, tmp)
        # the whole samples [start, start + HOP) into the region's part of it
        a = 0 if start >= 0 else -start
        b = HOP if start + HOP <= n else n - start
        if a < b:
            if chunked:
                for i in range(a, b):
                    out[start + i] = tmp[i]
            else:
                out[start + a:start + b] = tmp[a:b]
        start += HOP
    return out
