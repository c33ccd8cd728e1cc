# Seed 001's texture options (params.OPTION_KEYS; docs/generator.md, "Seed
# 001's stimulus: a lower bound and phase reset"), as a post-pass over the plan
# the per-texel loop made - so neither loop (plan.Plan's, plan_int.texels_py
# and its viper twin plan_int_viper.texels) changes, and without a texel below
# the bound and with the phase running on, the plan is the loop's, bit for
# bit. Imported only by a plan that sets an option, and not even then where
# the C core plans (device/cmod/texelcore tc_plan_options: the texelpad
# firmware, a deployed native module): a board playing any other texture
# never holds this code (every KB of bytecode counts on a Pico heap:
# tests/runtime/test_scene.py, test_real_memory_error_under_micropython).
#
#   min_cpmm  seed 001: "distribution frequencies are constrained to exceed
#             1 cycle/mm" (../shared/seeds/001_*.txt, III.A). Our reading:
#             the distribution is truncated. A texel whose pitch is below the
#             bound is redrawn from a SECOND generator stream (gen/rng.py:
#             REDRAW_CONSTS below, the same seed, 16 outputs discarded; one output
#             per try, in texel order), at most MIN_TRIES tries; a texel still
#             below then plays AT the bound (counted in plan.at_min; texels
#             redrawn in plan.redrawn). The main stream is untouched, so every
#             other texel keeps its draw.
#   phase     "reset": every texel starts at the texture's start phase (the
#             one drawn first, t28[0] / phi[0]); seed 001 has no phase
#             continuity and its texel borders are what its staircase tests.
#
# Format 2 (apply_int), all integers - the same plan on every runtime:
#   below     the played step is below the bound's step,
#             d < D_MIN = round(min_mc * 53 * 2^28 / 10^7) (as the band
#             limit's D_CAP), with (d, e) = plan_int.step_d(y): e < 28 and
#             d < D_MIN
#   redraw    y = log_pitch(norm_q24(output)) (the loop's arithmetic)
#   tail      d28, t28 and the count above Nyquist recomputed from y for the
#             whole map with the loop's arithmetic (a texel left below plays
#             d = D_MIN, as one above the band limit plays D_CAP)
#   reset     t28[i] = t28[0]
# Format 1 (apply_float): the same in the runtime's float: below is
# f < min_cpmm; a try is one Rng.normal() pulled, quantized and capped as
# plan.Plan's loop does; phi/t28/d28 recomputed with the loop's arithmetic.
# With draws= (the lab's logged draws) the redraws still come from the
# seed's second stream.
import math
from array import array      # at the top: an extensible built-in imported inside a function
#                              walks sys.path each time (1.64 ms on the emulated RP2040)
from . import params as _params
from .rng import Rng, ppnd16, uniform_of
from .grid import mdb
from .plan import UNITS_PER_TURN, PHASE_MASK, _TWO_PI, _DX, _frac_u28, round_half_away
from .plan_int import step_d, norm_q24, mulmod28, Y_LO, Y_HI, NYQ_EXP, MASK28
from ..compat import core

MIN_TRIES = 64
SKIP_HOPELESS = True    # (tests turn it off to prove the skip changes nothing)
# The redraw stream: gen/rng.py's generator and seeding with other constants,
# the fractional parts of sqrt(2), sqrt(3), sqrt(5) (SHA-256's first words)
# in 16-bit halves. A second stream, so the main one - and every texel that
# needs no redraw - stays what it is without the bound.
REDRAW_CONSTS = ((0x6A09, 0xE667), (0xBB67, 0xAE85), (0x3C6E, 0xF372))


def _reset(plan):
    return plan.params.get("phase", "continuous") == "reset"


# --- format 2 ----------------------------------------------------------------------

def log_pitch(z, mu, sigma, q):
    """plan_int.texels_py's y of one draw z (Q24): mu + round(sigma*z/2^24)
    half away from zero, clamped to [Y_LO, Y_HI], quantized."""
    za = -z if z < 0 else z
    s1 = sigma >> 14
    s0 = sigma & 0x3FFF
    z1 = za >> 14
    z0 = za & 0x3FFF
    m = s1 * z0 + s0 * z1 + ((s0 * z0 + 0x800000) >> 14)
    p = ((s1 * z1) << 4) + (m >> 10)
    y = mu - p if z < 0 else mu + p
    if y < Y_LO:
        y = Y_LO
    elif y > Y_HI:
        y = Y_HI
    if q:
        ya = -y if y < 0 else y
        n = (2 * ya + q) // (2 * q)
        y = -n * q if y < 0 else n * q
    return y


