// See texel_core.h. Comments name the Python each block mirrors.
#include "texel_core.h"

#define MASK28 0x0FFFFFFF
#define Y_LO (-369098752)       // plan_int.Y_LO = -22 * 2^24
#define Y_HI 251658240          // plan_int.Y_HI = 15 * 2^24
#define LOG2_STEP0 342929786    // plan_int.LOG2_STEP0
#define LN2_Q20 726817          // plan_int.LN2_Q20
#define NORM 512                // plan_int_tables.NORM
#define EXP_MID 256             // plan_int_tables.EXP_MID

// plan_int.mul28: round(a * b / 2^28) in 15-bit limbs (0 <= a, b < 2^29)
static int32_t mul28(int32_t a, int32_t b) {
    int32_t a1 = a >> 15, a0 = a & 0x7FFF, b1 = b >> 15, b0 = b & 0x7FFF;
    return ((a1 * b1) << 2) + ((a1 * b0 + a0 * b1 + ((a0 * b0) >> 15) + 4096) >> 13);
}

// gen/rng.py Rng.next_hi_lo: xoshiro128++ in 16-bit halves; s = a, b, c, d
// (hi, lo each); the output's halves in *x_hi, *x_lo
static inline void rng_next(int32_t *s, int32_t *x_hi, int32_t *x_lo) {
    int32_t a_hi = s[0], a_lo = s[1], b_hi = s[2], b_lo = s[3];
    int32_t c_hi = s[4], c_lo = s[5], d_hi = s[6], d_lo = s[7];
    int32_t lo = a_lo + d_lo;
    int32_t hi = (a_hi + d_hi + (lo >> 16)) & 0xFFFF;
    lo &= 0xFFFF;
    int32_t r_hi = ((hi << 7) | (lo >> 9)) & 0xFFFF;
    int32_t r_lo = ((lo << 7) | (hi >> 9)) & 0xFFFF;
    lo = r_lo + a_lo;
    *x_hi = (r_hi + a_hi + (lo >> 16)) & 0xFFFF;
    *x_lo = lo & 0xFFFF;
    int32_t u_hi = ((b_hi << 9) | (b_lo >> 7)) & 0xFFFF;
    int32_t u_lo = (b_lo << 9) & 0xFFFF;
    c_hi ^= a_hi; c_lo ^= a_lo;
    d_hi ^= b_hi; d_lo ^= b_lo;
    b_hi ^= c_hi; b_lo ^= c_lo;
    a_hi ^= d_hi; a_lo ^= d_lo;
    c_hi ^= u_hi; c_lo ^= u_lo;
    hi = d_hi;
    d_hi = ((hi << 11) | (d_lo >> 5)) & 0xFFFF;
    d_lo = ((d_lo << 11) | (hi >> 5)) & 0xFFFF;
    s[0] = a_hi; s[1] = a_lo; s[2] = b_hi; s[3] = b_lo;
    s[4] = c_hi; s[5] = c_lo; s[6] = d_hi; s[7] = d_lo;
}

// plan_int.norm_q24: |z| of the output (x_hi, x_lo) in Q24, its sign in *sgn
static inline int32_t norm_abs(int32_t x_hi, int32_t x_lo, const int32_t *tab, int32_t *sgn) {
    if (x_hi >= 0x8000) {
        x_hi = 0xFFFF - x_hi;
        x_lo = 0xFFFF - x_lo;
        *sgn = 1;
    } else {
        *sgn = -1;
    }
    int32_t wh = (x_hi << 1) | (x_lo >> 15);
    int32_t wl = ((x_lo << 1) & 0xFFFF) | 1;
    int32_t b, e;
    if (wh) { b = wh; e = 16; } else { b = wl; e = 0; }
    if (b >= 0x100) { b >>= 8; e += 8; }
    if (b >= 0x10) { b >>= 4; e += 4; }
    if (b >= 0x4) { b >>= 2; e += 2; }
    if (b >= 0x2) { e += 1; }
    int32_t top;
    if (e >= 16) {
        int32_t k = e - 16;
        top = ((wh << (16 - k)) | (wl >> k)) & 0xFFFF;
    } else {
        top = (wl << (16 - e)) & 0xFFFF;
    }
    int32_t j = NORM + (e << 5) + (top >> 11);
    int32_t t0 = tab[j];
    return t0 + (((tab[j + 1] - t0) * (top & 0x7FF) + 1024) >> 11);
}

