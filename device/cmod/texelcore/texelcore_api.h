// _texelcore's functions, shared by its two MicroPython builds: the texelpad
// firmware's user C module (modtexelcore.c, after py/runtime.h) and the
// dynamic native module (natmod.c, after py/dynruntime.h; texelpad deploy
// installs it on stock boards). The includer defines TC_RAISE_BUF(what, have,
// need) and TC_FREE(ptr, bytes), the two things the two APIs spell apart.
// Arguments are the arrays the Python callers already hold; every size is
// checked before the C core touches it. What allocates on the MicroPython heap:
// paint's 3.9 KB work buffer and plan's log pitches (both freed before they
// return), and the arrays u16, plan and install return.
#include <string.h>
#include "py/objarray.h"
#include "brush_core.h"
#include "texel_core.h"
#include "refresh_core.h"
#define TC_FLOAT mp_float_t
#include "check_core.h"

// The functions and arguments below, as texel.compat.CORE_API expects them:
// bump both with any change to an existing function's arguments or results, so
// a board's older native module is not used. A function added (install) needs
// no bump: its callers look it up (getattr) and use the Python where an older
// module lacks it; a function that now takes more (plan: the options) neither,
// where the older one answered None and the Python decided.
#define TC_API 7                // 7: W_ROW (word 14, the refresh's last row) and W_BASE 0 on 32-bit boards; 6: the STM32 ADC
#define MAX_CHUNKS 128          // 65,536 values of 512 (a full screen is 38 chunks)
#define TC_U16_VALS 19200       // kinds/samples.py MAX_SAMPLES
#define TC_TAB_I32 (512 + 32 * 32 + 1)     // plan_int_tables.table(): EXP_HI, EXP_MID, NORM
#define TC_SINE_U16 1025                  // sine_table.table()

static void *tc_buf(mp_obj_t o, size_t want, int flags, const char *what) {
    mp_buffer_info_t b;
    mp_get_buffer_raise(o, &b, flags);
    if (b.len < want) {
        TC_RAISE_BUF(what, b.len, want);
    }
    return b.buf;
}

// paint's and paint_part's first 14 arguments, checked
typedef struct {
    uint16_t *st;
    const int32_t *invk, *ll;
    int32_t sign, off, n, bits;
    uint16_t *chunks[MAX_CHUNKS];
    tb_tables t;
} tc_paint_args;

static void tc_paint_read(const mp_obj_t *args, tc_paint_args *a) {
    a->st = tc_buf(args[0], 16, MP_BUFFER_RW, "st");
    a->invk = tc_buf(args[1], 4 * TB_K, MP_BUFFER_READ, "invk");
    a->ll = tc_buf(args[2], 4 * TB_K, MP_BUFFER_READ, "ll");
    a->sign = mp_obj_get_int(args[3]);
    a->off = mp_obj_get_int(args[4]);
    int32_t n = mp_obj_get_int(args[5]);
    size_t nch;
    mp_obj_t *items;
    mp_obj_get_array(args[6], &nch, &items);
    int32_t bits = mp_obj_get_int(args[7]);
    if (n < 0 || bits < 1 || bits > 30 || nch > MAX_CHUNKS ||
        (size_t)((n + (1 << bits) - 1) >> bits) > nch) {
        mp_raise_ValueError(MP_ERROR_TEXT("paint: n, chunks and chunk_bits disagree"));
    }
    for (size_t i = 0; i < nch; i++) {
        int32_t left = n - ((int32_t)i << bits);
        int32_t need = left < (1 << bits) ? left : (1 << bits);
        a->chunks[i] = tc_buf(items[i], 2 * (size_t)(need > 0 ? need : 0), MP_BUFFER_WRITE,
                              "chunk");
    }
    a->n = n;
    a->bits = bits;
    a->t.exp_tab = tc_buf(args[8], 4 * 512, MP_BUFFER_READ, "tab");
    a->t.log2t = tc_buf(args[9], 4 * 257, MP_BUFFER_READ, "log2t");
    a->t.phase = tc_buf(args[10], 2 * 256, MP_BUFFER_READ, "phase");
    a->t.tw = tc_buf(args[11], 2 * TB_WINDOW, MP_BUFFER_READ, "tw");
    a->t.hann = tc_buf(args[12], 4 * TB_WINDOW, MP_BUFFER_READ, "hann");
    a->t.pos = tc_buf(args[13], 4 * TB_WINDOW, MP_BUFFER_READ, "pos");
}

// paint(st, invk, ll, sign, off, n, chunks, chunk_bits, tab, log2t, phase, tw, hann, pos):
// texel.gen.brush._paint_c
static mp_obj_t tc_paint_fn(size_t n_args, const mp_obj_t *args) {
    tc_paint_args a;
    tc_paint_read(args, &a);
    int32_t *work = (int32_t *)m_malloc(4 * TB_WORK);  // on the heap, not the 8 KB stack
    tb_paint(a.st, a.invk, a.ll, a.sign, a.off, &a.t, a.n, a.chunks, a.bits, work);
    TC_FREE(work, 4 * TB_WORK);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_paint_obj, 14, 14, tc_paint_fn);

// paint_part(st, ..., pos (paint's 14), ring, w_from, w_to, lo_emit, work):
// texel.gen.brush_parts.Painting - windows w_from .. w_to - 1 onto ring (int32,
// WINDOW values) from the state st is at window w_from (brush_core.h
// tb_paint_range); work: the caller's int32 array of TB_WORK values (kept
// between the calls of one painting: no allocation here)
static mp_obj_t tc_paint_part_fn(size_t n_args, const mp_obj_t *args) {
    tc_paint_args a;
    tc_paint_read(args, &a);
    int32_t *ring = tc_buf(args[14], 4 * TB_WINDOW, MP_BUFFER_RW, "ring");
    int32_t w_from = mp_obj_get_int(args[15]);
    int32_t w_to = mp_obj_get_int(args[16]);
    int32_t lo_emit = mp_obj_get_int(args[17]);
    int32_t *work = tc_buf(args[18], 4 * TB_WORK, MP_BUFFER_RW, "work");
    if (w_from < 0 || w_from > w_to || w_to > tb_windows(a.n) || (w_from | w_to) & 1 ||
        lo_emit < 0 || lo_emit > a.n) {         // (lo_emit - start must not overflow)
        mp_raise_ValueError(MP_ERROR_TEXT("paint_part: windows or lo_emit out of range"));
    }
    tb_paint_range(a.st, a.invk, a.ll, a.sign, a.off, &a.t, a.n, a.chunks, a.bits, work, ring,
                   w_from, w_to, lo_emit);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_paint_part_obj, 19, 19, tc_paint_part_fn);