def d_min(min_mc):
    """The bound's phase step in 2^-28 turns per sample (as plan_int's D_CAP;
    a bigint on MicroPython, once per texture)."""
    return (min_mc * 53 * (1 << 28) + 5000000) // 10000000


def _below(y, dmin, tab):
    d, _, _, e = step_d(y, tab)
    return e < 28 and d < dmin


def redraw_int(plan, ys, dmin, tab):
    """Redraw, in place in ys, the log pitch of every texel below the bound;
    returns (texels redrawn, texels left at the bound). A texel left at the
    bound keeps its first draw's y (it plays D_MIN: tail_int; PlanInt.f
    shows the bound). When no draw can reach the bound - the largest z the
    inverse normal gives (x = 2^32 - 1) is below it; log_pitch and _below are
    monotone in z - the tries are skipped: the same plan, without up to
    MIN_TRIES draws per texel (a mean far below the bound at a small spread:
    seed 001's mapping at low P and I; bench/seed001_options.py)."""
    d28 = plan.d28
    rng = None
    redrawn = 0
    at_min = 0
    hopeless = SKIP_HOPELESS and _below(
        log_pitch(norm_q24(0xFFFF, 0xFFFF, tab), plan.mu, plan.sigma, plan.q), dmin, tab)
    for i in range(plan.count):
        # d28 >= D_MIN: not below (a capped step is D_CAP > D_MIN: params
        # refuses min >= band limit); under it, the step may still be an
        # aliased one (e >= 28, reduced mod a turn): step_d tells
        if d28[i] >= dmin or not _below(ys[i], dmin, tab):
            continue
        redrawn += 1
        if hopeless:
            at_min += 1
            continue
        if rng is None:
            rng = Rng(plan.params["seed"], consts=REDRAW_CONSTS)
        for _ in range(MIN_TRIES):
            hi, lo = rng.next_hi_lo()
            y = log_pitch(norm_q24(hi, lo, tab), plan.mu, plan.sigma, plan.q)
            if not _below(y, dmin, tab):
                ys[i] = y
                break
        else:
            at_min += 1
    return redrawn, at_min


def tail_int(plan, ys, dmin, tab):
    """d28, t28 from the log pitches ys with plan_int.texels_py's arithmetic
    (a step below D_MIN plays D_MIN); returns the count above Nyquist."""
    L = plan.L
    dcap = plan.dcap
    t28 = plan.t28
    d28 = plan.d28
    t = t28[0]                  # the start phase (the loop's first write)
    tf = 0
    above = 0
    for i in range(plan.count):
        d, a, af, e = step_d(ys[i], tab)
        if e >= NYQ_EXP:
            above += 1
        if e < 28 and d < dmin:
            d = dmin
            a = dmin
            af = 0
        if dcap and (e >= 28 or d > dcap):
            d = dcap
            a = dcap
            af = 0
        d28[i] = d & MASK28
        t28[i] = t
        tf += L * af
        t = (t + mulmod28(L, a) + (tf >> 8)) & MASK28
        tf &= 0xFF
    return above


def _apply_c(c, plan, ys, dmin, tab):
    """apply_int's bound (and reset) by the C core (device/cmod/texelcore
    tc_options): the same integers as redraw_int and tail_int
    (tests/gen/test_texel_core.py)."""
    r = Rng(plan.params["seed"], consts=REDRAW_CONSTS)
    st = array("H", (r.a_hi, r.a_lo, r.b_hi, r.b_lo, r.c_hi, r.c_lo, r.d_hi, r.d_lo))
    hopeless = SKIP_HOPELESS and _below(
        log_pitch(norm_q24(0xFFFF, 0xFFFF, tab), plan.mu, plan.sigma, plan.q), dmin, tab)
    out = array("i", (0, 0, plan.above_nyquist))
    c.options(st, plan.count, plan.L, plan.mu, plan.sigma, plan.q, plan.dcap, dmin,
              1 | (2 if hopeless else 0) | (4 if _reset(plan) else 0), MIN_TRIES, tab, ys,
              plan.t28, plan.d28, out)
    plan.redrawn, plan.at_min, plan.above_nyquist = out[0], out[1], out[2]


