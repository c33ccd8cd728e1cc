# The Tactile Paintbrush (seed 002, ../shared/seeds/002_*.txt; docs/brush.md):
# a texture as a "brush" - per wavenumber of a space-frequency transform, the
# Weibull distribution (shape k, scale lam) of the spectral magnitudes across
# windows - painted onto a region as the paper describes it: per window, a
# magnitude drawn from the brush and a phase drawn at random for every
# wavenumber (the phases are not part of the texture: seed 002 discards them),
# an inverse FFT, Hann windows joined by overlap-add.
#
# Geometry, adapted from the paper's (1 mm windows every 0.25 mm, wavenumbers
# 0 = mean .. 100 = 10 um, on a 5 um recording) to the display's 5.3 um sample:
#   WINDOW = 192 samples = 1.0176 mm (3 x 2^6, so the inverse transform is a
#            radix-3 and radix-2 FFT; a multiple of 4, so HOP = WINDOW / 4
#            exactly and the periodic Hann window overlap-adds to a constant:
#            sum over the 4 overlapping windows of w = 2 at every sample)
#   HOP    = 48 samples = 0.2544 mm
#   K      = 97 wavenumbers: k cycles per window, k = 0 (the window's mean
#            friction) .. 96 (wavelength 2 samples = 10.6 um: the display's
#            Nyquist); wavelength = 1.0176 mm / k
# Magnitudes (the analysis, host/texelpad/brush/transform.py): with the
# periodic Hann window w[n] = 0.5 - 0.5 cos(2 pi n / WINDOW) and W = sum w =
# WINDOW / 2, m_0 = |sum x w| / W and m_k = 2 |sum x w e^(-2 pi i k n / WINDOW)| / W
# for k >= 1, so a sinusoid of amplitude A at wavenumber k >= 1 gives m_k = A
# and a constant c gives m_0 = c.
#
# Everything after the painting's setup (compensated(): floats, once) is in
# integers, so the map is the same on every runtime: three ways to run it -
# Python loops (any port), numpy (CPython: the host) and viper (brush_viper.py)
# - give the same integers (tests/brush/test_paint.py).
import math
from array import array      # at the top: an extensible built-in imported inside a function
#                              walks sys.path each time (1.64 ms on the emulated RP2040)

from .check import is_int, is_num, finite, fail
from .plan_int import exp2_m
from .plan_int_tables import table

WINDOW = 192
HOP = 48
K = 97
NYQ = K - 1
FORMAT = "texelpad-brush/2"
OLD_FORMATS = ("texelpad-brush/1",)

# --- tables (tools/gen_brush_tables.py writes them; tests/brush/test_paint.py
# checks them against its formulas): literals, so every runtime has the same
# numbers (a float32 board could round a cosine the other way; it has no gamma).
# PHASE[p] = round(16384 cos(2 pi p / 256)), Q14: a window's phase p (its
# draw's low byte); sin is PHASE[(p - 64) & 255].
PHASE = (
    16384, 16379, 16364, 16340, 16305, 16261, 16207, 16143, 16069, 15986, 15893, 15791, 15679,
    15557, 15426, 15286, 15137, 14978, 14811, 14635, 14449, 14256, 14053, 13842, 13623, 13395,
    13160, 12916, 12665, 12406, 12140, 11866, 11585, 11297, 11003, 10702, 10394, 10080, 9760,
    9434, 9102, 8765, 8423, 8076, 7723, 7366, 7005, 6639, 6270, 5897, 5520, 5139, 4756, 4370,
    3981, 3590, 3196, 2801, 2404, 2006, 1606, 1205, 804, 402, 0, -402, -804, -1205, -1606,
    -2006, -2404, -2801, -3196, -3590, -3981, -4370, -4756, -5139, -5520, -5897, -6270, -6639,
    -7005, -7366, -7723, -8076, -8423, -8765, -9102, -9434, -9760, -10080, -10394, -10702,
    -11003, -11297, -11585, -11866, -12140, -12406, -12665, -12916, -13160, -13395, -13623,
    -13842, -14053, -14256, -14449, -14635, -14811, -14978, -15137, -15286, -15426, -15557,
    -15679, -15791, -15893, -15986, -16069, -16143, -16207, -16261, -16305, -16340, -16364,
    -16379, -16384, -16379, -16364, -16340, -16305, -16261, -16207, -16143, -16069, -15986,
    -15893, -15791, -15679, -15557, -15426, -15286, -15137, -14978, -14811, -14635, -14449,
    -14256, -14053, -13842, -13623, -13395, -13160, -12916, -12665, -12406, -12140, -11866,
    -11585, -11297, -11003, -10702, -10394, -10080, -9760, -9434, -9102, -8765, -8423, -8076,
    -7723, -7366, -7005, -6639, -6270, -5897, -5520, -5139, -4756, -4370, -3981, -3590, -3196,
    -2801, -2404, -2006, -1606, -1205, -804, -402, 0, 402, 804, 1205, 1606, 2006, 2404, 2801,
    3196, 3590, 3981, 4370, 4756, 5139, 5520, 5897, 6270, 6639, 7005, 7366, 7723, 8076, 8423,
    8765, 9102, 9434, 9760, 10080, 10394, 10702, 11003, 11297, 11585, 11866, 12140, 12406,
    12665, 12916, 13160, 13395, 13623, 13842, 14053, 14256, 14449, 14635, 14811, 14978, 15137,
    15286, 15426, 15557, 15679, 15791, 15893, 15986, 16069, 16143, 16207, 16261, 16305, 16340,
    16364, 16379)
# TW[j] = round(4096 cos(2 pi j / 192)), Q12: the FFT's twiddles; sin is
# TW[(j + 144) % 192].
TW = (
    4096, 4094, 4087, 4076, 4061, 4041, 4017, 3989, 3956, 3920, 3879, 3833, 3784, 3731, 3674,
    3612, 3547, 3478, 3406, 3329, 3250, 3166, 3080, 2990, 2896, 2800, 2701, 2598, 2493, 2386,
    2276, 2163, 2048, 1931, 1812, 1690, 1567, 1443, 1317, 1189, 1060, 930, 799, 667, 535, 401,
    268, 134, 0, -134, -268, -401, -535, -667, -799, -930, -1060, -1189, -1317, -1443, -1567,
    -1690, -1812, -1931, -2048, -2163, -2276, -2386, -2493, -2598, -2701, -2800, -2896, -2990,
    -3080, -3166, -3250, -3329, -3406, -3478, -3547, -3612, -3674, -3731, -3784, -3833, -3879,
    -3920, -3956, -3989, -4017, -4041, -4061, -4076, -4087, -4094, -4096, -4094, -4087, -4076,
    -4061, -4041, -4017, -3989, -3956, -3920, -3879, -3833, -3784, -3731, -3674, -3612, -3547,
    -3478, -3406, -3329, -3250, -3166, -3080, -2990, -2896, -2800, -2701, -2598, -2493, -2386,
    -2276, -2163, -2048, -1931, -1812, -1690, -1567, -1443, -1317, -1189, -1060, -930, -799,
    -667, -535, -401, -268, -134, 0, 134, 268, 401, 535, 667, 799, 930, 1060, 1189, 1317, 1443,
    1567, 1690, 1812, 1931, 2048, 2163, 2276, 2386, 2493, 2598, 2701, 2800, 2896, 2990, 3080,
    3166, 3250, 3329, 3406, 3478, 3547, 3612, 3674, 3731, 3784, 3833, 3879, 3920, 3956, 3989,
    4017, 4041, 4061, 4076, 4087, 4094)
