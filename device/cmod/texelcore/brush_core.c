// See brush_core.h. Every bound is device/texel/gen/brush.py's: magnitudes
// below 2^14, FFT values below 2^19, so every product here is below 2^31.
#include "brush_core.h"

#define LL_NONE (-(3 << 29))

// xoshiro128++'s state update (gen/rng.py), for tb_draws and tb_skip
#define TB_XO_STEP(a, b, c, d)                  \
    do {                                        \
        uint32_t u_ = (b) << 9;                 \
        (c) ^= (a);                             \
        (d) ^= (b);                             \
        (b) ^= (c);                             \
        (a) ^= (d);                             \
        (c) ^= u_;                              \
        (d) = ((d) << 11) | ((d) >> 21);        \
    } while (0)

// brush.log2_q24 in two halves: the caller finds v's top bit n and shifts v
// up to M = v << (31 - n) (bit 31 set; brush.log2_q24's m = v << (29 - n) is
// M >> 2, exactly: v < 2^30), then log2n looks LOG2 up. The top bit by
// shifting M up by 4, 2, 1 (a Cortex-M0+ has no CLZ; libgcc's takes longer),
// from where the caller's values mostly are: brush.log2_q24's halving, in
// fewer steps.
#define TB_NORM(M, n)                           \
    do {                                        \
        while ((M) < (1u << 28)) {              \
            (M) <<= 4;                          \
            (n) -= 4;                           \
        }                                       \
        if ((M) < (1u << 30)) {                 \
            (M) <<= 2;                          \
            (n) -= 2;                           \
        }                                       \
        if ((M) < (1u << 31)) {                 \
            (M) <<= 1;                          \
            (n) -= 1;                           \
        }                                       \
    } while (0)

static inline int32_t log2n(uint32_t M, int32_t n, const int32_t *t) {
    const int32_t *p = t + (M >> 23 & 0xFF);
    int32_t lo = p[0];
    return (n << 24) + lo + (((p[1] - lo) * (int32_t)(M >> 11 & 0xFFF)) >> 12);
}

static inline int32_t mul28(int32_t a, int32_t b) {
    // plan_int.mul28: round(a * b / 2^28) in 15-bit limbs
    int32_t a1 = a >> 15, a0 = a & 0x7FFF, b1 = b >> 15, b0 = b & 0x7FFF;
    int32_t s = a1 * b0 + a0 * b1 + ((a0 * b0) >> 15) + 4096;
    return ((a1 * b1) << 2) + (s >> 13);
}

static inline int32_t round_exp2(int32_t z, int32_t emax, const int32_t *tab) {
    // brush.round_exp2. Its last product mul28(a, 2^28 + d), d below 2^15
    // (d <= 2829): b1 = 2^13, b0 = d, so ((a1 b1) << 2) + (s >> 13) =
    // a1 2^15 + a0 + ((a1 d + ((a0 d) >> 15) + 4096) >> 13) (a0 2^13 leaves
    // the shift whole) = a + that: the same integer, two products fewer
    int32_t e = z >> 24;
    if (e >= emax) {
        return 1 << emax;
    }
    if (e < -2) {
        return 0;
    }
    int32_t a = mul28(tab[(z >> 16) & 0xFF], tab[256 + ((z >> 8) & 0xFF)]);
    int32_t d = (((z & 0xFF) * 726817 + 32768) >> 16);      // LN2_Q20
    int32_t m = a + (((a >> 15) * d + (((a & 0x7FFF) * d) >> 15) + 4096) >> 13);
    return (m + (1 << (27 - e))) >> (28 - e);
}

