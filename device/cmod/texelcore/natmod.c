// _texelcore as a dynamic native module (a .mpy with machine code: py/dynruntime.mk
// and tools/mpy_ld.py of MicroPython 1.28; Makefile here). texelpad deploy
// installs the build of a board's architecture (sys.implementation._mpy):
// armv6m (RP2040), armv7emsp (STM32F4), x64 (the unix virtual board). The
// functions are texelcore_api.h's, the same the firmware's module has.
#include "py/dynruntime.h"

#define TC_RAISE_BUF(what, have, need) \
    mp_raise_ValueError(MP_ERROR_TEXT("_texelcore: a buffer is too small"))
#define TC_FREE(ptr, bytes) m_free(ptr)
// the array type, from the array module (a native module has no &mp_type_array),
// looked up once by mpy_init: `array` is an extensible built-in, so an import
// searches every sys.path filesystem for an array.py first - 4-5 ms of each
// u16() on a stock Pico (38 of them for a full-screen map), and of install()'s
// check of each region's buffer. A global, not a static: a native module has
// BSS for globals only (MicroPython's docs/develop/natmod.rst); the type is the
// firmware's, in flash, so the collector need not see this pointer.
const mp_obj_type_t *tc_array_type;
#define TC_ARRAY_TYPE (tc_array_type)

// the dict type, from the runtime's table (a native module has no &mp_type_dict)
#define TC_DICT_TYPE (mp_fun_table.type_dict)

#include "texelcore_api.h"

// gcc emits memset/memcpy calls for the C core's zeroed arrays and copies; a
// native module has no libc, so they go to the firmware's (the examples in
// MicroPython's examples/natmod do the same)
void *memset(void *s, int c, size_t n) {
    return mp_fun_table.memset_(s, c, n);
}
void *memcpy(void *dst, const void *src, size_t n) {
    return mp_fun_table.memmove_(dst, src, n);
}

mp_obj_t mpy_init(mp_obj_fun_bc_t *self, size_t n_args, size_t n_kw, mp_obj_t *args) {
    MP_DYNRUNTIME_INIT_ENTRY
    tc_array_type = (const mp_obj_type_t *)MP_OBJ_TO_PTR(mp_load_attr(
        mp_import_name(MP_QSTR_array, mp_const_none, MP_OBJ_NEW_SMALL_INT(0)), MP_QSTR_array));
    mp_store_global(MP_QSTR_paint, MP_OBJ_FROM_PTR(&tc_paint_obj));
    mp_store_global(MP_QSTR_paint_part, MP_OBJ_FROM_PTR(&tc_paint_part_obj));
    mp_store_global(MP_QSTR_skip, MP_OBJ_FROM_PTR(&tc_skip_obj));
    mp_store_global(MP_QSTR_leak, MP_OBJ_FROM_PTR(&tc_leak_obj));
    mp_store_global(MP_QSTR_texels, MP_OBJ_FROM_PTR(&tc_texels_obj));
    mp_store_global(MP_QSTR_fill, MP_OBJ_FROM_PTR(&tc_fill_obj));
    mp_store_global(MP_QSTR_render, MP_OBJ_FROM_PTR(&tc_render_obj));
    mp_store_global(MP_QSTR_u16, MP_OBJ_FROM_PTR(&tc_u16_obj));
    mp_store_global(MP_QSTR_zero, MP_OBJ_FROM_PTR(&tc_zero_obj));
    mp_store_global(MP_QSTR_samples, MP_OBJ_FROM_PTR(&tc_samples_obj));
    mp_store_global(MP_QSTR_sines, MP_OBJ_FROM_PTR(&tc_sines_obj));
    mp_store_global(MP_QSTR_options, MP_OBJ_FROM_PTR(&tc_options_obj));
    mp_store_global(MP_QSTR_refresh, MP_OBJ_FROM_PTR(&tc_refresh_obj));
    mp_store_global(MP_QSTR_refresh_entry, MP_OBJ_FROM_PTR(&tc_refresh_entry_obj));
    mp_store_global(MP_QSTR_install, MP_OBJ_FROM_PTR(&tc_install_obj));
    mp_store_global(MP_QSTR_wave_ll, MP_OBJ_FROM_PTR(&tc_wave_ll_obj));
#ifndef TC_NO_FLOAT
    mp_store_global(MP_QSTR_texel_check, MP_OBJ_FROM_PTR(&tc_texel_check_obj));
    mp_store_global(MP_QSTR_region_check, MP_OBJ_FROM_PTR(&tc_region_check_obj));
    mp_store_global(MP_QSTR_regions_check, MP_OBJ_FROM_PTR(&tc_regions_check_obj));
    mp_store_global(MP_QSTR_describe_regions, MP_OBJ_FROM_PTR(&tc_describe_regions_obj));
    mp_store_global(MP_QSTR_plan, MP_OBJ_FROM_PTR(&tc_plan_obj));
    mp_store_global(MP_QSTR_leak_start, MP_OBJ_FROM_PTR(&tc_leak_start_obj));
    mp_store_global(MP_QSTR_floats_in, MP_OBJ_FROM_PTR(&tc_floats_in_obj));
#endif
#if MICROPY_FLOAT_IMPL == MICROPY_FLOAT_IMPL_FLOAT && !defined(TC_NO_FLOAT)
    mp_store_global(MP_QSTR_answer, MP_OBJ_FROM_PTR(&tc_answer_obj));
#endif
    mp_store_global(MP_QSTR_BUILD, MP_OBJ_NEW_QSTR(MP_QSTR_native));
    mp_store_global(MP_QSTR_API, MP_OBJ_NEW_SMALL_INT(TC_API));
    MP_DYNRUNTIME_INIT_EXIT
}