# HANN[n] = 256 - round(256 cos(2 pi n / WINDOW)) for n < 96 and 256 + the
# same for n + 96: the periodic Hann window in Q9 (512 = 1.0), rounded in
# pairs so the four windows over any sample sum to exactly 1024 (= 2.0):
# overlap-add has no seams at all.
HANN = (
    0, 0, 1, 1, 2, 3, 5, 7, 9, 11, 14, 16, 19, 23, 26, 30, 34, 39, 43, 48, 53, 58, 64, 69, 75,
    81, 87, 94, 100, 107, 114, 121, 128, 135, 143, 150, 158, 166, 174, 182, 190, 198, 206, 214,
    223, 231, 239, 248, 256, 264, 273, 281, 289, 298, 306, 314, 322, 330, 338, 346, 354, 362,
    369, 377, 384, 391, 398, 405, 412, 418, 425, 431, 437, 443, 448, 454, 459, 464, 469, 473,
    478, 482, 486, 489, 493, 496, 498, 501, 503, 505, 507, 509, 510, 511, 511, 512, 512, 512,
    511, 511, 510, 509, 507, 505, 503, 501, 498, 496, 493, 489, 486, 482, 478, 473, 469, 464,
    459, 454, 448, 443, 437, 431, 425, 418, 412, 405, 398, 391, 384, 377, 369, 362, 354, 346,
    338, 330, 322, 314, 306, 298, 289, 281, 273, 264, 256, 248, 239, 231, 223, 214, 206, 198,
    190, 182, 174, 166, 158, 150, 143, 135, 128, 121, 114, 107, 100, 94, 87, 81, 75, 69, 64, 58,
    53, 48, 43, 39, 34, 30, 26, 23, 19, 16, 14, 11, 9, 7, 5, 3, 2, 1, 1, 0)
# The painting's compensation (docs/brush.md, "Painting"; the derivation is
# in tools/gen_brush_tables.py). Waves (k >= 1): a re-analysed window reads
# LEAK_GAIN = 0.56247 of a unit wave's power painted with independent
# phases, shared over wavenumber distances 0, 1, 2, 3 as LEAK (leakage()
# deconvolves it); COMP_LK[i] = ln k', the shape to draw for the grid's
# shape k_i (log-spaced, 57 points, 0.05 .. 1000; linear in ln k between them)
# so the re-analysed magnitude fits (maximum likelihood) with shape k_i - it
# reaches 2.089 at most (k' = 1000), about a Rayleigh's: sharper brushes read
# back at that shape; COMP_LS[i] = log2(1 / S) at k' = k_i, S the fitted
# scale of a re-analysis of draws of scale 1 (a seeded Monte Carlo). The
# mean (k = 0) is a weighted sum of neighbouring windows' draws (weights
# 0.0028 0.0625 0.2472 0.3750 0.2472 0.0625 0.0028;
# S2 = 0.2707): COMP0_LK keeps its coefficient of variation, LG1 = ln Gamma(1 + 1/k)
# on the grid its mean (compensated()).
COMP_GRID = 57
COMP_K_LO = 0.05
COMP_K_HI = 1000.0
LEAK_GAIN = 0.562468634
LEAK = (0.481188647, 0.235684508, 0.0232956768, 0.000425484618)
# LEAK_Q14 = round(16384 / LEAK[0]), round(16384 LEAK[d] / LEAK[0]) for d = 1 .. 3
# (leakage()'s integer sweeps)
LEAK_Q14 = (34049, 8025, 793, 14)
COMP_LK = (
    -2.99573227, -2.99573227, -2.99573227, -2.99573227, -2.99573227, -2.99573227, -2.99573227,
    -2.93382774, -2.75149104, -2.56727913, -2.38067575, -2.19118532, -1.99827261, -1.80131145,
    -1.59977845, -1.39293734, -1.17852603, -0.954875856, -0.716569996, -0.443732078,
    -0.0727216439, 1.26506404, 6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528,
    6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528,
    6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528,
    6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528,
    6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528, 6.90775528,
    6.90775528, 6.90775528)
COMP_LS = (
    -39.640889, -32.5534636, -26.6334983, -21.6934889, -17.5774772, -14.1543426, -11.3137605,
    -8.96301456, -7.02432821, -5.43218387, -4.13048301, -3.07337286, -2.22130172, -1.54088875,
    -1.00400981, -0.586096056, -0.265685466, -0.0250974935, 0.151553158, 0.27785812,
    0.365570407, 0.423926699, 0.460776059, 0.482003174, 0.492251518, 0.495007996, 0.492815897,
    0.487643027, 0.480771685, 0.473204061, 0.465488978, 0.458053298, 0.45104467, 0.444651505,
    0.438921161, 0.433851659, 0.429389549, 0.425488241, 0.422127756, 0.419241302, 0.416772569,
    0.414666979, 0.412877585, 0.411364397, 0.410083596, 0.408997884, 0.408085103, 0.407316009,
    0.406666846, 0.406119082, 0.405658754, 0.40527228, 0.404947878, 0.404675632, 0.404447204,
    0.404255577, 0.404094852)
COMP0_LK = (
    -2.99573227, -2.87473544, -2.70858999, -2.54446781, -2.38273758, -2.22382637, -2.06821667,
    -1.91641974, -1.76890375, -1.62597092, -1.48761699, -1.35343407, -1.22260064, -1.09395467,
    -0.96611165, -0.837589202, -0.706918534, -0.572741204, -0.433896282, -0.28950032,
    -0.139014525, 0.0177141265, 0.18045297, 0.348633187, 0.521443018, 0.697944778, 0.877189447,
    1.05830695, 1.24056155, 1.42337341, 1.60631459, 1.78908989, 1.97151137, 2.15347254,
    2.33492553, 2.51586253, 2.69630147, 2.87627568, 3.05582644, 3.2349981, 3.41383483,
    3.59237864, 3.77066834, 3.94873898, 4.12662175, 4.30434404, 4.48192971, 4.6593994,
    4.83677083, 5.01405919, 5.19127742, 5.36843651, 5.54554579, 5.72261314, 5.89964525,
    6.07664772, 6.2536253)