__attribute__((noinline)) static int32_t draw_mag(uint32_t x, int32_t invk, int32_t ll, int32_t emax,
                               const tb_tables *t) {
    // brush.weibull_q + round_exp2 for one draw x (ll != LL_NONE)
    const int32_t *lt = t->log2t;
    // log2_q24(2 (x >> 8) + 1): v = (x >> 7) | 1 < 2^25, so M from v << 7, n = 24
    uint32_t M = (x | 0x80) & ~(uint32_t)0x7F;
    int32_t n = 24;
    TB_NORM(M, n);
    int32_t q = 419430400 - log2n(M, n, lt);                  // 25 * 2^24
    if (q < 1) {
        q = 1;
    }
    // q <= 25 * 2^24 < 2^29: M from q << 2, n = 29
    M = (uint32_t)q << 2;
    n = 29;
    TB_NORM(M, n);
    int32_t L = (log2n(M, n, lt) - 402653184 - 8871228) >> 4;
    int32_t hp = (L >> 12) * invk;
    if (hp < -33554432) {
        return 0;
    }
    if (hp > 87031808) {        // 83 octaves
        hp = 87031808;
    }
    // * 16, not << 4: hp may be negative (C99 leaves that shift undefined)
    return round_exp2(ll + hp * 16 + (((L & 0xFFF) * invk) >> 8), emax, t->exp_tab);
}

void tb_draws(uint16_t st[8], const int32_t *invk, const int32_t *ll, int32_t sign,
              int32_t off, const tb_tables *t, int32_t *mag, int32_t *ph) {
    // the K draws first (mag holds them until their magnitudes replace
    // them), then the magnitudes: the same integers as brush.draws, with
    // fewer values to hold at once
    uint32_t a = ((uint32_t)st[0] << 16) | st[1], b = ((uint32_t)st[2] << 16) | st[3];
    uint32_t c = ((uint32_t)st[4] << 16) | st[5], d = ((uint32_t)st[6] << 16) | st[7];
    for (int k = 0; k < TB_K; k++) {
        // xoshiro128++ (gen/rng.py): rotl(a + d, 7) + a
        uint32_t x = a + d;
        x = ((x << 7) | (x >> 25)) + a;
        TB_XO_STEP(a, b, c, d);
        ph[k] = (int32_t)(x & 0xFF);
        mag[k] = (int32_t)x;
    }
    st[0] = a >> 16; st[1] = a & 0xFFFF; st[2] = b >> 16; st[3] = b & 0xFFFF;
    st[4] = c >> 16; st[5] = c & 0xFFFF; st[6] = d >> 16; st[7] = d & 0xFFFF;
    int32_t v = ll[0] == LL_NONE ? 0 : draw_mag((uint32_t)mag[0], invk[0], ll[0], 16, t);
    v = sign * v + off;
    mag[0] = v > 32768 ? 32768 : (v < -32768 ? -32768 : v);    // MEAN_CLIP
    int32_t s = 0;
    for (int k = 1; k < TB_K; k++) {
        int32_t l = ll[k];
        v = l == LL_NONE ? 0 : draw_mag((uint32_t)mag[k], invk[k], l, 14, t);
        if (k == TB_K - 1) {
            v = (v + 1) >> 1;                   // the Nyquist, halved
        }
        mag[k] = v;
        s += v;
    }
    while (s > 65536) {                         // SUM_MAX
        s = 0;
        for (int k = 1; k < TB_K; k++) {
            mag[k] >>= 1;
            s += mag[k];
        }
    }
}

// Q12 products as brush._cmul rounds them, each of the four on its own
#define TB_R12(p) (((p) + 2048) >> 12)

static inline void bfly(int32_t *pa, int32_t *pb, int32_t wr, int32_t wi) {
    // one of brush.ifft's radix-2 butterflies, a general twiddle
    int32_t br = pb[0], bi = pb[1];
    int32_t xr = TB_R12(br * wr) - TB_R12(bi * wi);
    int32_t xi = TB_R12(br * wi) + TB_R12(bi * wr);
    int32_t ar = pa[0], ai = pa[1];
    pb[0] = ar - xr;
    pb[1] = ai - xi;
    pa[0] = ar + xr;
    pa[1] = ai + xi;
}

