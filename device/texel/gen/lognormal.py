# Seed 001's lognormal in linear units <-> the generator's decibel parameters.
#
# Seed 001 (../shared/seeds/001_*.txt, "Texel Length Test") gives its texel
# pitch distribution as a lognormal with mean 4 c/mm and SD 1.2 or 4.3 c/mm,
# in LINEAR units. The generator draws log10 f ~ Normal(mu10, sigma10) with
# pitch_db = 10*mu10 and irregularity_db = 10*log10(sigma10) (gen/params.py).
# It is the same distribution when (moments of a lognormal, natural log):
#   sigma_ln^2 = ln(1 + sd^2/mean^2)      mu_ln = ln(mean) - sigma_ln^2/2
#   mu10 = mu_ln/ln 10                    sigma10 = sigma_ln/ln 10
# Worked (docs/generator.md, "Seed 001's stimulus"):
#   to_db(4, 1.2) = (5.833, -8.945)       to_db(4, 4.3) = (4.353, -4.195)
#
# Pure device module (math only): imports and runs on MicroPython and
# CircuitPython. Textures carry pitch_db/irregularity_db, never mean/sd: a
# 30-bit-float board could round a conversion near a 0.001 dB boundary the
# other way than CPython and so play another format-2 texture; the host
# converts with to_db and sends the dB values (docs/generator.md says why).
import math
from . import params as _params

_LN10 = math.log(10.0)
SIGMA10_MIN = 0.001     # decades: params.IRREG_DB_MIN = -30 dB


def _mdb(x):
    """x rounded to 0.001 (half away from zero), as gen/grid.py's mdb."""
    v = x * 1000.0
    m = int(v + 0.5) if v >= 0 else -int(-v + 0.5)
    return m / 1000.0


def _number(key, v):
    """v as a finite float, or ValueError in gen/check.py's words."""
    from . import check as c
    if not c.is_num(v):
        c.fail(key, "expected a number, got %s %s" % (type(v).__name__, c.show(v)))
    if isinstance(v, int) and not -c.BIG < v < c.BIG:
        c.fail(key, "%s is out of range" % c.show(v))
    v = float(v)
    if not c.finite(v):
        c.fail(key, "%r is not finite" % (v,))
    return v


def _in_range(key, value, lo, hi, why):
    if not lo <= value <= hi:
        from . import check as c
        c.fail(key, "%r is out of range %s (%s)" % (value, c.rng(lo, hi), why))


def to_db(mean_cpmm, sd_cpmm):
    """(pitch_db, irregularity_db), each rounded to 0.001 dB, of the
    lognormal pitch distribution with this mean and SD in cycles/mm.

    sd = 0 (or a spread below 0.001 decade) gives params.IRREG_DB_MIN, the
    narrowest the generator draws. ValueError for a non-number, mean <= 0,
    sd < 0 or a result outside the generator's pitch/irregularity ranges."""
    mean = _number("mean_cpmm", mean_cpmm)
    sd = _number("sd_cpmm", sd_cpmm)
    if mean <= 0.0:
        from . import check as c
        c.fail("mean_cpmm", "%r must be > 0 (cycles/mm)" % (mean,))
    if sd < 0.0:
        from . import check as c
        c.fail("sd_cpmm", "%r must be >= 0 (cycles/mm)" % (sd,))
    r = sd / mean
    var_ln = math.log(1.0 + r * r)
    sigma10 = math.sqrt(var_ln) / _LN10
    mu10 = (math.log(mean) - var_ln / 2.0) / _LN10
    pitch_db = _mdb(10.0 * mu10)
    _in_range("pitch_db", pitch_db, _params.PITCH_DB_MIN, _params.PITCH_DB_MAX,
              "from mean_cpmm %r, sd_cpmm %r" % (mean, sd))
    if sigma10 < SIGMA10_MIN:
        return pitch_db, _params.IRREG_DB_MIN
    irreg_db = _mdb(10.0 * math.log10(sigma10))
    if irreg_db < _params.IRREG_DB_MIN:
        # sigma10 just above 0.001 can round to -30.000 only; never below
        irreg_db = _params.IRREG_DB_MIN
    _in_range("irregularity_db", irreg_db, _params.IRREG_DB_MIN, _params.IRREG_DB_MAX,
              "from mean_cpmm %r, sd_cpmm %r" % (mean, sd))
    return pitch_db, irreg_db


def from_db(pitch_db, irregularity_db):
    """(mean_cpmm, sd_cpmm) in cycles/mm of the lognormal the generator
    draws for these parameters (no band limit, no lower bound, no
    quantization): the inverse of to_db, for reports."""
    p = _number("pitch_db", pitch_db)
    i = _number("irregularity_db", irregularity_db)
    _in_range("pitch_db", p, _params.PITCH_DB_MIN, _params.PITCH_DB_MAX, "dB")
    _in_range("irregularity_db", i, _params.IRREG_DB_MIN, _params.IRREG_DB_MAX, "dB")
    mu_ln = p / 10.0 * _LN10
    sigma_ln = 10.0 ** (i / 10.0) * _LN10
    var_ln = sigma_ln * sigma_ln
    mean = math.exp(mu_ln + var_ln / 2.0)
    # exp(var) - 1 loses digits for a tiny var: expm1 is not on every port
    if var_ln < 1e-4:
        em1 = var_ln * (1.0 + var_ln / 2.0 + var_ln * var_ln / 6.0)
    else:
        em1 = math.exp(var_ln) - 1.0
    return mean, mean * math.sqrt(em1)