LG1 = (
    42.3356165, 32.8144754, 25.3029824, 19.3975759, 14.7727413, 11.1663162, 8.36750909,
    6.2071393, 4.54969164, 3.28685467, 2.33227027, 1.61727168, 1.08742737, 0.699741374,
    0.420387712, 0.222878723, 0.0865855292, -0.00445631593, -0.0625104334, -0.0969166611,
    -0.114717182, -0.121160345, -0.12010505, -0.114344026, -0.105860739, -0.0960319676,
    -0.0857859966, -0.0757247481, -0.0662168795, -0.0574677678, -0.0495713375, -0.0425478322,
    -0.036370868, -0.0309864398, -0.0263259809, -0.0223150965, -0.0188792017, -0.0159469851,
    -0.0134523728, -0.0113354826, -0.00954291853, -0.00802764976, -0.00674864386,
    -0.00567036821, -0.00476223535, -0.00399804037, -0.00335541981, -0.00281534868,
    -0.00236168393, -0.00198075699, -0.00166101476, -0.0013927064, -0.00116761204,
    -0.000978809374, -0.000820473653, -0.000687707065, -0.000576393598)
# LOG2[i] = round(log2(1 + i/256) 2^24), i = 0 .. 256 (the Weibull draws'
# logarithms in Q24 octaves: draws(); linear between entries, with the
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
RANGE_MIN = 1e-6        # |a1 - a0| at least: the range's scale 8192 / (a1 - a0) stays a
                        # float32 number (a float32 board overflows below ~2e-35)
MAG_CLIP = 16384        # a magnitude's amplitude, Q13: clipped at 2.0 (twice full scale)
MEAN_CLIP = 32768       # the mean's amplitude, Q13: clipped to [-4, 4]
SUM_MAX = 65536         # a window's wave magnitudes (k >= 1) sum to at most 8.0 (Q13): a
                        # window above it is halved until it is not (draws(): it plays
                        # clipped either way - 8.0 is a noise of RMS ~0.6 of full
                        # scale); with the means (4.0 each) two windows' doubled FFT
                        # values stay below 2^19, times a Q12 twiddle below 2^31 (fill)
Q13 = 8192


def _num(path, v, lo, hi):
    if not is_num(v):
        fail(path, "expected a number, got %r" % (v,))
    try:
        v = float(v)
    except OverflowError:                   # an int beyond a double (CPython)
        v = float("inf")
    if not finite(v):
        fail(path, "%r is not finite" % (v,))
    if not lo <= v <= hi:
        fail(path, "%r is outside %r .. %r" % (v, lo, hi))
    return v


def validate(brush, path="brush"):
    """The brush checked (a new dict: k, lam, range as floats); ValueError
    naming the key path of the first problem. Geometry keys, when present,
    must be this display's (window, hop, wavenumbers)."""
    if not isinstance(brush, dict):
        fail(path, "expected an object with k, lam (and range)")
    for key in brush:
        if key not in ("k", "lam", "range", "window", "hop", "wavenumbers", "format", "name",
                       "source", "dx_um", "seed"):
            fail(path, "unknown key %r" % (key,))
    f = brush.get("format", FORMAT)
    if f != FORMAT:
        if f in OLD_FORMATS:
            raise ValueError("%s.format: %r brushes (188-sample windows) are not painted any "
                             "more; fit or design it again (texelpad brush fit / design) for %r"
                             % (path, f, FORMAT))
        raise ValueError("%s.format: expected %r, got %r" % (path, FORMAT, f))
    for key, want in (("window", WINDOW), ("hop", HOP), ("wavenumbers", K)):
        if key in brush and brush[key] != want:
            raise ValueError("%s.%s: this display paints with %s = %d, got %r"
                             % (path, key, key, want, brush[key]))
    out = {}
    fin = getattr(_native_c(), "floats_in", None)
    for key, lo, hi in (("k", K_MIN, K_MAX), ("lam", 0.0, LAM_MAX)):
        v = brush.get(key)
        if not isinstance(v, (list, tuple)):
            raise ValueError("%s.%s: expected a list of %d numbers" % (path, key, K))
        if len(v) != K:
            raise ValueError("%s.%s: expected %d numbers (wavenumbers 0 .. %d), got %d"
                             % (path, key, K, K - 1, len(v)))
        if fin is not None and type(v) in (list, tuple) and fin(v, lo, hi) < 0:
            # every one a float in range, checked by the C core (texelcore_api.h
            # floats_in): 10.8 ms of the loop below on the emulated RP2040
            out[key] = list(v)
            continue
        vals = []
        for i, x in enumerate(v):
            # the common case without a call or a key path: a float in range
            # (NaN and infinities fail the comparison and go to _num for the message)
            if type(x) is float and lo <= x <= hi:
                vals.append(x)
            else:
                vals.append(_num("%s.%s[%d]" % (path, key, i), x, lo, hi))
        out[key] = vals
    r = brush.get("range", [0.0, 1.0])
    if not isinstance(r, (list, tuple)) or len(r) != 2:
        raise ValueError("%s.range: expected [a0, a1]" % path)
    r = [_num("%s.range[%d]" % (path, i), x, -RANGE_MAX, RANGE_MAX) for i, x in enumerate(r)]
    if not abs(r[1] - r[0]) >= RANGE_MIN:
        raise ValueError("%s.range: a0 and a1 must differ by at least %r, got %r"
                         % (path, RANGE_MIN, r))
    out["range"] = r
    return out


def region_texture(path, tex):
    """A scene's brush region checked (texel.runtime.scene calls it for
    kind "brush"; seed 002): the brush by key path (path.brush.lam[3]: ...)
    and the seed it is painted with. The canonical texture."""
    if "brush" not in tex:
        fail(path, "missing required key 'brush' ({k, lam, range}: docs/brush.md)")
    b = validate(tex["brush"], path + ".brush")
    seed = tex.get("seed", 0)
    if not is_int(seed) or not 0 <= seed <= 0xFFFFFFFF:
        raise ValueError("%s.seed: expected an int in [0, 4294967295], got %r"
                         % (path, seed if isinstance(seed, (int, float, str)) else type(seed)))
    return {"kind": "brush", "brush": b, "seed": seed}


def windows(n):
    """How many windows paint n samples: they start at (j - 3) * HOP so that
    every sample of the region lies under four (overlap-add is whole there),
    an even count (the FFT synthesises two windows at once: pair())."""
    w = (n + HOP - 1) // HOP + 3
    return w + (w & 1)