static inline void radix3(int32_t *z, int32_t f1r, int32_t f1i, int32_t f2r, int32_t f2i) {
    int32_t f0r = z[0], f0i = z[1];
    int32_t sr = f1r + f2r, si = f1i + f2i;
    int32_t tr = ((f1r - f2r) * 3547 + 2048) >> 12, ti = ((f1i - f2i) * 3547 + 2048) >> 12;
    int32_t hr = f0r - (sr >> 1), hi = f0i - (si >> 1);
    z[0] = f0r + sr;
    z[1] = f0i + si;
    z[128] = hr - ti;
    z[129] = hi + tr;
    z[256] = hr + ti;
    z[257] = hi - tr;
}

void tb_frames(const int32_t *ma, const int32_t *pa, const int32_t *mb, const int32_t *pb,
               const tb_tables *t, int32_t *z) {
    const int16_t *P = t->phase;
    const int32_t *pos = t->pos;
    z[0] = 2 * ma[0];
    z[1] = 2 * mb[0];
    for (int k = 1; k < TB_K - 1; k++) {
        int32_t m = ma[k], p = pa[k];
        int32_t ca = (m * P[p] + 8192) >> 14, sa = (m * P[(p - 64) & 255] + 8192) >> 14;
        m = mb[k];
        p = pb[k];
        int32_t cb = (m * P[p] + 8192) >> 14, sb = (m * P[(p - 64) & 255] + 8192) >> 14;
        int32_t *q = z + 2 * pos[k];
        q[0] = ca - sb;
        q[1] = sa + cb;
        q = z + 2 * pos[TB_WINDOW - k];
        q[0] = ca + sb;
        q[1] = cb - sa;
    }
    int32_t *q = z + 2 * pos[TB_K - 1];
    q[0] = 2 * (pa[TB_K - 1] < 128 ? ma[TB_K - 1] : -ma[TB_K - 1]);
    q[1] = 2 * (pb[TB_K - 1] < 128 ? mb[TB_K - 1] : -mb[TB_K - 1]);
    // the same butterflies as brush.ifft in another order (each on its own
    // values: the order between them changes nothing). The first two
    // passes (twiddles 1 and i, exact) together on four values at once
    int32_t *end = z + 2 * TB_WINDOW;
    for (int32_t *g = z; g < end; g += 8) {
        int32_t x0r = g[0], x0i = g[1], x1r = g[2], x1i = g[3];
        int32_t y0r = x0r + x1r, y0i = x0i + x1i, y1r = x0r - x1r, y1i = x0i - x1i;
        int32_t x2r = g[4], x2i = g[5], x3r = g[6], x3i = g[7];
        int32_t y2r = x2r + x3r, y2i = x2i + x3i, y3r = x2r - x3r, y3i = x2i - x3i;
        g[0] = y0r + y2r;
        g[1] = y0i + y2i;
        g[4] = y0r - y2r;
        g[5] = y0i - y2i;
        g[2] = y1r - y3i;       // y1 + i y3
        g[3] = y1i + y3r;
        g[6] = y1r + y3i;       // y1 - i y3
        g[7] = y1i - y3r;
    }
    // then each twiddle once for all the groups that use it; 1 and i apart
    const int16_t *tw = t->tw;
    for (int s = 8, ts = 24; s <= 64; s <<= 1, ts >>= 1) {
        int half = s >> 1;
        int32_t step = 2 * s;
        for (int32_t *a = z; a < end; a += step) {          // twiddle 1
            int32_t *b = a + s;
            int32_t br = b[0], bi = b[1], ar = a[0], ai = a[1];
            b[0] = ar - br;
            b[1] = ai - bi;
            a[0] = ar + br;
            a[1] = ai + bi;
        }
        for (int32_t *a = z + half; a < end; a += step) {   // twiddle i
            int32_t *b = a + s;
            int32_t br = b[0], bi = b[1], ar = a[0], ai = a[1];
            b[0] = ar + bi;
            b[1] = ai - br;
            a[0] = ar - bi;
            a[1] = ai + br;
        }
        for (int jj = 1; jj < half; jj++) {
            if (2 * jj == half) {
                continue;
            }
            int32_t tt = jj * ts;
            int32_t wr = tw[tt], wi = tw[tt < 48 ? tt + 144 : tt - 48];
            for (int32_t *a = z + 2 * jj; a < end; a += step) {
                bfly(a, a + s, wr, wi);
            }
        }
    }
    // the radix-3 pass; its twiddles 1 (n = 0) and i (n = 48, 2n = 48) apart,
    // the others' sines (brush._cmul: TW[(t + 144) % 192]) by the range of t
    radix3(z, z[128], z[129], z[256], z[257]);
    for (int n = 1; n < 64; n++) {
        int32_t *w = z + 2 * n;
        int32_t f1r, f1i, f2r, f2i, br, bi, wr, wi;
        br = w[128];
        bi = w[129];
        if (n < 48) {
            wr = tw[n];
            wi = tw[n + 144];
            f1r = TB_R12(br * wr) - TB_R12(bi * wi);
            f1i = TB_R12(br * wi) + TB_R12(bi * wr);
        } else if (n > 48) {
            wr = tw[n];
            wi = tw[n - 48];
            f1r = TB_R12(br * wr) - TB_R12(bi * wi);
            f1i = TB_R12(br * wi) + TB_R12(bi * wr);
        } else {
            f1r = -bi;
            f1i = br;
        }
        br = w[256];
        bi = w[257];
        if (n < 24) {
            wr = tw[2 * n];
            wi = tw[2 * n + 144];
            f2r = TB_R12(br * wr) - TB_R12(bi * wi);
            f2i = TB_R12(br * wi) + TB_R12(bi * wr);
        } else if (n > 24) {
            wr = tw[2 * n];
            wi = tw[2 * n - 48];
            f2r = TB_R12(br * wr) - TB_R12(bi * wi);
            f2i = TB_R12(br * wi) + TB_R12(bi * wr);
        } else {
            f2r = -bi;
            f2i = br;
        }
        radix3(w, f1r, f1i, f2r, f2i);
    }
}