def apply_int(plan, ys, tab, engine=None):
    """The options of plan.params on a format-2 plan the loop made
    (plan_int.PlanInt, plan_numpy.PlanIntNumpy); ys: its log pitches (kept
    or not). Sets min_mc, redrawn, at_min; changes ys, t28, d28 and
    above_nyquist only where the options ask. engine: the plan's ("py",
    "viper": these Python loops; None or "c": the C core where there is one,
    _apply_c)."""
    lo = plan.params.get("min_cpmm")
    c = core() if engine in (None, "c") else None
    if lo is not None:
        plan.min_mc = mdb(lo)
        dmin = d_min(plan.min_mc)
        if c:
            _apply_c(c, plan, ys, dmin, tab)
            return
        plan.redrawn, plan.at_min = redraw_int(plan, ys, dmin, tab)
        if plan.redrawn:
            plan.above_nyquist = tail_int(plan, ys, dmin, tab)
    if _reset(plan):
        t28 = plan.t28
        t0 = t28[0]
        for i in range(1, plan.count):
            t28[i] = t0


# --- format 1 ----------------------------------------------------------------------

def redraw_float(plan, F):
    """Redraw in plan.f every pitch below the bound; (redrawn, at_min)."""
    p = plan.params
    fmin = F(p["min_cpmm"])
    mu = F(p["pitch_db"]) / 10.0                     # as plan.Plan
    sigma = 10.0 ** (F(p["irregularity_db"]) / 10.0)
    q = F(p["quant_db"]) / 10.0
    cap = p["band_limit_cpmm"]
    if cap is not None:
        cap = F(cap)
    f = plan.f
    rng = None
    redrawn = 0
    at_min = 0
    # no draw can reach the bound when the largest z there is (u = 1 - 2^-33:
    # 6.36) gives a pitch 0.1 % below it (the margin covers the runtime's float
    # rounding): the tries are skipped (redraw_int's reasoning)
    top = mu + sigma * ppnd16(uniform_of(0xFFFF, 0xFFFF, F), uniform_of(0, 0, F))
    if q > 0.0:
        top = q * round_half_away(top / q)
    hopeless = SKIP_HOPELESS and 10.0 ** top * 1.001 < fmin
    for i in range(plan.count):
        if F(f[i]) >= fmin:
            continue
        redrawn += 1
        if hopeless:
            f[i] = fmin
            at_min += 1
            continue
        if rng is None:
            rng = Rng(p["seed"], F, REDRAW_CONSTS)
        for _ in range(MIN_TRIES):
            pull = mu + sigma * rng.normal()
            if q > 0.0:
                pull = q * round_half_away(pull / q)
            fi = 10.0 ** pull
            if cap is not None and fi > cap:
                fi = cap
            if fi >= fmin:
                break
        else:
            fi = fmin
            at_min += 1
        f[i] = fi
    return redrawn, at_min


def tail_float(plan, F):
    """phi, t28, d28 and above_nyquist from plan.f with plan.Plan's loop
    arithmetic, in its float type F (f holds F values exactly: array('d')
    on CPython, the board's own float there)."""
    f, phi, ta, da = plan.f, plan.phi, plan.t28, plan.d28
    Lf = F(plan.L)
    phase = plan.u * _TWO_PI
    t28 = ta[0]                 # the start phase (the loop's first write)
    above = 0
    fprev = 0.0
    for i in range(plan.count):
        fi = F(f[i])
        if fi > _params.NYQUIST_CPMM:
            above += 1
        if i > 0:
            phase = _TWO_PI * fprev * _DX * Lf + phase
        phi[i] = phase
        fprev = fi
        step = fi * _DX
        step = step - math.floor(step)
        da[i] = int(step * UNITS_PER_TURN + 0.5) & PHASE_MASK
        ta[i] = t28
        t28 = (t28 + _frac_u28(step * Lf)) & PHASE_MASK
    plan.above_nyquist = above


def apply_float(plan, F=float):
    """The options of plan.params on a format-1 plan the loop made
    (plan.Plan, plan_numpy.PlanNumpy). Sets redrawn, at_min; changes f, phi,
    t28, d28 and above_nyquist only where the options ask."""
    if plan.params.get("min_cpmm") is not None:
        plan.redrawn, plan.at_min = redraw_float(plan, F)
        if plan.redrawn:
            tail_float(plan, F)
    if _reset(plan):
        phi, ta = plan.phi, plan.t28
        for i in range(1, plan.count):
            phi[i] = phi[0]
            ta[i] = ta[0]