# --- the painting's setup: floats, once per painting -----------------------------------

def array_i(n):
    return array("i", bytes(4 * n))


INVK_MAX = 81920            # 1/k' <= 20 (k' >= 0.05): Q12
LL_NONE = -(3 << 29)        # log2 of a zero scale: every draw rounds to 0 (below any ll:
                            # the cut is -(2 + 4.2 / k') >= -86 octaves, -1.44e9 in Q24)
LL_MAX = 17 << 24           # log2 of a scale of 16 x full scale (Q13): draws beyond clip anyway
LEAK_SWEEPS = 24


def _at(tab, x):
    """tab on the shape grid at grid position x (linear between points, held
    at the ends)."""
    i = int(x)
    i = 0 if i < 0 else (COMP_GRID - 2 if i > COMP_GRID - 2 else i)
    t = x - i
    t = 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)
    return tab[i] + t * (tab[i + 1] - tab[i])


def _q24(f):
    """round(f * 2^24) for a float f (log2 octaves in Q24)."""
    return int(f * 16777216.0 + 0.5) if f >= 0 else -int(-f * 16777216.0 + 0.5)


def _shape(kk, mean):
    """(invk, the shape's factor on the scale as Q24 octaves, the cut) for a brush's
    shape kk: the draws' shape k' = exp(COMP_LK) at kk (COMP0_LK for the
    mean), as round(4096 / k') >= 1, and log2 of the factor on the scale
    that a re-analysis takes away at k' (COMP_LS) - or, for the mean, what
    keeps its mean lam Gamma(1 + 1/k): ln Gamma(1 + 1/k) - ln Gamma(1 + 1/k')."""
    lo = math.log(COMP_K_LO)
    step = (math.log(COMP_K_HI) - lo) / (COMP_GRID - 1)
    x = (math.log(kk) - lo) / step
    lk = _at(COMP0_LK if mean else COMP_LK, x)
    q = int(4096.0 * math.exp(-lk) + 0.5)
    xp = (lk - lo) / step
    if mean:
        f = (_at(LG1, x) - _at(LG1, xp)) / math.log(2.0)
    else:
        f = _at(COMP_LS, xp)
    q = 1 if q < 1 else (INVK_MAX if q > INVK_MAX else q)
    # the cut: a scale below which no draw reaches half a Q13 unit - the
    # largest draw is lam' (-ln u)^(1/k') with -ln u <= 17.33 (u's 24 bits),
    # 4.12 / k' octaves above lam' (82 octaves at k' = 0.05)
    return q, _q24(f), -_q24(2.0 + 4.2 * q / 4096.0)


def compensated(brush):
    """Per wavenumber the integer constants of its draws:
      invk[k]  round(4096 / k'), the draws' shape (_shape)
      ll[k]    log2(lam') in Q24 octaves, lam' the draws' scale in Q13
               amplitude (LL_NONE: scale 0): for a wave, half log2 of its
               deconvolved power (leakage(): in integers, relative to the
               brush's largest scale) plus the shape's factor (a flat brush
               re-analyses to its own scale); for the mean, log2 lam_0 plus
               its own; both times the range's scale
    and (sign of the range, the mean's offset -a0 * scale in Q13). Floats
    only for the range, the largest scale, the mean and once per
    run of one shape (a designed brush has one): the rest is integers, so a float32
    board rounds the same but for those few values."""
    a0, a1 = brush["range"]
    scale = Q13 / (a1 - a0)
    l2amp = math.log(abs(scale)) / math.log(2.0)
    invk = array_i(K)
    ll = array_i(K)
    # the mean
    ik, f, cut = _shape(brush["k"][0], True)
    invk[0] = ik
    lam0 = brush["lam"][0]
    ll[0] = LL_NONE
    if lam0 > 0.0:
        l2 = _q24(math.log(lam0) / math.log(2.0) + l2amp) + f
        if l2 >= cut:
            ll[0] = LL_MAX if l2 > LL_MAX else l2
    # the waves
    a, lmax = leakage(brush["lam"])
    base = _q24(math.log(lmax) / math.log(2.0) + l2amp) - (14 << 24) if lmax > 0.0 else 0
    ks = brush["k"]
    fast = getattr(_native_c(), "wave_ll", None)
    if fast is not None and -(1 << 31) <= base < (1 << 31) \
            and ks.count(ks[1]) - (ks[0] == ks[1]) == K - 1:
        # a brush of one shape (a designed one), its base a 32-bit int (a brush of
        # tiny scales over a wide range has one below: the Python): _waves_ll's
        # loop in C (texelcore_api.h wave_ll, the same integers: 9 ms of Python on
        # the emulated RP2040)
        s = _shape(ks[1], False)
        fast(a, invk, ll, base, s[0], s[1], s[2], LL_NONE, LL_MAX, _tables()[4])
    else:
        _waves_ll(ks, a, invk, ll, base)
    off = -a0 * scale
    off = int(off + 0.5) if off >= 0 else -int(-off + 0.5)
    off = MEAN_CLIP * 4 if off > MEAN_CLIP * 4 else (-MEAN_CLIP * 4 if off < -MEAN_CLIP * 4
                                                       else off)
    return invk, ll, (1 if scale > 0 else -1), off


def _waves_ll(ks, a, invk, ll, base):
    """compensated()'s waves k = 1 .. K-1: invk[k] and ll[k] from the shape
    ks[k] and the power a[k + 2] (leakage())."""
    s = kk = None
    for k in range(1, K):
        if ks[k] != kk:                         # a run of one shape: computed once (a
            kk = ks[k]                          # dict of them would want a block the
            s = _shape(kk, False)               # region's chunks may have taken)
        invk[k] = s[0]
        p = a[k + 2]
        if p <= 0:
            ll[k] = LL_NONE
            continue
        # p is the power in Q28 of lmax^2: log2 lam' = log2(p) / 2 - 14 + log2(lmax) + ..
        l2 = (log2_q24(p) >> 1) + base + s[1]
        ll[k] = LL_NONE if l2 < s[2] else (LL_MAX if l2 > LL_MAX else l2)


def _mulq(g, x):
    """round-ish(g * x / 2^14) for a Q14 g and 0 <= x < 2^31, every partial
    product below 2^31 (leakage)."""
    return (x >> 14) * g + (((x & 16383) * g) >> 14)


