// bench/brush_parts.py's native module (not texelpad's): the brush painter's
// per-window parts timed on the board - brush_core.c's tb_frames and tb_draws as
// they are, against a radix-4 192-point transform (fft4.h) and table-driven
// Weibull draws of other integers, the two changes a faster painter would need.
#include "py/dynruntime.h"
#include "brush_core.h"
#include "fft4.h"
void *memset(void *s, int c, size_t n) { return mp_fun_table.memset_(s, c, n); }
void *memcpy(void *dst, const void *src, size_t n) { return mp_fun_table.memmove_(dst, src, n); }
int32_t Z[2 * 192];
int32_t MA[97], PA[97], MB[97], PB[97];
// time_frames(n, tab, log2t, phase, tw, hann, pos): n x tb_frames (the current)
static mp_obj_t time_frames(size_t n_args, const mp_obj_t *args) {
    mp_int_t n = mp_obj_get_int(args[0]);
    mp_buffer_info_t b[6];
    for (int i = 0; i < 6; i++) mp_get_buffer_raise(args[1 + i], &b[i], MP_BUFFER_READ);
    tb_tables t = {b[0].buf, b[1].buf, b[2].buf, b[3].buf, b[4].buf, b[5].buf};
    for (int k = 0; k < 97; k++) { MA[k] = (k * 977) & 8191; PA[k] = (k * 37) & 255; MB[k] = (k * 571) & 8191; PB[k] = (k * 91) & 255; }
    for (mp_int_t i = 0; i < n; i++) tb_frames(MA, PA, MB, PB, &t, Z);
    return mp_obj_new_int(Z[3]);
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(time_frames_obj, 7, 7, time_frames);
// time_fft4(n, tw): n x the radix-4 192-point transform alone
static mp_obj_t time_fft4(mp_obj_t n_in, mp_obj_t tw_in) {
    mp_int_t n = mp_obj_get_int(n_in);
    mp_buffer_info_t b; mp_get_buffer_raise(tw_in, &b, MP_BUFFER_READ);
    for (int k = 0; k < 384; k++) Z[k] = (k * 977) & 8191;
    for (mp_int_t i = 0; i < n; i++) fft192_r4(Z, b.buf);
    return mp_obj_new_int(Z[3]);
}
static MP_DEFINE_CONST_FUN_OBJ_2(time_fft4_obj, time_fft4);
// time_draws(n, invk, ll, tab, log2t, phase, tw, hann, pos): n x tb_draws (the current, one window)
static mp_obj_t time_draws(size_t n_args, const mp_obj_t *args) {
    mp_int_t n = mp_obj_get_int(args[0]);
    mp_buffer_info_t bi, bl, b[6];
    mp_get_buffer_raise(args[1], &bi, MP_BUFFER_READ);
    mp_get_buffer_raise(args[2], &bl, MP_BUFFER_READ);
    for (int i = 0; i < 6; i++) mp_get_buffer_raise(args[3 + i], &b[i], MP_BUFFER_READ);
    tb_tables t = {b[0].buf, b[1].buf, b[2].buf, b[3].buf, b[4].buf, b[5].buf};
    uint16_t st[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    for (mp_int_t i = 0; i < n; i++) tb_draws(st, bi.buf, bl.buf, 1, 0, &t, MA, PA);
    return mp_obj_new_int(MA[5]);
}
static MP_DEFINE_CONST_FUN_OBJ_VAR_BETWEEN(time_draws_obj, 9, 9, time_draws);
// time_draws_tab(n, gt, ll, et): n x the table draws (one window)
int32_t GT[1025], LLT[97];
uint16_t ET[256];
static mp_obj_t time_draws_tab(mp_obj_t n_in) {
    mp_int_t n = mp_obj_get_int(n_in);
    for (int i = 0; i < 1025; i++) GT[i] = (i * 131) - 60000;
    for (int i = 0; i < 97; i++) LLT[i] = 600000 - i * 5000;
    for (int i = 0; i < 256; i++) ET[i] = 32768 + i * 128;
    uint32_t st[4] = {1, 2, 3, 4};
    for (mp_int_t i = 0; i < n; i++) draws_tab(st, GT, LLT, ET, MA, PA, 97);
    return mp_obj_new_int(MA[5]);
}
static MP_DEFINE_CONST_FUN_OBJ_1(time_draws_tab_obj, time_draws_tab);
mp_obj_t mpy_init(mp_obj_fun_bc_t *self, size_t n_args, size_t n_kw, mp_obj_t *args) {
    MP_DYNRUNTIME_INIT_ENTRY
    mp_store_global(MP_QSTR_time_frames, MP_OBJ_FROM_PTR(&time_frames_obj));
    mp_store_global(MP_QSTR_time_fft4, MP_OBJ_FROM_PTR(&time_fft4_obj));
    mp_store_global(MP_QSTR_time_draws, MP_OBJ_FROM_PTR(&time_draws_obj));
    mp_store_global(MP_QSTR_time_draws_tab, MP_OBJ_FROM_PTR(&time_draws_tab_obj));
    MP_DYNRUNTIME_INIT_EXIT
}