void tb_skip(uint16_t st[8], int32_t steps) {
    // tb_draws' generator steps without their draws: the state a window
    // further on starts from (TB_K steps a window)
    uint32_t a = ((uint32_t)st[0] << 16) | st[1], b = ((uint32_t)st[2] << 16) | st[3];
    uint32_t c = ((uint32_t)st[4] << 16) | st[5], d = ((uint32_t)st[6] << 16) | st[7];
    for (int32_t k = 0; k < steps; k++) {
        TB_XO_STEP(a, b, c, d);
    }
    st[0] = a >> 16; st[1] = a & 0xFFFF; st[2] = b >> 16; st[3] = b & 0xFFFF;
    st[4] = c >> 16; st[5] = c & 0xFFFF; st[6] = d >> 16; st[7] = d & 0xFFFF;
}

int32_t tb_windows(int32_t n) {
    int32_t w = (n + TB_HOP - 1) / TB_HOP + 3;
    return w + (w & 1);
}

void tb_paint(uint16_t st[8], const int32_t *invk, const int32_t *ll, int32_t sign,
              int32_t off, const tb_tables *t, int32_t n, uint16_t *const *chunks,
              int32_t chunk_bits, int32_t *work) {
    // the work arrays in the caller's buffer (TB_WORK values): 3.8 KB would be
    // half a Pico's 8 KB stack, which MicroPython's stack check does not see
    int32_t *ring = work + 4 * TB_K + 2 * TB_WINDOW;
    for (int i = 0; i < TB_WINDOW; i++) {
        ring[i] = 0;
    }
    tb_paint_range(st, invk, ll, sign, off, t, n, chunks, chunk_bits, work, ring, 0,
                   tb_windows(n), 0);
}