def leakage(lams):
    """The waves' powers to paint, in integers: (a, lmax), a[k + 2] the power
    of wavenumber k = 1 .. K-1 in Q28 of lmax^2 (lmax: the brush's largest
    wave scale; a has 3 values of padding each side: the band's edges
    mirrored). A re-analysed window
    reads at k the power painted at k + d times LEAK[|d|] (d = -3 .. 3; with
    independent phases powers add - the windows' and the Hann window's
    leaks, tools/gen_brush_tables.py), so a solves sum_d LEAK[|d|] a_{k+d} =
    lam_k^2 as nearly as non-negative powers can: projected Gauss-Seidel,
    LEAK_SWEEPS sweeps from a = lam^2 (exact at once for a flat brush: the
    kernel sums to 1; it is positive definite, so the sweeps converge; a lone
    line keeps its own power and its neighbours 0), with LEAK_Q14's
    coefficients (1 / LEAK[0], LEAK[d] / LEAK[0]). It treats neighbouring
    wavenumbers' shapes as equal. The sweeps run in C or viper where the
    board has them (the same integers)."""
    n = K - 1
    q, a, lmax = _leak_start(lams)
    if q is None:
        return a, lmax
    c = _native_c()
    if c is not None:
        c.leak(q, a, n, LEAK_SWEEPS, _leak_c())
        return a, lmax
    v = _viper()
    if v is not None:
        v[0].leak(q, a, n, LEAK_SWEEPS, _leak_c())
        return a, lmax
    c1, c2, c3 = LEAK_Q14[1], LEAK_Q14[2], LEAK_Q14[3]
    for _ in range(LEAK_SWEEPS):
        for i in range(3, n + 3):
            v = q[i] - _mulq(c1, a[i - 1] + a[i + 1]) - _mulq(c2, a[i - 2] + a[i + 2]) \
                - _mulq(c3, a[i - 3] + a[i + 3])
            a[i] = v if v > 0 else 0
    return a, lmax


def _leak_start(lams):
    """leakage()'s sweeps' input: (q, a, lmax) - a the target powers (Q28
    of lmax^2, padded: 3 values each side), q = a / LEAK[0] (Q14 product) -
    or (None, zeros, 0.0) for a brush without waves."""
    n = K - 1
    a = array_i(n + 6)
    fast = getattr(_native_c(), "leak_start", None)
    if fast is not None:
        # the loops below in C (texelcore_api.h leak_start: the same float steps,
        # each rounded as here; 11.6 ms of Python on the emulated RP2040)
        q = array_i(n + 6)
        lmax = fast(lams, a, q, LEAK_Q14[0])
        if lmax is None:
            return None, a, 0.0
    else:
        lmax = 0.0
        for i in range(1, K):
            if lams[i] > lmax:
                lmax = lams[i]
        if lmax <= 0.0:
            return None, a, 0.0
        q = array_i(n + 6)
        inv0 = LEAK_Q14[0]
        for i in range(n):
            x = lams[i + 1] / lmax
            p = int(x * x * 268435456.0 + 0.5)      # Q28
            a[i + 3] = p
            q[i + 3] = _mulq(inv0, p)
    # beyond the band the brush goes on mirrored (fixed powers, not solved
    # for): the sweeps treat the edges as the middle - a flat brush is its own
    # solution everywhere, and no edge bin swings to make up for a neighbour
    # the analysis would not have (wavenumber 0 is the mean's: drawn apart)
    for d in range(1, 4):
        a[3 - d] = a[3 + d]
        a[n + 2 + d] = a[n + 2 - d]
    return q, a, lmax


_LEAKC = None


def _leak_c():
    global _LEAKC
    if _LEAKC is None:
        _LEAKC = array("i", LEAK_Q14[1:])
    return _LEAKC


# --- the draws: integers from here on --------------------------------------------------

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


def weibull_q(hi, lo, invk, ll):
    """A magnitude of lam' (-ln u)^(1/k') as a Q24 octave z = log2(the Q13
    value), from the 32-bit draw (hi, lo)'s top 24 bits - all in small ints:
      u    = (x + 0.5) / 2^24, x = the draw's top 24 bits
      a    = log2(1/u) in Q24 = 25 * 2^24 - log2(2 x + 1)           (> 0)
      L    = log2(-ln u) = log2(a) - 24 + log2(ln 2)                (Q24)
      y    = L / k' = L * invk (Q12), in 12-bit limbs of L in Q20
      z    = ll + y
    Returns z, or None for a magnitude that rounds to 0 (y below -32
    octaves; y is at most 83 octaves: 4.12 / k', k' >= 0.05, so z stays
    within +-2^31 for ll from the cut, -86 octaves, to LL_MAX). The draw's low
    byte is the window's phase (draws())."""
    if ll == LL_NONE:
        return None
    x = (hi << 8) | (lo >> 8)
    a = 419430400 - log2_q24(2 * x + 1)     # 25 * 2^24
    if a < 1:
        a = 1
    L = (log2_q24(a) - 402653184 + LOG2_LN2) >> 4      # 24 * 2^24; Q20
    hp = (L >> 12) * invk
    if hp < -33554432:                      # y < -32 octaves: 0
        return None
    if hp > 87031808:                       # 83 octaves (never reached: the bound stated)
        hp = 87031808
    return ll + (hp << 4) + (((L & 0xFFF) * invk) >> 8)


def round_exp2(z, emax, tab):
    """round(2^(z / 2^24)) for a Q24 z, saturated at 2^emax (emax <= 16)."""
    e = z >> 24
    if e >= emax:
        return 1 << emax
    if e < -2:
        return 0
    return (exp2_m(z & 0xFFFFFF, tab) + (1 << (27 - e))) >> (28 - e)


def draws(rng, mag, ph, comp, tab):
    """One window: for k = 0 .. K-1 in order, one 32-bit draw - a Weibull
    magnitude by its inverse CDF from its top 24 bits with the compensated
    shape and scale (weibull_q, round_exp2: the same on every runtime once
    comp is), in Q13 amplitude, and the phase 2 pi ph[k] / 256 from its low
    byte. The mean (k = 0) through the range's sign and offset, clipped to
    +-MEAN_CLIP; the waves clipped at MAG_CLIP, the Nyquist's halved (the
    analysis reads A (-1)^n as 2A: transform.py) and played as a sign (its
    phase's top bit); then halved together while they sum above SUM_MAX."""
    invk, ll, sign, off = comp
    s = 0
    for k in range(K):
        hi, lo = rng.next_hi_lo()
        ph[k] = lo & 0xFF
        z = weibull_q(hi, lo, invk[k], ll[k])
        if k == 0:
            v = 0 if z is None else round_exp2(z, 16, tab)
            v = sign * v + off
            mag[0] = MEAN_CLIP if v > MEAN_CLIP else (-MEAN_CLIP if v < -MEAN_CLIP else v)
        else:
            v = 0 if z is None else round_exp2(z, 14, tab)     # 2^14 = MAG_CLIP
            if k == NYQ:
                v = (v + 1) >> 1
            mag[k] = v
            s += v
    while s > SUM_MAX:
        s = 0
        for k in range(1, K):
            mag[k] >>= 1
            s += mag[k]


