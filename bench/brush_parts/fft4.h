// bench/brush_parts.py's prototype (not texelpad's painter): a 192-point inverse complex FFT as three
// 64-point radix-4 DIT transforms (digit-reversed input) and the same radix-3
// pass as brush_core.c, Q12 twiddles, each product rounded on its own.
#include <stdint.h>
#define R12(p) (((p) + 2048) >> 12)
static inline int m192(int x) { while (x >= 192) x -= 192; return x; }
// z: 192 complex (interleaved), sub-transform b at z + 128 b ints, input in
// base-4 digit-reversed order; tw: cos table of 192 (Q12), sin = tw[(t + 144) % 192]
static inline void cm(int32_t br, int32_t bi, int32_t wr, int32_t wi, int32_t *xr, int32_t *xi) {
    *xr = R12(br * wr) - R12(bi * wi);
    *xi = R12(br * wi) + R12(bi * wr);
}
static void fft64_r4(int32_t *z, const int16_t *tw) {
    // stage 1: span 1 (16 butterflies, twiddles 1), inverse: +i
    for (int g = 0; g < 64; g += 4) {
        int32_t *p = z + 2 * g;
        int32_t ar = p[0], ai = p[1], br = p[2], bi = p[3], cr = p[4], ci = p[5], dr = p[6], di = p[7];
        int32_t s0r = ar + cr, s0i = ai + ci, s1r = ar - cr, s1i = ai - ci;
        int32_t s2r = br + dr, s2i = bi + di, s3r = br - dr, s3i = bi - di;
        p[0] = s0r + s2r; p[1] = s0i + s2i;
        p[4] = s0r - s2r; p[5] = s0i - s2i;
        p[2] = s1r - s3i; p[3] = s1i + s3r;
        p[6] = s1r + s3i; p[7] = s1i - s3r;
    }
    // stages 2, 3: spans 4, 16
    for (int span = 4, ts = 12; span < 64; span <<= 2, ts >>= 2) {
        int step = 4 * span;
        for (int j = 0; j < span; j++) {
            int32_t w1r = tw[j * ts], w1i = tw[m192(j * ts + 144)];
            int32_t w2r = tw[2 * j * ts], w2i = tw[m192(2 * j * ts + 144)];
            int32_t w3r = tw[m192(3 * j * ts)], w3i = tw[m192(3 * j * ts + 144)];
            for (int g = j; g < 64; g += step) {
                int32_t *a = z + 2 * g, *b = a + 2 * span, *c = b + 2 * span, *d = c + 2 * span;
                int32_t ar = a[0], ai = a[1], br, bi, cr, ci, dr, di;
                cm(b[0], b[1], w1r, w1i, &br, &bi);
                cm(c[0], c[1], w2r, w2i, &cr, &ci);
                cm(d[0], d[1], w3r, w3i, &dr, &di);
                int32_t s0r = ar + cr, s0i = ai + ci, s1r = ar - cr, s1i = ai - ci;
                int32_t s2r = br + dr, s2i = bi + di, s3r = br - dr, s3i = bi - di;
                a[0] = s0r + s2r; a[1] = s0i + s2i;
                c[0] = s0r - s2r; c[1] = s0i - s2i;
                b[0] = s1r - s3i; b[1] = s1i + s3r;
                d[0] = s1r + s3i; d[1] = s1i - s3r;
            }
        }
    }
}
static void fft192_r4(int32_t *z, const int16_t *tw) {
    fft64_r4(z, tw);
    fft64_r4(z + 128, tw);
    fft64_r4(z + 256, tw);
    for (int n = 0; n < 64; n++) {
        int32_t *w = z + 2 * n;
        int32_t f1r, f1i, f2r, f2i;
        cm(w[128], w[129], tw[n], tw[m192(n + 144)], &f1r, &f1i);
        cm(w[256], w[257], tw[2 * n], tw[m192(2 * n + 144)], &f2r, &f2i);
        int32_t f0r = w[0], f0i = w[1];
        int32_t sr = f1r + f2r, si = f1i + f2i;
        int32_t tr = ((f1r - f2r) * 3547 + 2048) >> 12, ti = ((f1i - f2i) * 3547 + 2048) >> 12;
        int32_t hr = f0r - (sr >> 1), hi = f0i - (si >> 1);
        w[0] = f0r + sr; w[1] = f0i + si;
        w[128] = hr - ti; w[129] = hi + tr;
        w[256] = hr + ti; w[257] = hi - tr;
    }
}
// table-driven Weibull draws: g = log2 of (-ln u)^(1/k') from a 1025-entry table
// per shape (Q16 octaves, linear between), exp2 from a 257-entry table (Q14
// mantissa): the magnitude (Q13), for K draws of one window
static void draws_tab(uint32_t st[4], const int32_t *gt, const int32_t *ll, const uint16_t *et,
                      int32_t *mag, int32_t *ph, int K) {
    uint32_t a = st[0], b = st[1], c = st[2], d = st[3];
    for (int k = 0; k < K; k++) {
        uint32_t x = a + d;
        x = ((x << 7) | (x >> 25)) + a;
        uint32_t u = b << 9;
        c ^= a; d ^= b; b ^= c; a ^= d; c ^= u;
        d = (d << 11) | (d >> 21);
        ph[k] = (int32_t)(x & 0xFF);
        uint32_t i = x >> 22, f = (x >> 12) & 1023;
        int32_t g0 = gt[i];
        int32_t g = g0 + (((gt[i + 1] - g0) * (int32_t)f) >> 10);
        int32_t z = ll[k] + g;                  // Q16 octaves
        int32_t e = z >> 16;
        if (e < -1) { mag[k] = 0; continue; }
        if (e > 14) e = 14;
        uint32_t m = et[(z >> 8) & 255];        // 2^frac in Q15 (32768..65535)
        mag[k] = (int32_t)((m << (e + 1)) >> 16);
    }
    st[0] = a; st[1] = b; st[2] = c; st[3] = d;
}
