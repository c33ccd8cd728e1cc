// Texture format 2 in C: the per-texel plan loop (device/texel/gen/plan_int.py
// texels_py; plan_int_viper.texels is the same compiled by viper) and the int
// engine's fill (gen/engine_int.py _fill_py), statement for statement: the
// same integers on every build of this core (the texelpad firmware's user C
// module, the dynamic native .mpy of natmod.c, CPython through ctypes:
// tests/support/core_c.py). Plain C99, no MicroPython headers. Every bound is
// plan_int.py's: each value stays below 2^31 in magnitude, so int32_t holds
// it; assumes an arithmetic >> on negative values (gcc, arm-none-eabi-gcc), as
// Python's >> is.
#ifndef TEXELPAD_TEXEL_CORE_H
#define TEXELPAD_TEXEL_CORE_H
#include <stdint.h>

// plan_int.texels_py: st = seeded(seed) (10 halves; st[8], st[9] get the
// start phase's draw), tab = plan_int_tables.table() (EXP_HI at 0, EXP_MID at
// 256, NORM at 512). Fills t28/d28 (count each), ys if keep & 2, zs if
// keep & 1; returns the number of texels above Nyquist.
int32_t tc_texels(uint16_t st[10], int32_t count, int32_t L, int32_t mu, int32_t sigma,
                  int32_t q, int32_t dcap, const int32_t *tab, int32_t *t28, int32_t *d28,
                  int32_t *ys, int32_t *zs, int32_t keep);

// PlanInt.__init__'s integers (gen/plan_int.py) from the parameters' grid
// integers (gen/grid.py mdb: millidecibels; cap_mc the band limit in
// milli-c/mm, 0 for none): out = mu, sigma, q, dcap. And seeded(seed)'s 10
// halves into st (gen/rng.py SEED_CONSTS; the last two 0).
void tc_plan_consts(int32_t pitch_mdb, int32_t irreg_mdb, int32_t quant_mdb, int32_t cap_mc,
                    const int32_t *tab, int32_t out[4]);
void tc_seeded(uint32_t seed, uint16_t st[10]);

// gen/options.py apply_int's integer work on a plan the loop made: with
// TC_OPT_BOUND, redraw_int (every texel below the bound dmin redrawn from the
// stream st - Rng(seed, consts=REDRAW_CONSTS) after its warm-up, 8 halves,
// left where it ends - up to `tries` draws, none with TC_OPT_HOPELESS) and,
// when any was, tail_int (t28/d28 and the count above Nyquist from ys);
// with TC_OPT_RESET every t28 = t28[0]. out: redrawn, at_min, above (out[2]
// comes in as the loop's count, kept when nothing was redrawn).
#define TC_OPT_BOUND 1
#define TC_OPT_HOPELESS 2
#define TC_OPT_RESET 4
void tc_options(uint16_t st[8], int32_t count, int32_t L, int32_t mu, int32_t sigma, int32_t q,
                int32_t dcap, int32_t dmin, int32_t flags, int32_t tries, const int32_t *tab,
                int32_t *ys, int32_t *t28, int32_t *d28, int32_t out[3]);

// gen/options.py apply_int on a plan the loop made, set up as _apply_c sets it
// up: the redraw stream (gen/rng.py Rng(seed, consts=REDRAW_CONSTS) after its
// WARMUP draws), d_min(min_mc), the hopeless test (SKIP_HOPELESS) and
// MIN_TRIES tries, then tc_options. min_mc: grid.mdb(min_cpmm), < 0 for no
// bound; reset: phase "reset". k: tc_plan_consts' mu, sigma, q, dcap; above:
// the loop's count above Nyquist; out as tc_options'. The C plan
// (texelcore_api.h plan) runs it, so a board plays seed 001's options
// without importing gen/options.py (10.8 ms at a Pico's first such push).
#define TC_MIN_TRIES 64         // gen/options.py MIN_TRIES (tests/gen/test_texel_core.py)
void tc_plan_options(uint32_t seed, int32_t min_mc, int32_t reset, int32_t count, int32_t L,
                     const int32_t k[4], const int32_t *tab, int32_t *ys, int32_t *t28,
                     int32_t *d28, int32_t above, int32_t out[3]);

// engine_int._fill_py: samples a..b-1 of out from phase t (2^-28 turns) and
// step d; tab = sine_table.table() (1,025 Q16 values); g = gain in Q14.
// Returns the phase after the last sample.
int32_t tc_fill(uint16_t *out, int32_t a, int32_t b, int32_t t, int32_t d,
                const uint16_t *tab, int32_t g);

// engine_int.render_u16's loop: every texel's fill, the last cut at n.
void tc_render(uint16_t *out, int32_t n, int32_t L, int32_t count, const int32_t *t28,
               const int32_t *d28, const uint16_t *tab, int32_t g);

// kinds/samples.py fill_chunks (its _loop, statement for statement): the n
// positions of a samples region into chunks of 2^bits values, from m values:
// tile (value i mod m at position i) or, with stretch, linear interpolation
// with the 14-bit weight round(r * 2^14 / (n-1)) (floor(r * 2^15 / (n-1)),
// in int64 past 32,769 positions, as Python's two exact steps).
void tc_samples(uint16_t **chunks, int32_t bits, int32_t n, const uint16_t *vals, int32_t m,
                int32_t stretch);

// gen/reference_viper.py fill, statement for statement: n values of a sum of
// m sines (the references 2sin, 3sin, 4sin) into out as uint16. ph: 2m words,
// sine j's table step and remainder, carried to the next call; steps: 2m
// words, what a sample adds to them; tab = sine_table.table(); a0, ws, rq:
// reference_viper.CONSTANTS. The remainder e = x*2^16 - u*ws in int64 (viper's
// 32-bit words wrap there and its difference is exact: the same integer).
void tc_sines(uint16_t *out, int32_t n, const int32_t *steps, int32_t *ph, int32_t m,
              const uint16_t *tab, int32_t a0, int32_t ws, int32_t rq);

#endif