# --- two windows' frames by one inverse FFT ------------------------------------------

# Where the FFT reads spectrum entry k: sub-transform k % 3 (64 entries each), at
# the bit-reversed index of k // 3 (ifft()). A literal: worked out at import it
# was 12 of the module's 18 ms import on the emulated Pico's firmware (a brush's
# first push); tests/brush/test_paint.py works it out again.
POS = (
    0, 64, 128, 32, 96, 160, 16, 80, 144, 48, 112, 176, 8, 72, 136, 40,
    104, 168, 24, 88, 152, 56, 120, 184, 4, 68, 132, 36, 100, 164, 20, 84,
    148, 52, 116, 180, 12, 76, 140, 44, 108, 172, 28, 92, 156, 60, 124, 188,
    2, 66, 130, 34, 98, 162, 18, 82, 146, 50, 114, 178, 10, 74, 138, 42,
    106, 170, 26, 90, 154, 58, 122, 186, 6, 70, 134, 38, 102, 166, 22, 86,
    150, 54, 118, 182, 14, 78, 142, 46, 110, 174, 30, 94, 158, 62, 126, 190,
    1, 65, 129, 33, 97, 161, 17, 81, 145, 49, 113, 177, 9, 73, 137, 41,
    105, 169, 25, 89, 153, 57, 121, 185, 5, 69, 133, 37, 101, 165, 21, 85,
    149, 53, 117, 181, 13, 77, 141, 45, 109, 173, 29, 93, 157, 61, 125, 189,
    3, 67, 131, 35, 99, 163, 19, 83, 147, 51, 115, 179, 11, 75, 139, 43,
    107, 171, 27, 91, 155, 59, 123, 187, 7, 71, 135, 39, 103, 167, 23, 87,
    151, 55, 119, 183, 15, 79, 143, 47, 111, 175, 31, 95, 159, 63, 127, 191,
)
SQRT3_2 = 3547              # round(4096 sqrt(3) / 2), Q12


def fill(ma, pa, mb, pb, re, im):
    """The spectrum of two windows a and b for one complex inverse FFT,
    twice over (the overlap-add halves it: one rounding less): Z[k] = c_a +
    i c_b and Z[N-k] = conj(c_a) + i conj(c_b), c = m e^(2 pi i p / 256),
    so the transform's real part is twice window a's frame and its imaginary
    part twice window b's (the means at Z[0], the Nyquist's signed
    magnitudes at Z[96]); written at POS (ifft's order). Q13; the real part
    of c is (m * PHASE[p] + 8192) >> 14, rounded: the same integers
    everywhere. Every |Z| sums to at most 2 (2 SUM_MAX + 2 MEAN_CLIP) < 2^19,
    which bounds every value inside the FFT."""
    P = PHASE
    re[0] = 2 * ma[0]
    im[0] = 2 * mb[0]
    for k in range(1, NYQ):
        m = ma[k]
        p = pa[k]
        ca = (m * P[p] + 8192) >> 14
        sa = (m * P[(p - 64) & 255] + 8192) >> 14
        m = mb[k]
        p = pb[k]
        cb = (m * P[p] + 8192) >> 14
        sb = (m * P[(p - 64) & 255] + 8192) >> 14
        j = POS[k]
        re[j] = ca - sb
        im[j] = sa + cb
        j = POS[WINDOW - k]
        re[j] = ca + sb
        im[j] = cb - sa
    j = POS[NYQ]
    re[j] = 2 * (ma[NYQ] if pa[NYQ] < 128 else -ma[NYQ])
    im[j] = 2 * (mb[NYQ] if pb[NYQ] < 128 else -mb[NYQ])


def _cmul(br, bi, t):
    """(br + i bi) e^(2 pi i t / 192), each of the four products rounded
    (Q12 twiddles: each below 2^31 for values below 2^19)."""
    wr = TW[t]
    wi = TW[(t + 144) % WINDOW]
    return (((br * wr + 2048) >> 12) - ((bi * wi + 2048) >> 12),
            ((br * wi + 2048) >> 12) + ((bi * wr + 2048) >> 12))


def ifft(re, im):
    """x[n] = sum_k Z[k] e^(2 pi i k n / 192), in place, from fill()'s order
    to natural order, in integers: three 64-point radix-2 transforms
    (decimation in time, bit-reversed input), then one radix-3 pass with the
    twiddles e^(2 pi i r n / 192). Twiddle 1 and i multiply exactly, so the
    viper copy may skip them (brush_viper.ifft)."""
    for base in (0, 64, 128):
        s = 2
        while s <= 64:
            half = s >> 1
            ts = WINDOW // s
            for g in range(base, base + 64, s):
                for j in range(half):
                    a = g + j
                    b = a + half
                    xr, xi = _cmul(re[b], im[b], j * ts)
                    ar = re[a]
                    ai = im[a]
                    re[b] = ar - xr
                    im[b] = ai - xi
                    re[a] = ar + xr
                    im[a] = ai + xi
            s <<= 1
    for n in range(64):
        f0r = re[n]
        f0i = im[n]
        f1r, f1i = _cmul(re[64 + n], im[64 + n], n)
        f2r, f2i = _cmul(re[128 + n], im[128 + n], 2 * n)
        sr = f1r + f2r
        si = f1i + f2i
        tr = ((f1r - f2r) * SQRT3_2 + 2048) >> 12
        ti = ((f1i - f2i) * SQRT3_2 + 2048) >> 12
        hr = f0r - (sr >> 1)
        hi = f0i - (si >> 1)
        re[n] = f0r + sr
        im[n] = f0i + si
        re[64 + n] = hr - ti
        im[64 + n] = hi + tr
        re[128 + n] = hr + ti
        im[128 + n] = hi - tr


def frames_py(ma, pa, mb, pb, re, im):
    """Windows a and b's frames, doubled (Q13 amplitude, WINDOW samples
    each) into re and im: fill() then ifft()."""
    fill(ma, pa, mb, pb, re, im)
    ifft(re, im)