// skip(st, steps): brush_parts.Painting - the generator's state steps on (tb_skip)
static mp_obj_t tc_skip_fn(mp_obj_t st_in, mp_obj_t steps_in) {
    uint16_t *st = tc_buf(st_in, 16, MP_BUFFER_RW, "st");
    mp_int_t steps = mp_obj_get_int(steps_in);
    if (steps < 0 || steps > (1 << 24)) {
        mp_raise_ValueError(MP_ERROR_TEXT("skip: steps out of range"));
    }
    tb_skip(st, (int32_t)steps);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_2(tc_skip_obj, tc_skip_fn);

// leak(q, a, n, sweeps, c): texel.gen.brush.leakage's sweeps
static mp_obj_t tc_leak_fn(size_t n_args, const mp_obj_t *args) {
    int32_t n = mp_obj_get_int(args[2]);
    if (n < 0 || n > 4096) {
        mp_raise_ValueError(MP_ERROR_TEXT("leak: n out of range"));
    }
    const int32_t *q = tc_buf(args[0], 4 * (size_t)(n + 6), MP_BUFFER_READ, "q");
    int32_t *a = tc_buf(args[1], 4 * (size_t)(n + 6), MP_BUFFER_RW, "a");
    const int32_t *c = tc_buf(args[4], 12, MP_BUFFER_READ, "c");
    tb_leak(q, a, n, mp_obj_get_int(args[3]), c);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_leak_obj, 5, 5, tc_leak_fn);

// texels(st, count, L, mu, sigma, q, dcap, tab, t28, d28, ys, zs, keep) -> above:
// texel.gen.plan_int.texels_py
static mp_obj_t tc_texels_fn(size_t n_args, const mp_obj_t *args) {
    int32_t count = mp_obj_get_int(args[1]);
    int32_t L = mp_obj_get_int(args[2]);
    int32_t keep = mp_obj_get_int(args[12]);
    if (count < 0 || count > (1 << 24) || L < 1 || L >= (1 << 21)) {
        mp_raise_ValueError(MP_ERROR_TEXT("texels: count or L out of range"));
    }
    size_t want = 4 * (size_t)count;
    uint16_t *st = tc_buf(args[0], 20, MP_BUFFER_RW, "st");
    const int32_t *tab = tc_buf(args[7], 4 * TC_TAB_I32, MP_BUFFER_READ, "tab");
    int32_t *t28 = tc_buf(args[8], want, MP_BUFFER_WRITE, "t28");
    int32_t *d28 = tc_buf(args[9], want, MP_BUFFER_WRITE, "d28");
    int32_t *ys = tc_buf(args[10], keep & 2 ? want : 0, MP_BUFFER_WRITE, "ys");
    int32_t *zs = tc_buf(args[11], keep & 1 ? want : 0, MP_BUFFER_WRITE, "zs");
    return mp_obj_new_int(tc_texels(st, count, L, mp_obj_get_int(args[3]),
                                    mp_obj_get_int(args[4]), mp_obj_get_int(args[5]),
                                    mp_obj_get_int(args[6]), tab, t28, d28, ys, zs, keep));
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_texels_obj, 13, 13, tc_texels_fn);

// options(st, count, L, mu, sigma, q, dcap, dmin, flags, tries, tab, ys, t28, d28, out):
// texel.gen.options.apply_int's integer work (tc_options)
static mp_obj_t tc_options_fn(size_t n_args, const mp_obj_t *args) {
    int32_t count = mp_obj_get_int(args[1]);
    int32_t L = mp_obj_get_int(args[2]);
    int32_t tries = mp_obj_get_int(args[9]);
    if (count < 1 || count > (1 << 24) || L < 1 || L >= (1 << 21) || tries < 0) {
        mp_raise_ValueError(MP_ERROR_TEXT("options: count, L or tries out of range"));
    }
    size_t want = 4 * (size_t)count;
    uint16_t *st = tc_buf(args[0], 16, MP_BUFFER_RW, "st");
    const int32_t *tab = tc_buf(args[10], 4 * TC_TAB_I32, MP_BUFFER_READ, "tab");
    int32_t *ys = tc_buf(args[11], want, MP_BUFFER_RW, "ys");
    int32_t *t28 = tc_buf(args[12], want, MP_BUFFER_RW, "t28");
    int32_t *d28 = tc_buf(args[13], want, MP_BUFFER_RW, "d28");
    int32_t *out = tc_buf(args[14], 12, MP_BUFFER_RW, "out");
    tc_options(st, count, L, mp_obj_get_int(args[3]), mp_obj_get_int(args[4]),
               mp_obj_get_int(args[5]), mp_obj_get_int(args[6]), mp_obj_get_int(args[7]),
               mp_obj_get_int(args[8]), tries, tab, ys, t28, d28, out);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_options_obj, 15, 15, tc_options_fn);

// fill(out, a, b, t, d, tab, g) -> t: texel.gen.engine_int._fill_py
static mp_obj_t tc_fill_fn(size_t n_args, const mp_obj_t *args) {
    mp_buffer_info_t o;
    mp_get_buffer_raise(args[0], &o, MP_BUFFER_WRITE);
    int32_t a = mp_obj_get_int(args[1]);
    int32_t b = mp_obj_get_int(args[2]);
    if (a < 0 || b < a || (size_t)b > o.len / 2) {
        mp_raise_ValueError(MP_ERROR_TEXT("fill: a, b outside out"));
    }
    const uint16_t *tab = tc_buf(args[5], 2 * TC_SINE_U16, MP_BUFFER_READ, "tab");
    return mp_obj_new_int(tc_fill((uint16_t *)o.buf, a, b,
                                  mp_obj_get_int(args[3]) & 0x0FFFFFFF,
                                  mp_obj_get_int(args[4]) & 0x0FFFFFFF, tab,
                                  mp_obj_get_int(args[6])));
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_fill_obj, 7, 7, tc_fill_fn);

// render(out, n, L, count, t28, d28, tab, g): texel.gen.engine_int.render_u16's loop
static mp_obj_t tc_render_fn(size_t n_args, const mp_obj_t *args) {
    int32_t n = mp_obj_get_int(args[1]);
    int32_t L = mp_obj_get_int(args[2]);
    int32_t count = mp_obj_get_int(args[3]);
    if (n < 0 || L < 1 || count < 0 || (int64_t)count * L >= (1 << 30)) {
        mp_raise_ValueError(MP_ERROR_TEXT("render: n, L and count disagree"));
    }
    uint16_t *out = tc_buf(args[0], 2 * (size_t)n, MP_BUFFER_WRITE, "out");
    const int32_t *t28 = tc_buf(args[4], 4 * (size_t)count, MP_BUFFER_READ, "t28");
    const int32_t *d28 = tc_buf(args[5], 4 * (size_t)count, MP_BUFFER_READ, "d28");
    const uint16_t *tab = tc_buf(args[6], 2 * TC_SINE_U16, MP_BUFFER_READ, "tab");
    tc_render(out, n, L, count, t28, d28, tab, mp_obj_get_int(args[7]));
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_render_obj, 8, 8, tc_render_fn);

// samples(chunks, chunk_bits, n, vals, m, stretch): kinds/samples.py fill_chunks
// from a flat array('H') of m values into a region's chunks (tc_samples)
static mp_obj_t tc_samples_fn(size_t n_args, const mp_obj_t *args) {
    size_t nch;
    mp_obj_t *items;
    mp_obj_get_array(args[0], &nch, &items);
    int32_t bits = mp_obj_get_int(args[1]);
    int32_t n = mp_obj_get_int(args[2]);
    int32_t m = mp_obj_get_int(args[4]);
    if (n < 1 || m < 1 || m > TC_U16_VALS || bits < 1 || bits > 30 || nch > MAX_CHUNKS ||
        (size_t)((n + (1 << bits) - 1) >> bits) > nch) {
        mp_raise_ValueError(MP_ERROR_TEXT("samples: n, m, chunks and chunk_bits disagree"));
    }
    uint16_t *chunks[MAX_CHUNKS];
    for (size_t i = 0; i < nch; i++) {
        int32_t left = n - ((int32_t)i << bits);
        int32_t need = left < (1 << bits) ? left : (1 << bits);
        chunks[i] = tc_buf(items[i], 2 * (size_t)(need > 0 ? need : 0), MP_BUFFER_WRITE, "chunk");
    }
    const uint16_t *vals = tc_buf(args[3], 2 * (size_t)m, MP_BUFFER_READ, "vals");
    tc_samples(chunks, bits, n, vals, m, mp_obj_get_int(args[5]) != 0);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_samples_obj, 6, 6, tc_samples_fn);

// sines(out, n, steps, ph, m, tab, a0, ws, rq): gen/reference_viper.py fill in C
// (tc_sines): n values of reference 2sin, 3sin or 4sin into out, the phases in ph
// carried to the next call. gen/reference.py uses it where the core has it: a
// full-screen 4sin took 220 ms of viper on a stock Pico
#define TC_SINES_MAX 4              // reference_viper.CONSTANTS: up to four sines
static mp_obj_t tc_sines_fn(size_t n_args, const mp_obj_t *args) {
    (void)n_args;
    int32_t n = mp_obj_get_int(args[1]);
    int32_t m = mp_obj_get_int(args[4]);
    if (n < 0 || m < 1 || m > TC_SINES_MAX) {
        mp_raise_ValueError(MP_ERROR_TEXT("sines: n or m out of range"));
    }
    uint16_t *out = tc_buf(args[0], 2 * (size_t)n, MP_BUFFER_WRITE, "out");
    const int32_t *steps = tc_buf(args[2], 8 * (size_t)m, MP_BUFFER_READ, "steps");
    int32_t *ph = tc_buf(args[3], 8 * (size_t)m, MP_BUFFER_RW, "ph");
    for (int32_t j = 0; j < 2 * m; j += 2) {
        // table steps 0..1023 and remainders 0..99999: the loop's bounds (a
        // wrong array would read outside the table)
        if ((uint32_t)ph[j] > 1023 || (uint32_t)ph[j + 1] > 99999 ||
            (uint32_t)steps[j] > 1023 || (uint32_t)steps[j + 1] > 99999) {
            mp_raise_ValueError(MP_ERROR_TEXT("sines: a phase or step out of range"));
        }
    }
    const uint16_t *tab = tc_buf(args[5], 2 * TC_SINE_U16, MP_BUFFER_READ, "tab");
    int32_t a0 = mp_obj_get_int(args[6]), ws = mp_obj_get_int(args[7]);
    int32_t rq = mp_obj_get_int(args[8]);
    // reference_viper.CONSTANTS' kind (ws ~2^21, rq = 2^36 // ws): every product then
    // stays below 2^31, and the remainder's loops take a few steps
    if (a0 < 0 || a0 >= (1 << 24) || ws < (1 << 16) || ws >= (1 << 23) ||
        rq != (int32_t)(((int64_t)1 << 36) / ws)) {
        mp_raise_ValueError(MP_ERROR_TEXT("sines: a0, ws, rq are not a reference's"));
    }
    tc_sines(out, n, steps, ph, m, tab, a0, ws, rq);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_sines_obj, 9, 9, tc_sines_fn);

// refresh(W): one refresh on texel.runtime.refresh_viper's word array W (an
// array('I') whose words are addresses FastRefresh resolved: trusted, as
// core() trusts them); what the tests compare with core()
static mp_obj_t tc_refresh_fn(mp_obj_t w_in) {
    tc_refresh((const uint32_t *)tc_buf(w_in, 4 * 15, MP_BUFFER_READ, "W"));   // W_FIXED words
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(tc_refresh_obj, tc_refresh_fn);

// wave_ll(a, invk, ll, base, q, f, cut, ll_none, ll_max, log2t): texel/gen/brush.py
// compensated's loop over the waves k = 1 .. K-1 (K = len(invk)) for a brush of one
// shape (_shape's (q, f, cut) for them all): invk[k] = q, and ll[k] from the power
// a[k + 2] (Q28) - ll_none for none, else (log2_q24(p) >> 1) + base + f clamped
// (below cut: ll_none; above ll_max: ll_max): brush_core.c tb_wave_ll. Integers
// only, as the Python: 9 ms of it on the emulated RP2040. log2t: the LOG2 table (257 Q24 values). base,
// f and cut: ints of 32 bits (brush.py passes base only then).
static mp_obj_t tc_wave_ll_fn(size_t n_args, const mp_obj_t *args) {
    (void)n_args;
    mp_buffer_info_t ib, lb;
    mp_get_buffer_raise(args[1], &ib, MP_BUFFER_WRITE);
    mp_get_buffer_raise(args[2], &lb, MP_BUFFER_WRITE);
    size_t K = ib.len / 4;
    if (K < 2 || lb.len / 4 != K) {
        mp_raise_ValueError(MP_ERROR_TEXT("wave_ll: invk and ll disagree"));
    }
    const int32_t *a = tc_buf(args[0], 4 * (K - 1 + 6), MP_BUFFER_READ, "a");
    const int32_t *t = tc_buf(args[9], 4 * 257, MP_BUFFER_READ, "log2t");
    int32_t *invk = (int32_t *)ib.buf, *ll = (int32_t *)lb.buf;
    int64_t base = mp_obj_get_int(args[3]);
    int32_t q = mp_obj_get_int(args[4]);
    int64_t f = mp_obj_get_int(args[5]);
    int64_t cut = mp_obj_get_int(args[6]);
    int32_t ll_none = mp_obj_get_int(args[7]), ll_max = mp_obj_get_int(args[8]);
    tb_wave_ll(a, (int32_t)K, invk, ll, base, q, f, cut, ll_none, ll_max, t);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_wave_ll_obj, 10, 10, tc_wave_ll_fn);

// install(fixed, tab, bufs, plans) -> (W, chunk_tables): texel.runtime.refresh_fast
// FastRefresh._install's word array on a 32-bit board (W_BASE 0: W holds the
// addresses themselves), in one call - 1.5 ms of Python a swap on the emulated
// RP2040 (two regions; more with more). fixed: W_FIXED words, the refresh's own
// addresses (state, duty table, telemetry, registers, sine table; W_TAB, W_IDLE
// and W_ROW are written here or by the caller). tab: the scene's region table
// copy, whose K_BUF/K_CHUNK rows get their buffer's address and K_PLAN rows
// the index of their plan's first word in W (refresh_fast._resolve). bufs:
// the scene's buffers, each a buffer or a tuple of chunks (K_CHUNK: its chunks'
// addresses go into chunk_tables, one array('I') for every such buffer, None
// without any); plans: (t28, d28, L, gain_q14) each, into W_PLAN words, or a few
// samples' 5-tuple (kinds/samples.py plan(): its array's address, then its numbers).
#define TC_W_FIXED 15           // refresh_fast.W_FIXED = W_BUF0
#define TC_W_TAB 3
#define TC_W_PLAN 5
static mp_obj_array_t *tc_new_u32(size_t n) {
    mp_obj_array_t *o = (mp_obj_array_t *)m_malloc(sizeof(mp_obj_array_t));
    o->base.type = TC_ARRAY_TYPE;
    o->typecode = 'I';
    o->free = 0;
    o->len = n;
    o->items = m_malloc(n ? 4 * n : 4);
    memset(o->items, 0, n ? 4 * n : 4);
    return o;
}

static uint32_t tc_addr(mp_obj_t o) {
    mp_buffer_info_t b;
    mp_get_buffer_raise(o, &b, MP_BUFFER_READ);
    return (uint32_t)(uintptr_t)b.buf;
}

static mp_obj_t tc_install_fn(size_t n_args, const mp_obj_t *args) {
    (void)n_args;
    if (sizeof(void *) != 4) {
        mp_raise_ValueError(MP_ERROR_TEXT("install: a 32-bit board's"));
    }
    const uint32_t *fixed = tc_buf(args[0], 4 * TC_W_FIXED, MP_BUFFER_READ, "fixed");
    mp_buffer_info_t tb;
    mp_get_buffer_raise(args[1], &tb, MP_BUFFER_RW);
    int32_t *tab = (int32_t *)tb.buf;
    size_t nt = tb.len / 4;
    size_t nbuf, nplan;
    mp_obj_t *bufs, *plans;
    mp_obj_get_array(args[2], &nbuf, &bufs);
    mp_obj_get_array(args[3], &nplan, &plans);
    // the chunk tables: one array for every chunked buffer
    size_t nch = 0;
    for (size_t k = 0; k < nbuf; k++) {
        mp_buffer_info_t b;
        if (!mp_get_buffer(bufs[k], &b, MP_BUFFER_READ)) {
            size_t n;
            mp_obj_t *cs;
            if (mp_obj_get_type(bufs[k]) != &mp_type_tuple) {
                mp_raise_ValueError(MP_ERROR_TEXT("install: a buffer is an array or a tuple of chunks"));
            }
            mp_obj_get_array(bufs[k], &n, &cs);
            nch += n;
        }
    }
    size_t nw = TC_W_FIXED + nbuf + TC_W_PLAN * nplan;
    mp_obj_array_t *wo = tc_new_u32(nw);
    mp_obj_array_t *co = nch ? tc_new_u32(nch) : NULL;
    uint32_t *w = (uint32_t *)wo->items;
    uint32_t *ct = co ? (uint32_t *)co->items : NULL;
    memcpy(w, fixed, 4 * TC_W_FIXED);
    w[TC_W_TAB] = (uint32_t)(uintptr_t)tab;
    for (size_t k = 0; k < nbuf; k++) {
        mp_buffer_info_t b;
        if (mp_get_buffer(bufs[k], &b, MP_BUFFER_READ)) {
            w[TC_W_FIXED + k] = (uint32_t)(uintptr_t)b.buf;
            continue;
        }
        size_t n;
        mp_obj_t *cs;
        mp_obj_get_array(bufs[k], &n, &cs);
        w[TC_W_FIXED + k] = (uint32_t)(uintptr_t)ct;
        for (size_t c = 0; c < n; c++) {
            *ct++ = tc_addr(cs[c]);
        }
    }
    for (size_t p = 0; p < nplan; p++) {
        size_t n4;
        mp_obj_t *pl;
        mp_obj_get_array(plans[p], &n4, &pl);
        uint32_t *q = w + TC_W_FIXED + nbuf + TC_W_PLAN * p;
        if (n4 == 5) {                           // a few samples (kinds/samples.py plan())
            q[0] = tc_addr(pl[0]);
            for (size_t i = 1; i < 5; i++) {
                q[i] = (uint32_t)mp_obj_get_int_truncated(pl[i]);
            }
            continue;
        }
        mp_int_t L = n4 == 4 ? mp_obj_get_int(pl[2]) : 0;
        if (L < 1) {
            mp_raise_ValueError(MP_ERROR_TEXT("install: a plan is (t28, d28, L >= 1, gain)"));
        }
        q[0] = tc_addr(pl[0]);
        q[1] = tc_addr(pl[1]);
        q[2] = (uint32_t)L;
        q[3] = (uint32_t)mp_obj_get_int(pl[3]);
        q[4] = (uint32_t)(65536 / L + 1);      // core()'s reciprocal of L
    }
    for (size_t r = 0; r + 4 < nt; r += 4) {     // every row but the sentinel
        int32_t kind = tab[r + 2], v = tab[r + 3];
        if (kind == 2 || kind == 4 || kind == 5) {   // scene.K_PLAN, K_TILE, K_STRETCH
            if (v < 0 || (size_t)v >= nplan) {
                mp_raise_ValueError(MP_ERROR_TEXT("install: a row names no plan"));
            }
            tab[r + 3] = (int32_t)(TC_W_FIXED + nbuf + TC_W_PLAN * (size_t)v);
        } else if (kind == 1 || kind == 3) {     // scene.K_BUF, K_CHUNK
            if (v < 0 || (size_t)v >= nbuf) {
                mp_raise_ValueError(MP_ERROR_TEXT("install: a row names no buffer"));
            }
            tab[r + 3] = (int32_t)w[TC_W_FIXED + v];
        }
    }
    mp_obj_t out[2] = {MP_OBJ_FROM_PTR(wo), co ? MP_OBJ_FROM_PTR(co) : mp_const_none};
    return mp_obj_new_tuple(2, out);
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_install_obj, 4, 4, tc_install_fn);

// The RP2040 refresh interrupt's call: hw/rp2.py's trampoline calls it as
// MicroPython's native code calls refresh_viper.core (r0 a function object,
// r1 = 1 argument, r2 = 0, r3 the arguments): args[0] is W's address as a
// small int ((address << 1) | 1, refresh_viper._ARGS). In RAM on the firmware.
static TC_RAMFUNC mp_obj_t tc_refresh_irq(mp_obj_t fun, size_t n_args, size_t n_kw,
                                          const mp_obj_t *args) {
    (void)fun;
    (void)n_args;
    (void)n_kw;
    tc_refresh((const uint32_t *)(uintptr_t)MP_OBJ_SMALL_INT_VALUE(args[0]));
    return mp_const_none;
}

// refresh_entry() -> the address of tc_refresh_irq (Thumb bit set on ARM):
// what refresh_viper.irq_rp2.native_entry hands the trampoline
static mp_obj_t tc_refresh_entry_fn(void) {
    return mp_obj_new_int_from_uint((mp_uint_t)(uintptr_t)&tc_refresh_irq);
}
static MP_DEFINE_CONST_FUN_OBJ_0(tc_refresh_entry_obj, tc_refresh_entry_fn);

// u16(n) -> array('H') of n zeros in one heap block, built at C speed: what
// texel.compat.u16_one_block makes with array('H', range(n)) (72 ms for a
// 19,200-sample map on an RP2040) so as not to need a second 2n-byte block for
// array('H', bytes(2n)). The includer's TC_ARRAY_TYPE is the array type.
#define TC_U16_MAX (1 << 20)            // gen/params.py LENGTH_MAX samples
static mp_obj_t tc_u16_fn(mp_obj_t n_in) {
    mp_int_t n = mp_obj_get_int(n_in);
    if (n < 0 || n > TC_U16_MAX) {
        mp_raise_ValueError(MP_ERROR_TEXT("u16: n out of range"));
    }
    mp_obj_array_t *o = (mp_obj_array_t *)m_malloc(sizeof(mp_obj_array_t));
    o->base.type = TC_ARRAY_TYPE;
    o->typecode = 'H';
    o->free = 0;
    o->len = (size_t)n;
    o->items = m_malloc(n ? 2 * (size_t)n : 2);
    memset(o->items, 0, n ? 2 * (size_t)n : 2);
    return MP_OBJ_FROM_PTR(o);
}
static MP_DEFINE_CONST_FUN_OBJ_1(tc_u16_obj, tc_u16_fn);

// zero(buf): every byte of a writable buffer 0. texel.runtime.refresh_fast
// _zero: the W, table copy and chunk tables a swap dropped hold raw addresses
// of the old scene's maps (the collector reads them as pointers); Python's
// slice stores took 70-95 us a buffer on a stock Pico, two to four a swap
static mp_obj_t tc_zero_fn(mp_obj_t buf) {
    mp_buffer_info_t b;
    mp_get_buffer_raise(buf, &b, MP_BUFFER_WRITE);
    memset(b.buf, 0, b.len);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_1(tc_zero_obj, tc_zero_fn);

// The checks and the plan below do float arithmetic in the runtime's float.
// A native module for a core without a float unit (armv6m: a stock RP2040)
// would carry libgcc's soft-float routines in RAM beside them (7 KB: its .mpy
// grew from 9.1 to 16.3 KB, and a stock Pico's heap could no longer paint a
// quarter-screen brush): there the Makefile leaves them out (TC_NO_FLOAT) and
// the Python checks run. The firmware links the port's own float routines.
#ifndef TC_NO_FLOAT
// texel_check(tex, spec) -> the canonical texel texture, or None: the fast path
// of texel/runtime/kinds/texel.py check (through gen/params.py validate and
// gen/grid.py), for the textures it accepts as they come - floats and ints in
// range, None where allowed, the phase words. Anything else (an unknown key,
// a bool, a string where a number goes, a value out of range or on a grid
// tie, min_cpmm not below the band limit, a float key given a huge int)
// returns None, and the Python path words the refusal or decides: one place
// holds the messages. tex: a dict (anything else: None).
// spec: kinds/texel.py _c_spec(): (tie, quant_min, then lo, hi, default for
// each of TC_CK_NUM keys in TC_CK_NAMES' order from pitch_db) - Python's own
// objects, so bounds compare as Python compares them.
#define TC_CK_KIND 0
#define TC_CK_QUANT 4
#define TC_CK_GAIN 6
#define TC_CK_V 7
#define TC_CK_BAND 8
#define TC_CK_MIN 9
#define TC_CK_PHASE 10
#define TC_CK_NUM 9                     // pitch_db .. min_cpmm
#define TC_CK_KEYS 11
// the keys, NUL-separated in index order (no pointer table: a native module's
// data holds no relocated pointers; no libc strlen/memcmp there either)
static const char tc_ck_names[] = "kind\0pitch_db\0irregularity_db\0texel_samples\0quant_db\0"
    "seed\0gain\0v\0band_limit_cpmm\0min_cpmm\0phase\0";
// 'f' a number (int accepted, made a float), 'i' an int, 'n' a number or None
static const char tc_ck_kinds[TC_CK_KEYS + 1] = "?ffififinnw";

static qstr tc_ck_qstr(int i) {
    switch (i) {
        case 1: return MP_QSTR_pitch_db;
        case 2: return MP_QSTR_irregularity_db;
        case 3: return MP_QSTR_texel_samples;
        case 4: return MP_QSTR_quant_db;
        case 5: return MP_QSTR_seed;
        case 6: return MP_QSTR_gain;
        case 7: return MP_QSTR_v;
        case 8: return MP_QSTR_band_limit_cpmm;
        default: return MP_QSTR_min_cpmm;
    }
}

// s (n bytes) is the NUL-terminated word w
static int tc_ck_is(const char *s, size_t n, const char *w) {
    size_t k = 0;
    while (k < n && w[k] != 0 && w[k] == s[k]) {
        k++;
    }
    return k == n && w[k] == 0;
}

// index of key k in tc_ck_names, or -1
static int tc_ck_key(mp_obj_t k) {
    if (!mp_obj_is_str(k)) {
        return -1;
    }
    size_t n;
    const char *s = mp_obj_str_get_data(k, &n);
    const char *w = tc_ck_names;
    for (int i = 0; i < TC_CK_KEYS; i++) {
        if (tc_ck_is(s, n, w)) {
            return i;
        }
        while (*w++ != 0) {
        }
    }
    return -1;
}

static int tc_ck_word(mp_obj_t v, const char *w) {
    if (!mp_obj_is_str(v)) {
        return 0;
    }
    size_t n;
    const char *s = mp_obj_str_get_data(v, &n);
    return tc_ck_is(s, n, w);
}

static mp_obj_t tc_texel_check_fn(mp_obj_t tex_in, mp_obj_t spec_in) {
    size_t ns;
    mp_obj_t *spec;
    mp_obj_get_array(spec_in, &ns, &spec);
    if (ns != 2 + 3 * TC_CK_NUM) {
        mp_raise_ValueError(MP_ERROR_TEXT("texel_check: spec has the wrong length"));
    }
    // the float and int types from the arguments (spec[0] is a float, an int's
    // type is int's): no name lookup, which would see the caller's globals
    const mp_obj_type_t *float_type = mp_obj_get_type(spec[0]);
    const mp_obj_type_t *int_type = mp_obj_get_type(MP_OBJ_NEW_SMALL_INT(0));
    if (mp_obj_get_type(tex_in) != TC_DICT_TYPE) {
        return mp_const_none;
    }
    mp_obj_t val[TC_CK_KEYS];
    for (int i = 0; i < TC_CK_KEYS; i++) {
        val[i] = MP_OBJ_NULL;
    }
    mp_map_t *map = &((mp_obj_dict_t *)MP_OBJ_TO_PTR(tex_in))->map;
    for (size_t j = 0; j < map->alloc; j++) {
        if (!mp_map_slot_is_filled(map, j)) {
            continue;
        }
        int i = tc_ck_key(map->table[j].key);
        if (i < 0) {
            return mp_const_none;       // unknown (length_samples too): Python words it
        }
        val[i] = map->table[j].value;
    }
    if (val[1] == MP_OBJ_NULL || val[2] == MP_OBJ_NULL) {
        return mp_const_none;           // a required key missing
    }
    mp_float_t tie = mp_obj_get_float(spec[0]);
    mp_float_t quant_min = mp_obj_get_float(spec[1]);
    mp_obj_t out[TC_CK_KEYS];
    mp_float_t f[TC_CK_KEYS];           // the float keys' values, as floats
    for (int i = 1; i <= TC_CK_NUM; i++) {
        mp_obj_t lo = spec[2 + 3 * (i - 1)], hi = spec[3 + 3 * (i - 1)];
        mp_obj_t v = val[i];
        char kind = tc_ck_kinds[i];
        if (v == MP_OBJ_NULL) {
            v = spec[4 + 3 * (i - 1)];  // the default (None for the bounds)
            out[i] = v;
            if (v != mp_const_none && kind != 'i') {
                f[i] = mp_obj_get_float(v);
            }
            continue;
        }
        if (kind == 'i') {
            // an int (small or big; a bool is neither) in [lo, hi], kept as is
            if (!(mp_obj_is_small_int(v) || mp_obj_get_type(v) == int_type)) {
                return mp_const_none;
            }
            if (mp_obj_is_small_int(v) && mp_obj_is_small_int(lo) && mp_obj_is_small_int(hi)) {
                mp_int_t x = MP_OBJ_SMALL_INT_VALUE(v);
                if (x < MP_OBJ_SMALL_INT_VALUE(lo) || x > MP_OBJ_SMALL_INT_VALUE(hi)) {
                    return mp_const_none;
                }
            } else if (mp_binary_op(MP_BINARY_OP_LESS_EQUAL, lo, v) != mp_const_true ||
                       mp_binary_op(MP_BINARY_OP_LESS_EQUAL, v, hi) != mp_const_true) {
                return mp_const_none;
            }
            out[i] = v;
            continue;
        }
        if (v == mp_const_none && kind == 'n') {
            out[i] = v;
            continue;
        }
        mp_float_t x;
        if (mp_obj_get_type(v) == float_type) {
            x = mp_obj_get_float(v);
            out[i] = v;                 // params.check_value returns a float as is
        } else if (mp_obj_is_small_int(v)) {
            x = (mp_float_t)MP_OBJ_SMALL_INT_VALUE(v);
            out[i] = MP_OBJ_NULL;       // float(value), made below
        } else {
            return mp_const_none;       // a bool, a big int, a str, None ...
        }
        // in range (NaN fails both); quant_db: 0 (off) or >= QUANT_DB_MIN
        if (!(x >= mp_obj_get_float(lo) && x <= mp_obj_get_float(hi))) {
            return mp_const_none;
        }
        if (i == TC_CK_QUANT && x != 0 && !(x >= quant_min)) {
            return mp_const_none;
        }
        f[i] = x;
        if (out[i] == MP_OBJ_NULL) {
            out[i] = mp_obj_new_float(x);
        }
    }
    // the phase: one of its words; the default ("continuous") is left out
    int reset = 0;
    if (val[TC_CK_PHASE] != MP_OBJ_NULL) {
        if (tc_ck_word(val[TC_CK_PHASE], "reset")) {
            reset = 1;
        } else if (!tc_ck_word(val[TC_CK_PHASE], "continuous")) {
            return mp_const_none;
        }
    }
    // format 2: the grid (gen/grid.py to_grid: its keys that are not None)
    if (mp_obj_is_small_int(out[TC_CK_V]) && MP_OBJ_SMALL_INT_VALUE(out[TC_CK_V]) == 2) {
        static const uint8_t grid_keys[5] = {1, 2, TC_CK_QUANT, TC_CK_BAND, TC_CK_MIN};
        for (int j = 0; j < 5; j++) {
            int i = grid_keys[j];
            if (out[i] == mp_const_none) {
                continue;
            }
            mp_float_t g;
            if (!tc_grid(f[i], tie, mp_obj_get_float(spec[2 + 3 * (i - 1)]),
                         mp_obj_get_float(spec[3 + 3 * (i - 1)]), &g)) {
                return mp_const_none;   // a tie (refused) or moved into range: Python
            }
            f[i] = g;
            out[i] = mp_obj_new_float(g);
        }
    }
    if (out[TC_CK_MIN] != mp_const_none && out[TC_CK_BAND] != mp_const_none &&
        !(f[TC_CK_MIN] < f[TC_CK_BAND])) {
        return mp_const_none;           // min_cpmm not below the band limit: refused
    }
    mp_obj_t d = mp_obj_new_dict(TC_CK_KEYS);
    mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_kind), MP_OBJ_NEW_QSTR(MP_QSTR_texel));
    for (int i = 1; i <= TC_CK_BAND; i++) {
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(tc_ck_qstr(i)), out[i]);
    }
    if (out[TC_CK_MIN] != mp_const_none) {
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_min_cpmm), out[TC_CK_MIN]);
    }
    if (reset) {
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_phase), val[TC_CK_PHASE]);
    }
    return d;
}
static MP_DEFINE_CONST_FUN_OBJ_2(tc_texel_check_obj, tc_texel_check_fn);