// options.log_pitch / the loop's y: mu +- round(sigma * |z| / 2^24), clamped,
// rounded half away from zero to q's grid (s1, s0: sigma's 14-bit limbs)
static inline int32_t log_pitch(int32_t za, int32_t sgn, int32_t mu, int32_t s1, int32_t s0,
                                int32_t q) {
    int32_t z1 = za >> 14, z0 = za & 0x3FFF;
    int32_t m = s1 * z0 + s0 * z1 + ((s0 * z0 + 0x800000) >> 14);
    int32_t p = ((s1 * z1) << 4) + (m >> 10);
    int32_t y = sgn < 0 ? mu - p : mu + p;
    if (y < Y_LO) {
        y = Y_LO;
    } else if (y > Y_HI) {
        y = Y_HI;
    }
    if (q) {
        if (y < 0) {
            y = -((q - 2 * y) / (2 * q)) * q;
        } else {
            y = ((2 * y + q) / (2 * q)) * q;
        }
    }
    return y;
}

// plan_int.step_d: (d, a, af, e) of a log pitch y; D = round(2^(y + LOG2_STEP0))
// in 2^-28 turns
static inline void step_d(int32_t y, const int32_t *tab, int32_t *dp, int32_t *ap,
                          int32_t *afp, int32_t *ep) {
    int32_t w = y + LOG2_STEP0;
    int32_t e = w >> 24;
    int32_t r = w & 0xFFFFFF;
    int32_t mm = mul28(mul28(tab[r >> 16], tab[EXP_MID + ((r >> 8) & 0xFF)]),
                       (1 << 28) + (((r & 0xFF) * LN2_Q20 + 32768) >> 16));
    int32_t d, a, af;
    if (e >= 28) {
        int32_t k = e - 28;
        d = (mm & (MASK28 >> k)) << k;
        a = d;
        af = 0;
    } else if (e < -2) {
        d = 0;
        a = 0;
        af = 0;
    } else {
        d = (mm + (1 << (27 - e))) >> (28 - e);
        if (e >= 20) {
            int32_t k = e - 20;
            a = mm >> (28 - e);
            af = (mm & (0xFF >> k)) << k;
        } else {
            a = (mm + (1 << (19 - e))) >> (20 - e);
            af = a & 0xFF;
            a >>= 8;
        }
    }
    *dp = d; *ap = a; *afp = af; *ep = e;
}

// t += L * (a + af/256) mod 2^28 (plan_int.mulmod28 and the carry in *tf)
static inline int32_t advance(int32_t t, int32_t L, int32_t a, int32_t af, int32_t *tf) {
    *tf += L * af;
    int32_t ll = L & 0x3FFF, lh = L >> 14, dh = a >> 14, dl = a & 0x3FFF;
    t = (t + ll * dl + (((ll * dh + lh * dl) & 0x3FFF) << 14) + (*tf >> 8)) & MASK28;
    *tf &= 0xFF;
    return t;
}

int32_t tc_texels(uint16_t st[10], int32_t count, int32_t L, int32_t mu, int32_t sigma,
                  int32_t q, int32_t dcap, const int32_t *tab, int32_t *t28, int32_t *d28,
                  int32_t *ys, int32_t *zs, int32_t keep) {
    int32_t above = 0, t = 0, tf = 0;
    int32_t s[8];
    for (int k = 0; k < 8; k++) {
        s[k] = st[k];
    }
    int32_t s1 = sigma >> 14, s0 = sigma & 0x3FFF;
    for (int32_t i = -17; i < count; i++) {     // the warm-up (16), the start phase's draw
        int32_t x_hi, x_lo;
        rng_next(s, &x_hi, &x_lo);
        if (i < 0) {
            if (i == -1) {                      // the start phase (rng.phase_fraction_u28)
                st[8] = (uint16_t)x_hi;
                st[9] = (uint16_t)x_lo;
                t = (((x_hi << 12) | (x_lo >> 4)) + ((x_lo >> 3) & 1)) & MASK28;
            }
            continue;
        }
        int32_t sgn, za = norm_abs(x_hi, x_lo, tab, &sgn);
        if (keep & 1) {
            zs[i] = za * sgn;
        }
        int32_t y = log_pitch(za, sgn, mu, s1, s0, q);
        if (keep & 2) {
            ys[i] = y;
        }
        int32_t d, a, af, e;
        step_d(y, tab, &d, &a, &af, &e);
        if (e >= 27) {                          // plan_int.NYQ_EXP
            above++;
        }
        if (dcap && (e >= 28 || d > dcap)) {
            d = dcap;
            a = dcap;
            af = 0;
        }
        d28[i] = d & MASK28;
        t28[i] = t;
        t = advance(t, L, a, af, &tf);
    }
    return above;
}

