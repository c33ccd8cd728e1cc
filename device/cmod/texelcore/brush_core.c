// See brush_core.h. Every bound is device/texel/gen/brush.py's: magnitudes
// below 2^14, FFT values below 2^19, so every product here is below 2^31.
#include "brush_core.h"

#define LL_NONE (-(3 << 29))

static int32_t log2q(uint32_t v, const int32_t *t) {
    // brush.log2_q24 (1 <= v < 2^30): the top bit's position (found by
    // halving, as the Python does: a Cortex-M0+ has no CLZ and libgcc's takes
    // longer), then LOG2
    int32_t n = 0;
    uint32_t w = v;
    if (w >= 65536) {
        w >>= 16;
        n += 16;
    }
    if (w >= 256) {
        w >>= 8;
        n += 8;
    }
    if (w >= 16) {
        w >>= 4;
        n += 4;
    }
    if (w >= 4) {
        w >>= 2;
        n += 2;
    }
    if (w >= 2) {
        n += 1;
    }
    uint32_t m = v << (29 - n);
    int32_t i = (int32_t)((m >> 21) & 0xFF);
    int32_t lo = t[i];
    return (n << 24) + lo + (((t[i + 1] - lo) * (int32_t)((m >> 9) & 0xFFF)) >> 12);
}

static int32_t mul28(int32_t a, int32_t b) {
    // plan_int.mul28: round(a * b / 2^28) in 15-bit limbs
    int32_t a1 = a >> 15, a0 = a & 0x7FFF, b1 = b >> 15, b0 = b & 0x7FFF;
    int32_t s = a1 * b0 + a0 * b1 + ((a0 * b0) >> 15) + 4096;
    return ((a1 * b1) << 2) + (s >> 13);
}

static int32_t round_exp2(int32_t z, int32_t emax, const int32_t *tab) {
    int32_t e = z >> 24;
    if (e >= emax) {
        return 1 << emax;
    }
    if (e < -2) {
        return 0;
    }
    int32_t r = z & 0xFFFFFF;
    int32_t m = mul28(mul28(tab[r >> 16], tab[256 + ((r >> 8) & 0xFF)]),
                      (1 << 28) + (((r & 0xFF) * 726817 + 32768) >> 16));   // LN2_Q20
    return (m + (1 << (27 - e))) >> (28 - e);
}

void tb_draws(uint16_t st[8], const int32_t *invk, const int32_t *ll, int32_t sign,
              int32_t off, const tb_tables *t, int32_t *mag, int32_t *ph) {
    uint32_t a = ((uint32_t)st[0] << 16) | st[1], b = ((uint32_t)st[2] << 16) | st[3];
    uint32_t c = ((uint32_t)st[4] << 16) | st[5], d = ((uint32_t)st[6] << 16) | st[7];
    int32_t s = 0;
    for (int k = 0; k < TB_K; k++) {
        // xoshiro128++ (gen/rng.py): rotl(a + d, 7) + a
        uint32_t x = a + d;
        x = ((x << 7) | (x >> 25)) + a;
        uint32_t u = b << 9;
        c ^= a;
        d ^= b;
        b ^= c;
        a ^= d;
        c ^= u;
        d = (d << 11) | (d >> 21);
        ph[k] = (int32_t)(x & 0xFF);
        int32_t v = 0;
        if (ll[k] != LL_NONE) {
            uint32_t x24 = x >> 8;
            int32_t q = 419430400 - log2q(2 * x24 + 1, t->log2t);     // 25 * 2^24
            if (q < 1) {
                q = 1;
            }
            int32_t L = (log2q((uint32_t)q, t->log2t) - 402653184 - 8871228) >> 4;
            int32_t hp = (L >> 12) * invk[k];
            if (hp >= -33554432) {
                if (hp > 87031808) {        // 83 octaves
                    hp = 87031808;
                }
                // * 16, not << 4: hp may be negative (C99 leaves that shift undefined)
                int32_t z = ll[k] + hp * 16 + (((L & 0xFFF) * invk[k]) >> 8);
                v = round_exp2(z, k == 0 ? 16 : 14, t->exp_tab);
            }
        }
        if (k == 0) {
            v = sign * v + off;
            mag[0] = v > 32768 ? 32768 : (v < -32768 ? -32768 : v);    // MEAN_CLIP
        } else {
            if (k == TB_K - 1) {
                v = (v + 1) >> 1;               // the Nyquist, halved
            }
            mag[k] = v;
            s += v;
        }
    }
    while (s > 65536) {                         // SUM_MAX
        s = 0;
        for (int k = 1; k < TB_K; k++) {
            mag[k] >>= 1;
            s += mag[k];
        }
    }
    st[0] = a >> 16; st[1] = a & 0xFFFF; st[2] = b >> 16; st[3] = b & 0xFFFF;
    st[4] = c >> 16; st[5] = c & 0xFFFF; st[6] = d >> 16; st[7] = d & 0xFFFF;
}