// region_check(r, lim, positions, dx_um) -> (start_mm, end_mm, start, end, texture),
// or None: the fast path of texel/runtime/scene.py's per-region checks for a
// region as it comes - a dict of exactly start_mm, end_mm and texture, both
// boundaries floats or ints in [0, lim] whose positions are at most
// `positions`, start before end, at least one position between them. The
// positions as scene.to_position rounds them, int(mm * 1000.0 / dx_um + 0.5)
// in the runtime's float; start_mm/end_mm as _mm_in returns them (a float as
// is, an int made a float). Anything else: None, and the Python checks decide
// and word the refusal. r: a dict (anything else: None); lim:
// scene.py's total_mm + 1.0 + dx_um / 500.0, a Python float.
static int tc_rc_pos(mp_float_t x, mp_float_t dx_um, mp_int_t *pos) {
    mp_float_t t = x * (mp_float_t)1000.0;
    t = t / dx_um;
    t = t + (mp_float_t)0.5;
    if (!(t >= 0 && t < (mp_float_t)(1 << 29))) {
        return 0;
    }
    *pos = (mp_int_t)t;
    return 1;
}

static int tc_rc_mm(mp_obj_t v, mp_float_t lim, mp_int_t positions, mp_float_t dx_um,
                    const mp_obj_type_t *float_type, mp_float_t *x, mp_int_t *pos) {
    if (mp_obj_is_small_int(v)) {
        *x = (mp_float_t)MP_OBJ_SMALL_INT_VALUE(v);
    } else if (mp_obj_get_type(v) == float_type) {
        *x = mp_obj_get_float(v);
    } else {
        return 0;
    }
    return *x >= 0 && *x <= lim && tc_rc_pos(*x, dx_um, pos) && *pos <= positions;
}