static inline int32_t below(int32_t y, int32_t dmin, const int32_t *tab) {
    int32_t d, a, af, e;
    step_d(y, tab, &d, &a, &af, &e);
    return e < 28 && d < dmin;
}

void tc_options(uint16_t st[8], int32_t count, int32_t L, int32_t mu, int32_t sigma, int32_t q,
                int32_t dcap, int32_t dmin, int32_t flags, int32_t tries, const int32_t *tab,
                int32_t *ys, int32_t *t28, int32_t *d28, int32_t out[3]) {
    int32_t s[8];
    for (int k = 0; k < 8; k++) {
        s[k] = st[k];
    }
    int32_t s1 = sigma >> 14, s0 = sigma & 0x3FFF;
    int32_t redrawn = 0, at_min = 0, above = out[2];
    if (flags & TC_OPT_BOUND) {
        for (int32_t i = 0; i < count; i++) {   // options.redraw_int
            if (d28[i] >= dmin || !below(ys[i], dmin, tab)) {
                continue;
            }
            redrawn++;
            if (flags & TC_OPT_HOPELESS) {
                at_min++;
                continue;
            }
            int32_t k;
            for (k = 0; k < tries; k++) {
                int32_t x_hi, x_lo, sgn;
                rng_next(s, &x_hi, &x_lo);
                int32_t za = norm_abs(x_hi, x_lo, tab, &sgn);
                int32_t y = log_pitch(za, sgn, mu, s1, s0, q);
                if (!below(y, dmin, tab)) {
                    ys[i] = y;
                    break;
                }
            }
            if (k == tries) {
                at_min++;
            }
        }
        if (redrawn) {                          // options.tail_int
            int32_t t = t28[0], tf = 0;
            above = 0;
            for (int32_t i = 0; i < count; i++) {
                int32_t d, a, af, e;
                step_d(ys[i], tab, &d, &a, &af, &e);
                if (e >= 27) {
                    above++;
                }
                if (e < 28 && d < dmin) {
                    d = dmin;
                    a = dmin;
                    af = 0;
                }
                if (dcap && (e >= 28 || d > dcap)) {
                    d = dcap;
                    a = dcap;
                    af = 0;
                }
                d28[i] = d & MASK28;
                t28[i] = t;
                t = advance(t, L, a, af, &tf);
            }
        }
    }
    if (flags & TC_OPT_RESET) {                 // "reset": every texel at the start phase
        for (int32_t i = 1; i < count; i++) {
            t28[i] = t28[0];
        }
    }
    for (int k = 0; k < 8; k++) {
        st[k] = (uint16_t)s[k];
    }
    out[0] = redrawn;
    out[1] = at_min;
    out[2] = above;
}

int32_t tc_fill(uint16_t *out, int32_t a, int32_t b, int32_t t, int32_t d,
                const uint16_t *tab, int32_t g) {
    for (; a < b; a++) {
        t = (t + d) & MASK28;
        int32_t i = t >> 18;
        int32_t y0 = tab[i];
        int32_t v = y0 + (((tab[i + 1] - y0) * ((t >> 2) & 0xFFFF) + 32768) >> 16);
        out[a] = (uint16_t)((v * g + 8192) >> 14);
    }
    return t;
}

void tc_render(uint16_t *out, int32_t n, int32_t L, int32_t count, const int32_t *t28,
               const int32_t *d28, const uint16_t *tab, int32_t g) {
    for (int32_t i = 0; i < count; i++) {
        int32_t a = i * L, b = a + L;
        if (b > n) {
            b = n;
        }
        tc_fill(out, a, b, t28[i], d28[i], tab, g);
    }
}