static inline void cmul(int32_t br, int32_t bi, int32_t tw_i, const int16_t *tw,
                        int32_t *xr, int32_t *xi) {
    // (br + i bi) e^(2 pi i tw_i / 192), 0 <= tw_i < 192; twiddles 1 and i
    // are exact in this rounding, so they skip the products (no division
    // either: the sine's index by a branch)
    if (tw_i == 0) {
        *xr = br;
        *xi = bi;
        return;
    }
    if (tw_i == 48) {
        *xr = -bi;
        *xi = br;
        return;
    }
    int32_t wr = tw[tw_i], wi = tw[tw_i < 48 ? tw_i + 144 : tw_i - 48];
    *xr = ((br * wr + 2048) >> 12) - ((bi * wi + 2048) >> 12);
    *xi = ((br * wi + 2048) >> 12) + ((bi * wr + 2048) >> 12);
}

void tb_frames(const int32_t *ma, const int32_t *pa, const int32_t *mb, const int32_t *pb,
               const tb_tables *t, int32_t *re, int32_t *im) {
    const int16_t *P = t->phase;
    const int32_t *pos = t->pos;
    re[0] = 2 * ma[0];
    im[0] = 2 * mb[0];
    for (int k = 1; k < TB_K - 1; k++) {
        int32_t m = ma[k], p = pa[k];
        int32_t ca = (m * P[p] + 8192) >> 14, sa = (m * P[(p - 64) & 255] + 8192) >> 14;
        m = mb[k];
        p = pb[k];
        int32_t cb = (m * P[p] + 8192) >> 14, sb = (m * P[(p - 64) & 255] + 8192) >> 14;
        int32_t j = pos[k];
        re[j] = ca - sb;
        im[j] = sa + cb;
        j = pos[TB_WINDOW - k];
        re[j] = ca + sb;
        im[j] = cb - sa;
    }
    int32_t j = pos[TB_K - 1];
    re[j] = 2 * (pa[TB_K - 1] < 128 ? ma[TB_K - 1] : -ma[TB_K - 1]);
    im[j] = 2 * (pb[TB_K - 1] < 128 ? mb[TB_K - 1] : -mb[TB_K - 1]);
    // the same butterflies as brush.ifft in another order: each twiddle once
    // for all the groups that use it (j outer), the exact ones (1, i) apart
    const int16_t *tw = t->tw;
    for (int s = 2, ts = 96; s <= 64; s <<= 1, ts >>= 1) {
        int half = s >> 1;
        for (int jj = 0; jj < half; jj++) {
            int32_t tt = jj * ts;
            int32_t wr = tw[tt], wi = tw[tt < 48 ? tt + 144 : tt - 48];
            for (int ia = jj; ia < 192; ia += s) {
                int ib = ia + half;
                int32_t br = re[ib], bi = im[ib], xr, xi;
                if (tt == 0) {
                    xr = br;
                    xi = bi;
                } else if (tt == 48) {
                    xr = -bi;
                    xi = br;
                } else {
                    xr = ((br * wr + 2048) >> 12) - ((bi * wi + 2048) >> 12);
                    xi = ((br * wi + 2048) >> 12) + ((bi * wr + 2048) >> 12);
                }
                int32_t ar = re[ia], ai = im[ia];
                re[ib] = ar - xr;
                im[ib] = ai - xi;
                re[ia] = ar + xr;
                im[ia] = ai + xi;
            }
        }
    }
    for (int n = 0; n < 64; n++) {
        int32_t f0r = re[n], f0i = im[n], f1r, f1i, f2r, f2i;
        cmul(re[64 + n], im[64 + n], n, t->tw, &f1r, &f1i);
        cmul(re[128 + n], im[128 + n], 2 * n, t->tw, &f2r, &f2i);
        int32_t sr = f1r + f2r, si = f1i + f2i;
        int32_t tr = ((f1r - f2r) * 3547 + 2048) >> 12, ti = ((f1i - f2i) * 3547 + 2048) >> 12;
        int32_t hr = f0r - (sr >> 1), hi = f0i - (si >> 1);
        re[n] = f0r + sr;
        im[n] = f0i + si;
        re[64 + n] = hr - ti;
        im[64 + n] = hi + tr;
        re[128 + n] = hr + ti;
        im[128 + n] = hi - tr;
    }
}