static mp_obj_t tc_region_check_fn(size_t n_args, const mp_obj_t *args) {
    if (mp_obj_get_type(args[0]) != TC_DICT_TYPE) {
        return mp_const_none;
    }
    mp_map_t *map = &((mp_obj_dict_t *)MP_OBJ_TO_PTR(args[0]))->map;
    if (map->used != 3) {
        return mp_const_none;
    }
    mp_obj_t v[3] = {MP_OBJ_NULL, MP_OBJ_NULL, MP_OBJ_NULL};
    for (size_t j = 0; j < map->alloc; j++) {
        if (!mp_map_slot_is_filled(map, j)) {
            continue;
        }
        mp_obj_t k = map->table[j].key;
        if (!mp_obj_is_str(k)) {
            return mp_const_none;
        }
        size_t n;
        const char *s = mp_obj_str_get_data(k, &n);
        int i = tc_ck_is(s, n, "start_mm") ? 0 : tc_ck_is(s, n, "end_mm") ? 1 :
                tc_ck_is(s, n, "texture") ? 2 : -1;
        if (i < 0) {
            return mp_const_none;
        }
        v[i] = map->table[j].value;
    }
    if (v[0] == MP_OBJ_NULL || v[1] == MP_OBJ_NULL || v[2] == MP_OBJ_NULL) {
        return mp_const_none;
    }
    const mp_obj_type_t *float_type = mp_obj_get_type(args[1]);     // lim: a float
    mp_float_t lim = mp_obj_get_float(args[1]);
    mp_int_t positions = mp_obj_get_int(args[2]);
    mp_float_t dx_um = mp_obj_get_float(args[3]);
    mp_float_t a, b;
    mp_int_t s, e;
    if (!tc_rc_mm(v[0], lim, positions, dx_um, float_type, &a, &s) ||
        !tc_rc_mm(v[1], lim, positions, dx_um, float_type, &b, &e) || !(a < b) || s >= e) {
        return mp_const_none;
    }
    mp_obj_t out[5] = {
        mp_obj_is_small_int(v[0]) ? mp_obj_new_float(a) : v[0],
        mp_obj_is_small_int(v[1]) ? mp_obj_new_float(b) : v[1],
        mp_obj_new_int(s), mp_obj_new_int(e), v[2],
    };
    return mp_obj_new_tuple(5, out);
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_region_check_obj, 4, 4, tc_region_check_fn);