void tc_samples(uint16_t **chunks, int32_t bits, int32_t n, const uint16_t *vals, int32_t m,
                int32_t stretch) {
    int32_t mask = (1 << bits) - 1;
    // Chunk by chunk through a pointer (the inner loops index no chunk table): the
    // same values as position by position. On the emulated RP2040 the stretch of a
    // full screen (19,200 positions) took 9.5 ms indexing chunks[i >> bits][i & mask].
    if (!stretch || m == 1 || n == 1) {
        int32_t k = 0;
        for (int32_t c0 = 0; c0 < n; c0 += mask + 1) {
            uint16_t *out = chunks[c0 >> bits];
            uint16_t *stop = out + (n - c0 < mask + 1 ? n - c0 : mask + 1);
            while (out < stop) {
                *out++ = vals[k];
                if (++k == m) {
                    k = 0;
                }
            }
        }
        return;
    }
    int32_t den = n - 1, step = m - 1, k = 0, r = 0;
    if (den <= 32768) {
        // floor((r << 15) / den) kept as q + qr/den while r moves (r << 15 < 2^30):
        // r += step adds (step << 15) / den and its remainder; r -= j * den takes
        // j << 15 off q exactly. No division per position (an RP2040's divider
        // is a call away): the same w as Python's (r << 15) // den.
        int32_t sq = (step << 15) / den, sr = (step << 15) % den, q = 0, qr = 0;
        int32_t a = vals[0], d = m > 1 ? vals[1] - a : 0;
        for (int32_t c0 = 0; c0 < n; c0 += mask + 1) {
            uint16_t *out = chunks[c0 >> bits];
            uint16_t *stop = out + (n - c0 < mask + 1 ? n - c0 : mask + 1);
            while (out < stop) {
                // r == 0 gives w = (0 + 1) >> 1 = 0: a itself, as the branch did
                *out++ = (uint16_t)(a + ((d * ((q + 1) >> 1) + 8192) >> 14));
                r += step;
                q += sq;
                qr += sr;
                if (qr >= den) {
                    q++;
                    qr -= den;
                }
                if (r >= den) {
                    int32_t j = r / den;
                    k += j;
                    r -= j * den;
                    q -= j << 15;
                    a = vals[k];
                    d = k + 1 < m ? vals[k + 1] - a : 0;
                }
            }
        }
        return;
    }
    for (int32_t i = 0; i < n; i++) {       // past 32,769 positions: int64
        int32_t a = vals[k], v = a;
        if (r != 0) {
            int32_t w = (int32_t)(((((int64_t)r) << 15) / den + 1) >> 1);
            v = a + (((vals[k + 1] - a) * w + 8192) >> 14);
        }
        chunks[i >> bits][i & mask] = (uint16_t)v;
        r += step;
        if (r >= den) {
            k += r / den;
            r = r % den;
        }
    }
}

// (only texelcore_api.h's plan uses these, which a native module for a core
// without a float unit leaves out: TC_NO_FLOAT)
#ifndef TC_NO_FLOAT
// plan_int._round_q: Q24 octaves of mdb millidecibels, round half up (C_DB:
// log2(10) / 10000 * 2^40; the product needs 43 bits)
#define C_DB 365249857
#define LOG2_LOG2_10 29058488   // plan_int.LOG2_LOG2_10
static int32_t round_q(int32_t mdb) {
    return (int32_t)(((int64_t)mdb * C_DB + 32768) >> 16);
}

// plan_int.exp2_q24: round(2^(y / 2^24) * 2^24)
static int32_t exp2_q24(int32_t y, const int32_t *tab) {
    int32_t e = y >> 24, r = y & 0xFFFFFF;
    int32_t m = mul28(mul28(tab[r >> 16], tab[EXP_MID + ((r >> 8) & 0xFF)]),
                      (1 << 28) + (((r & 0xFF) * LN2_Q20 + 32768) >> 16));
    if (e >= 4) {
        return m << (e - 4);
    }
    return (m + (1 << (3 - e))) >> (4 - e);
}

void tc_plan_consts(int32_t pitch_mdb, int32_t irreg_mdb, int32_t quant_mdb, int32_t cap_mc,
                    const int32_t *tab, int32_t out[4]) {
    out[0] = round_q(pitch_mdb);
    out[1] = exp2_q24(LOG2_LOG2_10 + round_q(irreg_mdb), tab);
    out[2] = round_q(quant_mdb);         // 0 for 0 (quantization off)
    // (cap_mc * 53 * 2^28 + 5000000) // 10^7, 0 without a band limit
    out[3] = (int32_t)(((int64_t)cap_mc * 53 * (1 << 28) + 5000000) / 10000000);
}