void tb_paint_range(uint16_t st[8], const int32_t *invk, const int32_t *ll, int32_t sign,
                    int32_t off, const tb_tables *t, int32_t n, uint16_t *const *chunks,
                    int32_t chunk_bits, int32_t *work, int32_t *ring, int32_t w_from,
                    int32_t w_to, int32_t lo_emit) {
    int32_t *ma = work, *pa = ma + TB_K, *mb = pa + TB_K, *pb = mb + TB_K;
    int32_t *z = pb + TB_K;
    int32_t mask = (1 << chunk_bits) - 1;
    int32_t start = TB_HOP * w_from - 3 * TB_HOP;
    int32_t r0 = start % TB_WINDOW;             // start mod WINDOW, in 0 .. WINDOW - 1
    if (r0 < 0) {
        r0 += TB_WINDOW;
    }
    for (int32_t pair = w_from; pair < w_to; pair += 2) {
        tb_draws(st, invk, ll, sign, off, t, ma, pa);
        tb_draws(st, invk, ll, sign, off, t, mb, pb);
        tb_frames(ma, pa, mb, pb, t, z);
        for (int which = 0; which < 2; which++) {
            // ring[(r0 + i) % WINDOW] += ..., in two runs that do not wrap
            const int32_t *fr = z + which, *hann = t->hann;
            int32_t *rg = ring + r0;
            int32_t i = 0, m = TB_WINDOW - r0;
            for (; i < m; i++) {
                rg[i] += (fr[2 * i] * hann[i]) >> 10;
            }
            rg = ring - m;
            for (; i < TB_WINDOW; i++) {
                rg[i] += (fr[2 * i] * hann[i]) >> 10;
            }
            // the HOP samples from start that are inside lo_emit .. n - 1 (below
            // lo_emit a fresh ring lacks the windows before w_from)
            int32_t lo = start < lo_emit ? lo_emit - start : 0;
            int32_t hi = n - start < TB_HOP ? n - start : TB_HOP;
            rg = ring + r0;
            for (i = lo; i < hi; i++) {
                int32_t p = start + i;
                int32_t v = rg[i] >> 1;
                chunks[p >> chunk_bits][p & mask] = (uint16_t)(
                    v <= 0 ? 0 : (v >= 8192 ? 65535 : (v * 65535 + 4096) >> 13));
            }
            for (i = 0; i < TB_HOP; i++) {
                rg[i] = 0;
            }
            start += TB_HOP;
            r0 = r0 + TB_HOP < TB_WINDOW ? r0 + TB_HOP : r0 + TB_HOP - TB_WINDOW;
        }
    }
}

void tb_leak(const int32_t *q, int32_t *a, int32_t n, int32_t sweeps, const int32_t *c) {
    for (int32_t s = 0; s < sweeps; s++) {
        for (int32_t i = 3; i < n + 3; i++) {
            int32_t v = q[i] - tb_mulq(c[0], a[i - 1] + a[i + 1])
                        - tb_mulq(c[1], a[i - 2] + a[i + 2]) - tb_mulq(c[2], a[i - 3] + a[i + 3]);
            a[i] = v > 0 ? v : 0;
        }
    }
}

int32_t tb_log2_q24(int32_t v, const int32_t *log2t) {
    uint32_t M = (uint32_t)v;                   // v << 0: n = 31 before the shifts
    int32_t n = 31;
    TB_NORM(M, n);
    return log2n(M, n, log2t);
}

void tb_wave_ll(const int32_t *a, int32_t K, int32_t *invk, int32_t *ll, int64_t base,
                int32_t q, int64_t f, int64_t cut, int32_t ll_none, int32_t ll_max,
                const int32_t *log2t) {
    for (int32_t k = 1; k < K; k++) {
        invk[k] = q;
        int32_t p = a[k + 2];
        if (p <= 0) {
            ll[k] = ll_none;
            continue;
        }
        int64_t l2 = (int64_t)(tb_log2_q24(p, log2t) >> 1) + base + f;
        ll[k] = l2 < cut ? ll_none : (l2 > ll_max ? ll_max : (int32_t)l2);
    }
}