// regions_check(regs, lim, positions, dx_um, spec) -> a list, one entry a region,
// or None (regs not a list or tuple): scene.py _check's loop over the regions in
// one call - a Python call costs ~20 us on the emulated Pico, and the loop made
// six a region. Each entry: (region, start, end) when region_check and, for a
// texture of kind "texel", texel_check(texture, spec) take it - region the
// canonical {"start_mm", "end_mm", "texture"} dict, made in the order _check
// makes it; region_check's 5-tuple when only it does (the texture is Python's);
// None when it does not (Python words the refusal). When every entry is the
// first kind, sorted they overlap nowhere and there are at most TC_RC_MAX:
// (regions, spans) - _check's own regions list and [(start, end)], sorted.
#define TC_RC_MAX 16            // scene.MAX_REGIONS
static mp_obj_t tc_regions_check_fn(size_t n_args, const mp_obj_t *args) {
    (void)n_args;
    const mp_obj_type_t *t = mp_obj_get_type(args[0]);
    if (t != &mp_type_list && t != &mp_type_tuple) {
        return mp_const_none;
    }
    size_t n;
    mp_obj_t *regs;
    mp_obj_get_array(args[0], &n, &regs);
    mp_obj_t out = mp_obj_new_list(n, NULL);
    mp_obj_t *items;
    size_t n2;
    mp_obj_get_array(out, &n2, &items);
    for (size_t i = 0; i < n; i++) {
        mp_obj_t a[4] = {regs[i], args[1], args[2], args[3]};
        mp_obj_t f = tc_region_check_fn(4, a);
        items[i] = f;
        if (f == mp_const_none) {
            continue;
        }
        size_t n5;
        mp_obj_t *v;
        mp_obj_get_array(f, &n5, &v);
        mp_obj_t tx = v[4];
        if (mp_obj_get_type(tx) != TC_DICT_TYPE) {
            continue;
        }
        mp_map_t *map = &((mp_obj_dict_t *)MP_OBJ_TO_PTR(tx))->map;
        int texel = 0;
        for (size_t j = 0; j < map->alloc; j++) {
            if (mp_map_slot_is_filled(map, j) && tc_ck_word(map->table[j].key, "kind")) {
                texel = tc_ck_word(map->table[j].value, "texel");
                break;
            }
        }
        if (!texel) {
            continue;
        }
        mp_obj_t tex = tc_texel_check_fn(tx, args[4]);
        if (tex == mp_const_none) {
            continue;
        }
        mp_obj_t d = mp_obj_new_dict(3);
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_start_mm), v[0]);
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_end_mm), v[1]);
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_texture), tex);
        mp_obj_t r[3] = {d, v[2], v[3]};
        items[i] = mp_obj_new_tuple(3, r);
    }
    // every region checked whole: sorted by (start, end, index) as _check sorts its
    // spans, and none overlapping the one before - then _check's result itself,
    // (regions, spans); else the list, and Python words what it finds
    if (n > TC_RC_MAX) {
        return out;
    }
    size_t order[TC_RC_MAX];
    mp_int_t st[TC_RC_MAX], en[TC_RC_MAX];
    for (size_t i = 0; i < n; i++) {
        if (items[i] == mp_const_none || mp_obj_get_type(items[i]) != &mp_type_tuple) {
            return out;
        }
        size_t n3;
        mp_obj_t *r;
        mp_obj_get_array(items[i], &n3, &r);
        if (n3 != 3) {
            return out;
        }
        st[i] = mp_obj_get_int(r[1]);
        en[i] = mp_obj_get_int(r[2]);
        size_t j = i;
        while (j > 0 && (st[order[j - 1]] > st[i] ||
                         (st[order[j - 1]] == st[i] && en[order[j - 1]] > en[i]))) {
            order[j] = order[j - 1];
            j--;
        }
        order[j] = i;
    }
    for (size_t j = 1; j < n; j++) {
        if (st[order[j]] < en[order[j - 1]]) {
            return out;
        }
    }
    mp_obj_t regions = mp_obj_new_list(n, NULL), spans = mp_obj_new_list(n, NULL);
    mp_obj_t *ri, *si;
    size_t nr;
    mp_obj_get_array(regions, &nr, &ri);
    mp_obj_get_array(spans, &nr, &si);
    for (size_t j = 0; j < n; j++) {
        size_t n3;
        mp_obj_t *r;
        mp_obj_get_array(items[order[j]], &n3, &r);
        ri[j] = r[0];
        mp_obj_t se[2] = {r[1], r[2]};
        si[j] = mp_obj_new_tuple(2, se);
    }
    mp_obj_t both[2] = {regions, spans};
    return mp_obj_new_tuple(2, both);
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_regions_check_obj, 5, 5, tc_regions_check_fn);