// plan_int.seeded with gen/rng.py SEED_CONSTS
void tc_seeded(uint32_t seed, uint16_t st[10]) {
    static const uint16_t c[6] = {0x9E37, 0x79B9, 0x243F, 0x6A88, 0xB7E1, 0x5162};
    st[0] = (uint16_t)(seed >> 16);
    st[1] = (uint16_t)(seed & 0xFFFF);
    for (int i = 0; i < 6; i++) {
        st[2 + i] = c[i];
    }
    st[8] = 0;
    st[9] = 0;
}

void tc_plan_options(uint32_t seed, int32_t min_mc, int32_t reset, int32_t count, int32_t L,
                     const int32_t k[4], const int32_t *tab, int32_t *ys, int32_t *t28,
                     int32_t *d28, int32_t above, int32_t out[3]) {
    // Rng(seed, consts=options.REDRAW_CONSTS), then its 16 warm-up draws (rng.WARMUP)
    int32_t s[8] = {(int32_t)(seed >> 16), (int32_t)(seed & 0xFFFF), 0x6A09, 0xE667, 0xBB67,
                    0xAE85, 0x3C6E, 0xF372};
    for (int w = 0; w < 16; w++) {
        int32_t x_hi, x_lo;
        rng_next(s, &x_hi, &x_lo);
    }
    uint16_t st[8];
    for (int i = 0; i < 8; i++) {
        st[i] = (uint16_t)s[i];
    }
    int32_t flags = reset ? TC_OPT_RESET : 0, dmin = 0;
    if (min_mc >= 0) {
        // options.d_min: (min_mc * 53 * 2^28 + 5000000) // 10^7
        dmin = (int32_t)(((int64_t)min_mc * 53 * (1 << 28) + 5000000) / 10000000);
        flags |= TC_OPT_BOUND;
        // options.redraw_int's hopeless: the largest draw (x = 2^32 - 1) still below
        int32_t sgn;
        int32_t za = norm_abs(0xFFFF, 0xFFFF, tab, &sgn);
        if (below(log_pitch(za, sgn, k[0], k[1] >> 14, k[1] & 0x3FFF, k[2]), dmin, tab)) {
            flags |= TC_OPT_HOPELESS;
        }
    }
    out[0] = 0;
    out[1] = 0;
    out[2] = above;
    tc_options(st, count, L, k[0], k[1], k[2], k[3], dmin, flags, TC_MIN_TRIES, tab, ys, t28,
               d28, out);
}
#endif  // TC_NO_FLOAT


void tc_sines(uint16_t *out, int32_t n, const int32_t *steps, int32_t *ph, int32_t m,
              const uint16_t *tab, int32_t a0, int32_t ws, int32_t rq) {
    int32_t m2 = 2 * m, hw = ws >> 1;
    for (int32_t i = 0; i < n; i++) {
        int32_t a = 0;
        for (int32_t j = 0; j < m2; j += 2) {
            int32_t k = ph[j], r = ph[j + 1];
            int32_t y0 = tab[k];
            // fq = r*4096/100000 (0..4095, by a multiply: 99999*21475 < 2^31)
            a += (y0 << 4) + (((tab[k + 1] - y0) * ((r * 21475) >> 19)) >> 8);
            r += steps[j + 1];
            k += steps[j];
            if (r >= 100000) {
                r -= 100000;
                k += 1;
            }
            if (k >= 1024) {
                k -= 1024;
            }
            ph[j] = k;
            ph[j + 1] = r;
        }
        int32_t x = a - a0;
        if (x <= 0) {
            out[i] = 0;
        } else if (x >= ws) {           // beyond 65535 (a longer map): clipped
            out[i] = 65535;
        } else {
            int32_t u = ((x >> 6) * rq) >> 14;
            int64_t e = ((int64_t)x << 16) - (int64_t)u * ws;
            while (e >= hw) {
                u += 1;
                e -= ws;
            }
            while (e < hw - ws) {
                u -= 1;
                e += ws;
            }
            out[i] = (uint16_t)(u < 65535 ? u : 65535);
        }
    }
}