def ola_emit(frame, ring, start, n, out):
    """Overlap-add one doubled frame (times HANN, Q9, halved: >> 10) into
    the ring of partial sums (indexed by position mod WINDOW) and emit the HOP samples from start,
    whole now: half the sum (the four windows' Hann weights sum to 2),
    clipped to [0, 1] and scaled to uint16 (those inside 0 .. n-1 only);
    their ring entries back to 0. Returns the next window's start."""
    hann = HANN
    r = start % WINDOW
    for i in range(WINDOW):
        ring[r] += (frame[i] * hann[i]) >> 10
        r += 1
        if r == WINDOW:
            r = 0
    r = start % WINDOW
    for i in range(HOP):
        p = start + i
        if 0 <= p < n:
            val = ring[r] >> 1
            out[p] = 0 if val <= 0 else (65535 if val >= Q13 else (val * 65535 + 4096) >> 13)
        ring[r] = 0
        r += 1
    return start + HOP


# --- painting ------------------------------------------------------------------------

_V = None                   # the viper loops and their tables (_viper())
RBIAS = 1 << 23             # brush_viper.py: the ring of partial sums held + RBIAS


_T = None


# the tables as the C and viper loops read them, in this order: the texelpad
# firmware reads them in place from its ROMFS (rom.const_table; 3.5 KB of heap
# otherwise, kept for the next painting), other images make arrays once
TABLE_FILES = (("brush_phase.i16", "h"), ("brush_tw.i16", "h"), ("brush_hann.i32", "i"),
               ("brush_log2.i32", "i"), ("brush_pos.i32", "i"))


def _tables():
    """(None, PHASE and TW as int16, HANN, LOG2, POS as int32 tables): what
    the C and viper loops read (made once)."""
    global _T
    if _T is None:
        from ..compat import ROM
        if ROM:
            from ..rom import const_table
            _T = (None,) + tuple(const_table(__file__, f, t, c) for (f, c), t in
                                 zip(TABLE_FILES, (PHASE, TW, HANN, LOG2, POS)))
        else:
            _T = (None, array("h", PHASE), array("h", TW), array("i", HANN), array("i", LOG2),
                  array("i", POS))
    return _T


def _viper():
    """(module brush_viper, _tables()' arrays) or None where the port has no
    native emitter. A MemoryError while loading is not remembered: the next
    painting tries again."""
    global _V
    if _V is None:
        from ..compat import HAS_VIPER, native
        if not HAS_VIPER:
            _V = False
            return None
        if native("texel.gen.brush_viper", "frames") is None:
            return None
        import texel.gen.brush_viper as mod
        _V = (mod,) + _tables()[1:]
    return _V or None


_C = None                   # the firmware's C module (_native_c())


def _native_c():
    """The C painter (device/cmod/texelcore, compat.core(): the texelpad
    firmware's _texelcore, or deploy's native module), or None."""
    global _C
    if _C is None:
        from ..compat import core
        _C = core() or False
    return _C or None


def _numpy():
    from ..compat import numpy_mod
    return numpy_mod


def prepare():
    """The painter's tables made now (plan_int's 6 KB table, the viper
    loops' arrays): kept once made; scene.build calls this before it takes
    a region's chunks, while the heap still has blocks that size."""
    table()
    _tables()
    if _native_c() is None:
        _viper()


