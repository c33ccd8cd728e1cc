// _texelbrush: the brush painter's loops in C for the texelpad firmware
// (device/texel/gen/brush.py _paint_c, leakage). Arguments are the arrays
// brush.py already holds; nothing here allocates on the MicroPython heap.
#include "py/runtime.h"
#include "brush_core.h"

#define MAX_CHUNKS 128          // 65,536 values of 512 (a full screen is 38 chunks)

static void *buf(mp_obj_t o, size_t want, int flags, const char *what) {
    mp_buffer_info_t b;
    mp_get_buffer_raise(o, &b, flags);
    if (b.len < want) {
        mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s: %d bytes, need %d"), what,
                          (int)b.len, (int)want);
    }
    return b.buf;
}

// paint(st, invk, ll, sign, off, n, chunks, chunk_bits, tab, log2t, phase, tw, hann, pos)
static mp_obj_t texelbrush_paint(size_t n_args, const mp_obj_t *args) {
    uint16_t *st = buf(args[0], 16, MP_BUFFER_RW, "st");
    const int32_t *invk = buf(args[1], 4 * TB_K, MP_BUFFER_READ, "invk");
    const int32_t *ll = buf(args[2], 4 * TB_K, MP_BUFFER_READ, "ll");
    int32_t sign = mp_obj_get_int(args[3]);
    int32_t off = mp_obj_get_int(args[4]);
    int32_t n = mp_obj_get_int(args[5]);
    size_t nch;
    mp_obj_t *items;
    mp_obj_get_array(args[6], &nch, &items);
    int32_t bits = mp_obj_get_int(args[7]);
    if (n < 0 || bits < 1 || bits > 30 || nch > MAX_CHUNKS ||
        (size_t)((n + (1 << bits) - 1) >> bits) > nch) {
        mp_raise_ValueError(MP_ERROR_TEXT("paint: n, chunks and chunk_bits disagree"));
    }
    uint16_t *chunks[MAX_CHUNKS];
    for (size_t i = 0; i < nch; i++) {
        int32_t left = n - ((int32_t)i << bits);
        int32_t need = left < (1 << bits) ? left : (1 << bits);
        chunks[i] = buf(items[i], 2 * (size_t)(need > 0 ? need : 0), MP_BUFFER_WRITE, "chunk");
    }
    tb_tables t = {
        buf(args[8], 4 * 512, MP_BUFFER_READ, "tab"),
        buf(args[9], 4 * 257, MP_BUFFER_READ, "log2t"),
        buf(args[10], 2 * 256, MP_BUFFER_READ, "phase"),
        buf(args[11], 2 * TB_WINDOW, MP_BUFFER_READ, "tw"),
        buf(args[12], 4 * TB_WINDOW, MP_BUFFER_READ, "hann"),
        buf(args[13], 4 * TB_WINDOW, MP_BUFFER_READ, "pos"),
    };
    int32_t *work = m_new(int32_t, TB_WORK);   // on the heap, not the 8 KB stack
    tb_paint(st, invk, ll, sign, off, &t, n, chunks, bits, work);
    m_del(int32_t, work, TB_WORK);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(texelbrush_paint_obj, 14, 14, texelbrush_paint);

// leak(q, a, n, sweeps, c)
static mp_obj_t texelbrush_leak(size_t n_args, const mp_obj_t *args) {
    int32_t n = mp_obj_get_int(args[2]);
    if (n < 0 || n > 4096) {
        mp_raise_ValueError(MP_ERROR_TEXT("leak: n out of range"));
    }
    const int32_t *q = buf(args[0], 4 * (size_t)(n + 6), MP_BUFFER_READ, "q");
    int32_t *a = buf(args[1], 4 * (size_t)(n + 6), MP_BUFFER_RW, "a");
    const int32_t *c = buf(args[4], 12, MP_BUFFER_READ, "c");
    tb_leak(q, a, n, mp_obj_get_int(args[3]), c);
    return mp_const_none;
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(texelbrush_leak_obj, 5, 5, texelbrush_leak);

static const mp_rom_map_elem_t texelbrush_globals_table[] = {
    { MP_ROM_QSTR(MP_QSTR___name__), MP_ROM_QSTR(MP_QSTR__texelbrush) },
    { MP_ROM_QSTR(MP_QSTR_paint), MP_ROM_PTR(&texelbrush_paint_obj) },
    { MP_ROM_QSTR(MP_QSTR_leak), MP_ROM_PTR(&texelbrush_leak_obj) },
};
static MP_DEFINE_CONST_DICT(texelbrush_globals, texelbrush_globals_table);

const mp_obj_module_t texelbrush_module = {
    .base = { &mp_type_module },
    .globals = (mp_obj_dict_t *)&texelbrush_globals,
};

MP_REGISTER_MODULE(MP_QSTR__texelbrush, texelbrush_module);