// describe_regions(t, src, dx_um, bufs, plans, words, own) -> the list of region
// dicts Scene.describe() makes (runtime/scene.py), or None (a boundary too far
// for the int below: Python makes them): kind, start, end, start_mm, end_mm,
// bytes, mode, then the kind's own fields - a texel's pitch_db, irregularity_db,
// seed and v (kinds/texel.py describe) here, any other kind's from
// own(kind, texture). t: the scene's table; src: its canonical regions; words:
// scene.MODES and "flash". The mm values are scene._mm's on MicroPython -
// round(x * 10000.0) / 10000.0, round() half to even - in the same float
// operations. Python's loop took ~470 us a region on the emulated Pico (the
// texel-sweep's 6: 2.8 ms of its answer).
static mp_obj_t tc_mm(mp_int_t pos, mp_float_t dx, int *ok) {
    mp_float_t v = (mp_float_t)pos * dx;
    v = v / (mp_float_t)1000.0;
    v = v * (mp_float_t)10000.0;
    if (!(v >= 0 && v < (mp_float_t)1073741824.0)) {
        *ok = 0;
        return mp_const_none;
    }
    int32_t i = (int32_t)v;                     // v >= 0: the floor
    mp_float_t f = v - (mp_float_t)i;           // exact
    if (f > (mp_float_t)0.5 || (f == (mp_float_t)0.5 && (i & 1))) {
        i += 1;
    }
    return mp_obj_new_float((mp_float_t)i / (mp_float_t)10000.0);
}

static mp_obj_t tc_describe_regions_fn(size_t n_args, const mp_obj_t *args) {
    (void)n_args;
    mp_buffer_info_t tb;
    mp_get_buffer_raise(args[0], &tb, MP_BUFFER_READ);
    const int32_t *t = (const int32_t *)tb.buf;
    size_t nsrc, nbuf, nplan, nw;
    mp_obj_t *src, *bufs, *plans, *words;
    mp_obj_get_array(args[1], &nsrc, &src);
    mp_float_t dx = mp_obj_get_float(args[2]);
    mp_obj_get_array(args[3], &nbuf, &bufs);
    mp_obj_get_array(args[4], &nplan, &plans);
    mp_obj_get_array(args[5], &nw, &words);
    if (nw != 7 || tb.len / 16 < nsrc + 1) {
        mp_raise_ValueError(MP_ERROR_TEXT("describe_regions: bad table or words"));
    }
    mp_obj_t out = mp_obj_new_list(0, NULL);
    for (size_t k = 0; k < nsrc; k++) {
        const int32_t *row = t + 4 * k;
        int32_t s = row[0], e = row[1], how = row[2], v = row[3];
        mp_obj_t tex = mp_obj_subscr(src[k], MP_OBJ_NEW_QSTR(MP_QSTR_texture), MP_OBJ_SENTINEL);
        mp_obj_t kind = mp_obj_subscr(tex, MP_OBJ_NEW_QSTR(MP_QSTR_kind), MP_OBJ_SENTINEL);
        mp_int_t n = 0;
        mp_obj_t mode;
        if (how < 0 || how > 5) {
            mp_raise_ValueError(MP_ERROR_TEXT("describe_regions: a row's kind"));
        }
        mode = words[how];
        if (how == 1 || how == 3) {             // K_BUF, K_CHUNK
            if (v < 0 || (size_t)v >= nbuf) {
                mp_raise_ValueError(MP_ERROR_TEXT("describe_regions: a row names no buffer"));
            }
            if (how == 1 && mp_obj_get_type(bufs[v]) != TC_ARRAY_TYPE) {
                mode = words[6];                // a map in flash: no RAM
            } else {
                n = 2 * (mp_int_t)(e - s);
            }
        } else if (how != 0) {                  // a plan's: as Scene.nbytes counts it
            if (v < 0 || (size_t)v >= nplan) {
                mp_raise_ValueError(MP_ERROR_TEXT("describe_regions: a row names no plan"));
            }
            size_t np;
            mp_obj_t *pl;
            mp_obj_get_array(plans[v], &np, &pl);
            n = mp_obj_get_int(mp_obj_len(pl[0])) * (np == 5 ? 2 : 8);
        }
        int ok = 1;
        mp_obj_t a = tc_mm(s, dx, &ok), b = tc_mm(e, dx, &ok);
        if (!ok) {
            return mp_const_none;
        }
        mp_obj_t d = mp_obj_new_dict(11);
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_kind), kind);
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_start), mp_obj_new_int(s));
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_end), mp_obj_new_int(e));
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_start_mm), a);
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_end_mm), b);
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_bytes), mp_obj_new_int(n));
        mp_obj_dict_store(d, MP_OBJ_NEW_QSTR(MP_QSTR_mode), mode);
        if (tc_ck_word(kind, "texel")) {        // kinds/texel.py describe
            // (not static: a native module's qstrs are known at its load only)
            const qstr keys[4] = {MP_QSTR_pitch_db, MP_QSTR_irregularity_db, MP_QSTR_seed,
                                  MP_QSTR_v};
            for (int i = 0; i < 4; i++) {
                mp_obj_t key = MP_OBJ_NEW_QSTR(keys[i]);
                mp_obj_dict_store(d, key, mp_obj_subscr(tex, key, MP_OBJ_SENTINEL));
            }
        } else {                                // the kind's own describe(tex)
            mp_obj_t ca[2] = {kind, tex};
            mp_obj_t own = mp_call_function_n_kw(args[6], 2, 0, ca);
            if (mp_obj_get_type(own) != TC_DICT_TYPE) {
                mp_raise_ValueError(MP_ERROR_TEXT("describe_regions: own() gives a dict"));
            }
            mp_map_t *map = &((mp_obj_dict_t *)MP_OBJ_TO_PTR(own))->map;
            for (size_t j = 0; j < map->alloc; j++) {
                if (mp_map_slot_is_filled(map, j)) {
                    mp_obj_dict_store(d, map->table[j].key, map->table[j].value);
                }
            }
        }
        mp_obj_list_append(out, d);
    }
    return out;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_describe_regions_obj, 7, 7, tc_describe_regions_fn);