void tb_paint(uint16_t st[8], const int32_t *invk, const int32_t *ll, int32_t sign,
              int32_t off, const tb_tables *t, int32_t n, uint16_t *const *chunks,
              int32_t chunk_bits, int32_t *work) {
    // the work arrays in the caller's buffer (TB_WORK values): 3.8 KB would be
    // half a Pico's 8 KB stack, which MicroPython's stack check does not see
    int32_t *ma = work, *pa = ma + TB_K, *mb = pa + TB_K, *pb = mb + TB_K;
    int32_t *re = pb + TB_K, *im = re + TB_WINDOW, *ring = im + TB_WINDOW;
    int32_t mask = (1 << chunk_bits) - 1;
    for (int i = 0; i < TB_WINDOW; i++) {
        ring[i] = 0;
    }
    int32_t w = (n + TB_HOP - 1) / TB_HOP + 3;
    w += w & 1;
    int32_t start = -3 * TB_HOP;
    int32_t r0 = TB_WINDOW - 3 * TB_HOP;       // start mod WINDOW
    for (int32_t pair = 0; pair < w / 2; pair++) {
        tb_draws(st, invk, ll, sign, off, t, ma, pa);
        tb_draws(st, invk, ll, sign, off, t, mb, pb);
        tb_frames(ma, pa, mb, pb, t, re, im);
        for (int which = 0; which < 2; which++) {
            const int32_t *fr = which ? im : re;
            int32_t r = r0;
            for (int i = 0; i < TB_WINDOW; i++) {
                ring[r] += (fr[i] * t->hann[i]) >> 10;
                if (++r == TB_WINDOW) {
                    r = 0;
                }
            }
            r = r0;
            for (int i = 0; i < TB_HOP; i++) {
                int32_t p = start + i;
                if (p >= 0 && p < n) {
                    int32_t v = ring[r] >> 1;
                    chunks[p >> chunk_bits][p & mask] = (uint16_t)(
                        v <= 0 ? 0 : (v >= 8192 ? 65535 : (v * 65535 + 4096) >> 13));
                }
                ring[r] = 0;
                r++;
            }
            start += TB_HOP;
            r0 = r0 + TB_HOP < TB_WINDOW ? r0 + TB_HOP : r0 + TB_HOP - TB_WINDOW;
        }
    }
}

static inline int32_t mulq(int32_t g, int32_t x) {
    // brush.leakage's Q14 product for x >= 0 (x < 2^31): below 2^31 throughout
    return (x >> 14) * g + (((x & 16383) * g) >> 14);
}

void tb_leak(const int32_t *q, int32_t *a, int32_t n, int32_t sweeps, const int32_t *c) {
    for (int32_t s = 0; s < sweeps; s++) {
        for (int32_t i = 3; i < n + 3; i++) {
            int32_t v = q[i] - mulq(c[0], a[i - 1] + a[i + 1]) - mulq(c[1], a[i - 2] + a[i + 2])
                        - mulq(c[2], a[i - 3] + a[i + 3]);
            a[i] = v > 0 ? v : 0;
        }
    }
}