def paint(brush, seed, n, out=None, how=None):
    """The region's map: n samples of uint16 amplitude (0..65535) painted
    from a validated brush and a seed, into out (an array('H') of n, upload
    Chunks, or a new array). Windows in pairs: draws() for each, one inverse
    FFT for both (fill, ifft), overlap-add with the Q9 Hann window (HANN:
    the four windows over a sample sum to 1024 exactly: no seams), halved,
    clipped to [0, 1], uint16. Memory beyond out: WINDOW-long work arrays.

    how: "c" (_texelcore: the firmware's or deploy's native module; device/cmod/texelcore),
    "viper" (brush_viper.py: the port's native emitter), "numpy" (CPython:
    every pair's FFT at once) or "python" (the loops here); None takes the
    first the runtime has. All give the same integers."""
    from .rng import Rng
    if out is None:
        out = array("H", bytes(2 * n))
    elif len(out) < n:
        raise ValueError("out: %d values, too few for n = %d" % (len(out), n))
    if how is None:
        how = "c" if _native_c() is not None else (
            "viper" if _viper() is not None else ("numpy" if _numpy() is not None
                                                  else "python"))
    if how not in ("c", "viper", "numpy", "python"):
        raise ValueError("how: expected 'c', 'viper', 'numpy' or 'python', got %r" % (how,))
    if how == "c" and _native_c() is None:
        raise ValueError("how: this board has no C painter (_texelcore: the texelpad firmware, "
                         "or texelpad deploy's native module)")
    if how == "viper" and _viper() is None:
        raise ValueError("how: this port has no native emitter (viper)")
    if how == "numpy" and _numpy() is None:
        raise ValueError("how: numpy is not here")
    rng = Rng(seed)
    comp = compensated(brush)
    tab = table()
    if how == "c":
        return _paint_c(rng, comp, tab, n, out)
    if how == "viper":
        return _paint_viper(_viper(), rng, comp, tab, n, out)
    if how == "numpy":
        return _paint_numpy(_numpy(), rng, comp, tab, n, out)
    ma, pa, mb, pb = array_i(K), array_i(K), array_i(K), array_i(K)
    re, im, ring = array_i(WINDOW), array_i(WINDOW), array_i(WINDOW)
    start = -3 * HOP
    for _ in range(windows(n) // 2):
        draws(rng, ma, pa, comp, tab)
        draws(rng, mb, pb, comp, tab)
        frames_py(ma, pa, mb, pb, re, im)
        start = ola_emit(re, ring, start, n, out)
        start = ola_emit(im, ring, start, n, out)
    return out


def _paint_numpy(np, rng, comp, tab, n, out):
    """paint() on CPython: the draws as in Python, then fill, ifft and the
    overlap-add of every window at once (int64: the same integer operations)."""
    nw = windows(n)
    mags = np.zeros((nw, K), dtype=np.int64)
    phs = np.zeros((nw, K), dtype=np.int64)
    m, p = array_i(K), array_i(K)
    for w in range(nw):
        draws(rng, m, p, comp, tab)
        mags[w] = m
        phs[w] = p
    P = np.array(PHASE, dtype=np.int64)
    ca, sa = (mags * P[phs] + 8192) >> 14, (mags * P[(phs - 64) & 255] + 8192) >> 14
    a, b = slice(0, nw, 2), slice(1, nw, 2)
    pos = np.array(POS)
    ks = np.arange(1, NYQ)
    re = np.zeros((nw // 2, WINDOW), dtype=np.int64)
    im = np.zeros_like(re)
    re[:, 0], im[:, 0] = 2 * mags[a, 0], 2 * mags[b, 0]
    re[:, pos[ks]] = ca[a, 1:NYQ] - sa[b, 1:NYQ]
    im[:, pos[ks]] = sa[a, 1:NYQ] + ca[b, 1:NYQ]
    re[:, pos[WINDOW - ks]] = ca[a, 1:NYQ] + sa[b, 1:NYQ]
    im[:, pos[WINDOW - ks]] = ca[b, 1:NYQ] - sa[a, 1:NYQ]
    sgn = np.where(phs[:, NYQ] < 128, 2, -2) * mags[:, NYQ]
    re[:, pos[NYQ]], im[:, pos[NYQ]] = sgn[a], sgn[b]
    tw = np.array(TW, dtype=np.int64)

    def cmul(br, bi, t):
        wr, wi = tw[t], tw[(t + 144) % WINDOW]
        return (((br * wr + 2048) >> 12) - ((bi * wi + 2048) >> 12),
                ((br * wi + 2048) >> 12) + ((bi * wr + 2048) >> 12))
    for base in (0, 64, 128):
        s = 2
        while s <= 64:
            half = s >> 1
            j = np.arange(half)
            ia = (base + np.arange(0, 64, s)[:, None] + j[None, :]).ravel()
            ib = ia + half
            xr, xi = cmul(re[:, ib], im[:, ib], np.tile(j * (WINDOW // s), 64 // s))
            ar, ai = re[:, ia], im[:, ia]
            re[:, ib], im[:, ib] = ar - xr, ai - xi
            re[:, ia], im[:, ia] = ar + xr, ai + xi
            s <<= 1
    k = np.arange(64)
    f0r, f0i = re[:, :64].copy(), im[:, :64].copy()
    f1r, f1i = cmul(re[:, 64:128], im[:, 64:128], k)
    f2r, f2i = cmul(re[:, 128:], im[:, 128:], 2 * k)
    sr, si = f1r + f2r, f1i + f2i
    tr, ti = ((f1r - f2r) * SQRT3_2 + 2048) >> 12, ((f1i - f2i) * SQRT3_2 + 2048) >> 12
    hr, hi = f0r - (sr >> 1), f0i - (si >> 1)
    re[:, :64], im[:, :64] = f0r + sr, f0i + si
    re[:, 64:128], im[:, 64:128] = hr - ti, hi + tr
    re[:, 128:], im[:, 128:] = hr + ti, hi - tr
    frames = np.empty((nw, WINDOW), dtype=np.int64)
    frames[a], frames[b] = re, im
    parts = (frames * np.array(HANN, dtype=np.int64)) >> 10     # (nw, WINDOW)
    q = parts.reshape(nw, 4, HOP)
    # hop h of the map (from -3 HOP) sums part 3 of window h-3 ... part 0 of window h
    acc = np.zeros((nw + 3, HOP), dtype=np.int64)
    for part in range(4):
        acc[part:part + nw] += q[:, part]
    val = acc[3:3 + (n + HOP - 1) // HOP].ravel()[:n] >> 1
    u = np.where(val <= 0, 0, np.where(val >= Q13, 65535, (val * 65535 + 4096) >> 13))
    if isinstance(out, array):
        out[:n] = array("H", u.astype(np.uint16).tobytes())
    else:
        for i in range(n):
            out[i] = int(u[i])
    return out


def state(rng):
    """The texture generator's state as the C and viper loops step it: its
    eight 16-bit halves (gen/rng.py), array('H'); they write it back."""
    return array("H", (rng.a_hi, rng.a_lo, rng.b_hi, rng.b_lo, rng.c_hi, rng.c_lo,
                       rng.d_hi, rng.d_lo))


def _paint_c(rng, comp, tab, n, out):
    """paint()'s whole loop in C: the generator's state, the constants, the
    tables and out's arrays (one, or a Chunks' 512-value chunks) handed over."""
    c = _native_c()
    _, ptab, tw, hann, log2t, pos = _tables()
    invk, ll, sign, off = comp
    st = state(rng)
    chunks = getattr(out, "chunks", None)
    c.paint(st, invk, ll, sign, off, n, chunks if chunks is not None else (out,),
            _chunk_bits(chunks), tab, log2t, ptab, tw, hann, pos)
    return out


def _chunk_bits(chunks):
    """log2 of a Chunks' chunk length (upload.CHUNK: 512; every chunk but the
    last is that long), 30 for one array."""
    if chunks is None or len(chunks) < 2:
        return 30
    size = len(chunks[0])
    bits = 0
    while (1 << bits) < size:               # (MicroPython's int has no bit_length)
        bits += 1
    if size != 1 << bits:
        raise ValueError("out: chunks of %d values (a power of two expected)" % size)
    return bits


def _paint_viper(v, rng, comp, tab, n, out):
    """paint()'s loop with every per-pair step in viper (brush_viper.py): the
    draws of both windows, their frames (fill + ifft), and each window's
    overlap-add and emission straight into out's memory (an array, or a
    Chunks' arrays: a hop across two chunks goes through a 48-value array)."""
    mod, ptab, tw, hann, log2t, pos = v
    invk, ll, sign, off = comp
    llo = array_i(K)
    for k in range(K):
        llo[k] = ll[k] + (3 << 29)              # >= 0 (LL_NONE: 0)
    so = array("i", (sign + 1, off + (1 << 20)))
    st = state(rng)
    ma, pa, mb, pb = array_i(K), array_i(K), array_i(K), array_i(K)
    re, im, ring = array_i(WINDOW), array_i(WINDOW), array_i(WINDOW)
    for i in range(WINDOW):
        ring[i] = RBIAS
    tmp = array("H", bytes(2 * HOP))
    chunks = getattr(out, "chunks", None)
    cb = _chunk_bits(chunks)
    mask = (1 << cb) - 1
    draw, frames, ola = mod.draws, mod.frames, mod.ola_emit
    start = -3 * HOP
    for _ in range(windows(n) // 2):
        draw(st, invk, llo, ma, pa, tab, log2t, so)
        draw(st, invk, llo, mb, pb, tab, log2t, so)
        frames(ma, pa, mb, pb, ptab, pos, re, im, tw)
        for fr in (re, im):
            r0 = start % WINDOW
            a = 0 if start >= 0 else -start
            b = HOP if start + HOP <= n else n - start
            if b <= a:
                ola(fr, hann, ring, r0, tmp, 0, 0, 0)
            elif chunks is None:
                ola(fr, hann, ring, r0, out, start + a, a, b)
            else:
                p = start + a
                c = chunks[p >> cb]
                at = p & mask
                if at + b - a <= len(c):
                    ola(fr, hann, ring, r0, c, at, a, b)
                else:                           # across two chunks
                    ola(fr, hann, ring, r0, tmp, 0, a, b)
                    m = len(c) - at
                    c[at:] = tmp[:m]
                    chunks[(p >> cb) + 1][:b - a - m] = tmp[m:b - a]
            start += HOP
    return out