// plan(tex, n, tab) -> (both, count, L, gain_q14), or None: kinds/texel.py
// plan_of for a canonical format-2 texture (texel_check's or the Python
// check's dict), n positions long, in one call: the grid integers
// (gen/grid.py mdb in the runtime's float), PlanInt.__init__'s integers
// (tc_plan_consts), the seed's state (tc_seeded), the per-texel loop
// (tc_texels) into both = array('i') of t28 then d28 (count each, one block
// as PlanInt allocates them), seed 001's options where the texture sets them
// (min_cpmm, phase "reset": tc_plan_options, with the log pitches in a work
// buffer freed before it returns), and engine_int.gain_q14
// (int(gain * 16384 + 0.5)). None where the dict holds a key this does not
// know or is not format 2 (PlanInt and gen/options.py decide those); tab:
// plan_int_tables.table().
static mp_float_t tc_pl_float(mp_obj_t d, qstr k) {
    return mp_obj_get_float(mp_obj_subscr(d, MP_OBJ_NEW_QSTR(k), MP_OBJ_SENTINEL));
}

static mp_obj_t tc_plan_fn(mp_obj_t tex, mp_obj_t n_in, mp_obj_t tab_in) {
    if (mp_obj_get_type(tex) != TC_DICT_TYPE) {
        return mp_const_none;
    }
    mp_map_t *map = &((mp_obj_dict_t *)MP_OBJ_TO_PTR(tex))->map;
    // the options: min_cpmm (None: no bound) and phase ("continuous" or "reset");
    // the nine other keys are texel_check's: any other key, or one of them missing
    // (the count below), and the Python plans it
    int32_t min_mc = -1, reset = 0;
    size_t keys = 9;
    for (size_t j = 0; j < map->alloc; j++) {
        if (!mp_map_slot_is_filled(map, j)) {
            continue;
        }
        int i = tc_ck_key(map->table[j].key);
        mp_obj_t val = map->table[j].value;
        if (i < 0) {
            return mp_const_none;
        } else if (i == TC_CK_MIN) {
            keys++;
            if (val != mp_const_none) {
                min_mc = tc_mdb(mp_obj_get_float(val));
                if (min_mc < 0) {
                    return mp_const_none;
                }
            }
        } else if (i == TC_CK_PHASE) {
            keys++;
            if (tc_ck_word(val, "reset")) {
                reset = 1;
            } else if (!tc_ck_word(val, "continuous")) {
                return mp_const_none;
            }
        }
    }
    if (map->used != keys) {
        return mp_const_none;
    }
    mp_obj_t v = mp_obj_subscr(tex, MP_OBJ_NEW_QSTR(MP_QSTR_v), MP_OBJ_SENTINEL);
    if (!mp_obj_is_small_int(v) || MP_OBJ_SMALL_INT_VALUE(v) != 2) {
        return mp_const_none;
    }
    int32_t n = mp_obj_get_int(n_in);
    int32_t L = mp_obj_get_int(mp_obj_subscr(tex, MP_OBJ_NEW_QSTR(MP_QSTR_texel_samples),
                                             MP_OBJ_SENTINEL));
    if (n < 1 || n > TC_U16_MAX || L < 1 || L >= (1 << 21)) {
        mp_raise_ValueError(MP_ERROR_TEXT("plan: n or texel_samples out of range"));
    }
    const int32_t *tab = tc_buf(tab_in, 4 * TC_TAB_I32, MP_BUFFER_READ, "tab");
    mp_obj_t cap = mp_obj_subscr(tex, MP_OBJ_NEW_QSTR(MP_QSTR_band_limit_cpmm), MP_OBJ_SENTINEL);
    int32_t k[4];
    tc_plan_consts(tc_mdb(tc_pl_float(tex, MP_QSTR_pitch_db)),
                   tc_mdb(tc_pl_float(tex, MP_QSTR_irregularity_db)),
                   tc_mdb(tc_pl_float(tex, MP_QSTR_quant_db)),
                   cap == mp_const_none ? 0 : tc_mdb(mp_obj_get_float(cap)), tab, k);
    uint16_t st[10];
    uint32_t seed = (uint32_t)mp_obj_get_int_truncated(
        mp_obj_subscr(tex, MP_OBJ_NEW_QSTR(MP_QSTR_seed), MP_OBJ_SENTINEL));
    tc_seeded(seed, st);
    int32_t count = (n + L - 1) / L;
    mp_obj_array_t *o = (mp_obj_array_t *)m_malloc(sizeof(mp_obj_array_t));
    o->base.type = TC_ARRAY_TYPE;
    o->typecode = 'i';
    o->free = 0;
    o->len = 2 * (size_t)count;
    o->items = m_malloc(8 * (size_t)count);
    int32_t *t28 = (int32_t *)o->items;
    int32_t none;
    if (min_mc < 0 && !reset) {
        tc_texels(st, count, L, k[0], k[1], k[2], k[3], tab, t28, t28 + count, &none, &none, 0);
    } else {
        // the bound redraws from the log pitches: kept for the options, then freed
        int32_t *ys = (int32_t *)m_malloc(4 * (size_t)count);
        int32_t above = tc_texels(st, count, L, k[0], k[1], k[2], k[3], tab, t28, t28 + count,
                                  ys, &none, 2);
        int32_t out3[3];
        tc_plan_options(seed, min_mc, reset, count, L, k, tab, ys, t28, t28 + count, above,
                        out3);
        TC_FREE(ys, 4 * (size_t)count);
    }
    mp_float_t g = tc_pl_float(tex, MP_QSTR_gain) * (mp_float_t)16384 + (mp_float_t)0.5;
    mp_obj_t out[4] = {MP_OBJ_FROM_PTR(o), mp_obj_new_int(count), mp_obj_new_int(L),
                       mp_obj_new_int((mp_int_t)g)};
    return mp_obj_new_tuple(4, out);
}
static MP_DEFINE_CONST_FUN_OBJ_3(tc_plan_obj, tc_plan_fn);

// floats_in(seq, lo, hi) -> -1 when every item of the list or tuple seq is a
// float in [lo, hi] (NaN is not), else the index of the first that is not:
// texel/gen/brush.py validate's common case (a brush's 2 x 97 floats, 10.8 ms
// of Python on the emulated RP2040), which words any other case in Python.
// lo and hi: floats (their type is the float type asked for). With the float
// code: a native module without it (armv6m) would carry libgcc's float compares.
static mp_obj_t tc_floats_in_fn(mp_obj_t seq_in, mp_obj_t lo_in, mp_obj_t hi_in) {
    const mp_obj_type_t *float_type = mp_obj_get_type(lo_in);
    if (mp_obj_get_type(hi_in) != float_type || mp_obj_is_small_int(lo_in)) {
        mp_raise_ValueError(MP_ERROR_TEXT("floats_in: lo and hi are floats"));
    }
    mp_float_t lo = mp_obj_get_float(lo_in), hi = mp_obj_get_float(hi_in);
    size_t n;
    mp_obj_t *items;
    mp_obj_get_array(seq_in, &n, &items);
    for (size_t i = 0; i < n; i++) {
        mp_obj_t x = items[i];
        if (mp_obj_is_small_int(x) || mp_obj_get_type(x) != float_type) {
            return MP_OBJ_NEW_SMALL_INT((mp_int_t)i);
        }
        mp_float_t v = mp_obj_get_float(x);
        if (!(v >= lo && v <= hi)) {
            return MP_OBJ_NEW_SMALL_INT((mp_int_t)i);
        }
    }
    return MP_OBJ_NEW_SMALL_INT(-1);
}
static MP_DEFINE_CONST_FUN_OBJ_3(tc_floats_in_obj, tc_floats_in_fn);

