// The brush painter's integer loops in C (device/texel/gen/brush.py: draws,
// fill + ifft, ola_emit, leakage's sweeps), for the texelpad firmware's
// _texelcore module (modtexelcore.c, natmod.c) and for the host's tests through
// ctypes (tests/support/core_c.py): the same integers as the Python
// loops, statement for statement. Plain C99, no MicroPython headers.
// Assumes two's complement int32_t and an arithmetic >> on negative values
// (gcc and arm-none-eabi-gcc), as Python's >> is.
#ifndef TEXELPAD_BRUSH_CORE_H
#define TEXELPAD_BRUSH_CORE_H
#include <stdint.h>

#define TB_WINDOW 192
#define TB_HOP 48
#define TB_K 97
#define TB_WORK (4 * TB_K + 3 * TB_WINDOW)     // tb_paint's work buffer, int32 values

// The tables the Python module holds (gen/brush.py, gen/plan_int_tables.py),
// handed in by the caller so there is one copy of each.
typedef struct {
    const int32_t *exp_tab;     // plan_int_tables.table(): EXP_HI at 0, EXP_MID at 256
    const int32_t *log2t;       // brush.LOG2 (257)
    const int16_t *phase;       // brush.PHASE (256), Q14
    const int16_t *tw;          // brush.TW (192), Q12
    const int32_t *hann;        // brush.HANN (192), Q9
    const int32_t *pos;         // brush.POS (192)
} tb_tables;

// One window's K draws (brush.draws): st = the generator's state as eight
// 16-bit halves (gen/rng.py), updated; ll in Q24 octaves (brush.LL_NONE: 0).
void tb_draws(uint16_t st[8], const int32_t *invk, const int32_t *ll, int32_t sign,
              int32_t off, const tb_tables *t, int32_t *mag, int32_t *ph);

// Two windows' doubled frames (brush.fill, brush.ifft) into z, 2 * TB_WINDOW
// values: brush.ifft's re[i] at z[2 i], its im[i] at z[2 i + 1].
void tb_frames(const int32_t *ma, const int32_t *pa, const int32_t *mb, const int32_t *pb,
               const tb_tables *t, int32_t *z);

// brush.paint's loop: n samples into chunks (chunk i holds samples
// i << chunk_bits ..), from the generator's state after the setup; work:
// TB_WORK int32 values of scratch.
void tb_paint(uint16_t st[8], const int32_t *invk, const int32_t *ll, int32_t sign,
              int32_t off, const tb_tables *t, int32_t n, uint16_t *const *chunks,
              int32_t chunk_bits, int32_t *work);

// brush.windows(n): how many windows (an even count) paint n samples
int32_t tb_windows(int32_t n);

// TB_K * windows generator steps, their draws dropped (brush_parts.Painting): st
// becomes the state that many windows on
void tb_skip(uint16_t st[8], int32_t steps);

// tb_paint's loop over windows w_from .. w_to - 1 (both even; st: the
// state at window w_from, updated), onto ring (TB_WINDOW partial sums: zeros
// for a fresh start, or what the call before that ended at w_from left) and
// into the samples from lo_emit on (48 w_from for a fresh start past window 0:
// below it the ring lacks the windows before w_from). work: TB_WORK values,
// of which the ring part is not used. The same integers as tb_paint in any
// order of such calls (brush_parts.Painting; tests/brush/test_paint_parts.py).
void tb_paint_range(uint16_t st[8], const int32_t *invk, const int32_t *ll, int32_t sign,
                    int32_t off, const tb_tables *t, int32_t n, uint16_t *const *chunks,
                    int32_t chunk_bits, int32_t *work, int32_t *ring, int32_t w_from,
                    int32_t w_to, int32_t lo_emit);

// brush.leakage's sweeps over a padded array (3 values each side): a[i] =
// max(0, q[i] - C1 (a[i-1] + a[i+1]) - C2 (..) - C3 (..)), Q14 coefficients.
void tb_leak(const int32_t *q, int32_t *a, int32_t n, int32_t sweeps, const int32_t *c);

// brush._mulq: leakage's Q14 product g * x / 2^14 for x >= 0 (x < 2^31), every
// partial product below 2^31
static inline int32_t tb_mulq(int32_t g, int32_t x) {
    return (x >> 14) * g + (((x & 16383) * g) >> 14);
}

// brush.log2_q24: round-ish(log2(v) * 2^24) for 1 <= v < 2^30 (log2t: brush.LOG2)
int32_t tb_log2_q24(int32_t v, const int32_t *log2t);

// brush._waves_ll for a brush of one shape (_shape's q, f, cut for every wave):
// invk[k] = q and ll[k] from the power a[k + 2] (Q28), k = 1 .. K-1 - ll_none
// for none, else (log2_q24(p) >> 1) + base + f, below cut ll_none, above
// ll_max ll_max (in 64 bits: base may be any 32-bit int)
void tb_wave_ll(const int32_t *a, int32_t K, int32_t *invk, int32_t *ll, int64_t base,
                int32_t q, int64_t f, int64_t cut, int32_t ll_none, int32_t ll_max,
                const int32_t *log2t);

#endif