// leak_start(lams, a, q, inv0) -> lmax, or None: texel/gen/brush.py _leak_start's
// loops for a brush's scales lams (K floats, wavenumber 0 the mean's): lmax the
// largest of lams[1:] (the first of equals, the object itself; None when none is
// above 0.0), then for each wave i a[i + 3] = int(x * x * 2^28 + 0.5) with
// x = lams[i + 1] / lmax, and q[i + 3] = _mulq(inv0, a[i + 3]). The float steps
// one by one in the runtime's float, each rounded as MicroPython rounds them
// (volatile: no fused multiply-add where the FPU has one): 11.6 ms of Python
// on the emulated RP2040.
static mp_obj_t tc_leak_start_fn(size_t n_args, const mp_obj_t *args) {
    (void)n_args;
    size_t n;
    mp_obj_t *lams;
    mp_obj_get_array(args[0], &n, &lams);
    if (n < 2) {
        mp_raise_ValueError(MP_ERROR_TEXT("leak_start: lams too short"));
    }
    int32_t *a = tc_buf(args[1], 4 * (n - 1 + 6), MP_BUFFER_WRITE, "a");
    int32_t *q = tc_buf(args[2], 4 * (n - 1 + 6), MP_BUFFER_WRITE, "q");
    int32_t inv0 = mp_obj_get_int(args[3]);
    mp_obj_t best = MP_OBJ_NULL;
    mp_float_t lmax = 0;
    for (size_t i = 1; i < n; i++) {
        mp_float_t v = mp_obj_get_float(lams[i]);
        if (v > lmax) {
            lmax = v;
            best = lams[i];
        }
    }
    if (best == MP_OBJ_NULL) {
        return mp_const_none;
    }
    for (size_t i = 0; i + 1 < n; i++) {
        volatile mp_float_t x = mp_obj_get_float(lams[i + 1]) / lmax;
        volatile mp_float_t xx = x * x;
        volatile mp_float_t y = xx * (mp_float_t)268435456.0;
        volatile mp_float_t z = y + (mp_float_t)0.5;
        int32_t p = (int32_t)z;                  // int(): toward zero (z >= 0.5)
        a[i + 3] = p;
        q[i + 3] = tb_mulq(inv0, p);
    }
    return best;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(tc_leak_start_obj, 4, 4, tc_leak_start_fn);
#endif  // TC_NO_FLOAT

#if MICROPY_FLOAT_IMPL == MICROPY_FLOAT_IMPL_FLOAT && !defined(TC_NO_FLOAT)
// answer(value) -> True after printing value as one line of a literal the
// host's link reads (texel.wire.say: an answer), False having printed nothing
// when it holds something this does not write (the caller prints repr()). As
// repr() prints it, except each float: `<its 32 bits>j`, an imaginary int
// literal (no answer holds a complex), which the host turns back into the float
// (texelpad.link.protocol.floats_from_bits). MicroPython's float repr searches
// for a round-tripping text (py/formatfloat.c), 0.3-1.7 ms a float on the
// RP2040: most of a push's answer (docs/firmware.md). Written: None, bools,
// small ints, floats, str of printable ASCII, and dict, list and tuple of them
// exactly (not subclasses) up to TC_ANS_DEPTH deep. Allocates nothing: a 256-byte
// buffer on the C stack, printed to the board's stdout as print() prints.
// Not in the native modules without float code (armv6m: it would take 1.3 KB
// of a stock Pico's heap, where pushes are refused for RAM; docs/firmware.md).
#define TC_ANS_DEPTH 16

typedef struct {
    size_t n;
    char b[256];
} tc_out_t;

static void tc_out_flush(tc_out_t *o) {
    if (o->n) {
        mp_plat_print.print_strn(mp_plat_print.data, o->b, o->n);
        o->n = 0;
    }
}

static void tc_out_ch(tc_out_t *o, char c) {
    if (o->n == sizeof(o->b)) {
        tc_out_flush(o);
    }
    o->b[o->n++] = c;
}

static void tc_out_s(tc_out_t *o, const char *s) {
    while (*s) {
        tc_out_ch(o, *s++);
    }
}

static void tc_out_u(tc_out_t *o, uint32_t v) {
    char t[10];
    int k = 0;
    do {
        t[k++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    while (k) {
        tc_out_ch(o, t[--k]);
    }
}

// write v to o (o NULL: only check it can be written); 0 when it cannot
static int tc_ans(tc_out_t *o, mp_obj_t v, int depth) {
    if (depth > TC_ANS_DEPTH) {
        return 0;
    }
    if (v == mp_const_none || v == mp_const_true || v == mp_const_false) {
        if (o) {
            tc_out_s(o, v == mp_const_none ? "None" : v == mp_const_true ? "True" : "False");
        }
        return 1;
    }
    if (mp_obj_is_small_int(v)) {
        if (o) {
            mp_int_t x = MP_OBJ_SMALL_INT_VALUE(v);
            if (x < 0) {
                tc_out_ch(o, '-');
            }
            tc_out_u(o, x < 0 ? 0u - (uint32_t)x : (uint32_t)x);
        }
        return 1;
    }
    if (mp_obj_is_str(v)) {
        size_t n;
        const char *s = mp_obj_str_get_data(v, &n);
        // py/objstr.c mp_str_print_quoted: ' unless the text has a ' and no " (its
        // scan stops at the first ")
        int single = 0, dbl = 0;
        for (size_t i = 0; i < n; i++) {
            unsigned char c = (unsigned char)s[i];
            if (c < 0x20 || c >= 0x7f) {
                return 0;               // escapes and UTF-8: repr() words them
            }
            if (!dbl) {
                if (c == '\'') {
                    single = 1;
                } else if (c == '"') {
                    dbl = 1;
                }
            }
        }
        if (o) {
            char q = (single && !dbl) ? '"' : '\'';
            tc_out_ch(o, q);
            for (size_t i = 0; i < n; i++) {
                if (s[i] == q || s[i] == '\\') {
                    tc_out_ch(o, '\\');
                }
                tc_out_ch(o, s[i]);
            }
            tc_out_ch(o, q);
        }
        return 1;
    }
    const mp_obj_type_t *t = mp_obj_get_type(v);
    if (t->name == MP_QSTR_float) {
        if (o) {
            union {
                float f;
                uint32_t u;
            } b;
            b.f = mp_obj_get_float(v);
            tc_out_u(o, b.u);
            tc_out_ch(o, 'j');
        }
        return 1;
    }
    if (t == TC_DICT_TYPE) {
        mp_map_t *map = &((mp_obj_dict_t *)MP_OBJ_TO_PTR(v))->map;
        int first = 1;
        if (o) {
            tc_out_ch(o, '{');
        }
        for (size_t j = 0; j < map->alloc; j++) {
            if (!mp_map_slot_is_filled(map, j)) {
                continue;
            }
            if (o && !first) {
                tc_out_s(o, ", ");
            }
            first = 0;
            if (!tc_ans(o, map->table[j].key, depth + 1)) {
                return 0;
            }
            if (o) {
                tc_out_s(o, ": ");
            }
            if (!tc_ans(o, map->table[j].value, depth + 1)) {
                return 0;
            }
        }
        if (o) {
            tc_out_ch(o, '}');
        }
        return 1;
    }
    int tuple = t == &mp_type_tuple;
    if (tuple || t == &mp_type_list) {
        size_t n;
        mp_obj_t *items;
        mp_obj_get_array(v, &n, &items);
        if (o) {
            tc_out_ch(o, tuple ? '(' : '[');
        }
        for (size_t i = 0; i < n; i++) {
            if (o && i) {
                tc_out_s(o, ", ");
            }
            if (!tc_ans(o, items[i], depth + 1)) {
                return 0;
            }
        }
        if (o) {
            if (tuple && n == 1) {
                tc_out_ch(o, ',');
            }
            tc_out_ch(o, tuple ? ')' : ']');
        }
        return 1;
    }
    return 0;
}

static mp_obj_t tc_answer_fn(mp_obj_t v) {
    if (!tc_ans(NULL, v, 0)) {
        return mp_const_false;
    }
    tc_out_t o;
    o.n = 0;
    tc_ans(&o, v, 0);
    tc_out_ch(&o, '\n');
    tc_out_flush(&o);
    return mp_const_true;
}
static MP_DEFINE_CONST_FUN_OBJ_1(tc_answer_obj, tc_answer_fn);
#endif  // MICROPY_FLOAT_IMPL_FLOAT
