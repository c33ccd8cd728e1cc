// _texelcore in the texelpad firmware: a user C module beside ulab
// (micropython.cmake; host/texelpad/firmware/build.py includes it). The
// functions are texelcore_api.h's, the same the native .mpy (natmod.c) has.
#include "py/runtime.h"

#define TC_RAISE_BUF(what, have, need) \
    mp_raise_msg_varg(&mp_type_ValueError, MP_ERROR_TEXT("%s: %d bytes, need %d"), what, \
                      (int)(have), (int)(need))
#define TC_FREE(ptr, bytes) m_del(uint8_t, ptr, bytes)
#define TC_ARRAY_TYPE (&mp_type_array)
#define TC_DICT_TYPE (&mp_type_dict)

#include "texelcore_api.h"
#include "texelcore_fw.h"            // the firmware-only functions (scene_json)

static const mp_rom_map_elem_t texelcore_globals_table[] = {
    { MP_ROM_QSTR(MP_QSTR___name__), MP_ROM_QSTR(MP_QSTR__texelcore) },
    { MP_ROM_QSTR(MP_QSTR_paint), MP_ROM_PTR(&tc_paint_obj) },
    { MP_ROM_QSTR(MP_QSTR_paint_part), MP_ROM_PTR(&tc_paint_part_obj) },
    { MP_ROM_QSTR(MP_QSTR_skip), MP_ROM_PTR(&tc_skip_obj) },
    { MP_ROM_QSTR(MP_QSTR_leak), MP_ROM_PTR(&tc_leak_obj) },
    { MP_ROM_QSTR(MP_QSTR_texels), MP_ROM_PTR(&tc_texels_obj) },
    { MP_ROM_QSTR(MP_QSTR_fill), MP_ROM_PTR(&tc_fill_obj) },
    { MP_ROM_QSTR(MP_QSTR_render), MP_ROM_PTR(&tc_render_obj) },
    { MP_ROM_QSTR(MP_QSTR_u16), MP_ROM_PTR(&tc_u16_obj) },
    { MP_ROM_QSTR(MP_QSTR_zero), MP_ROM_PTR(&tc_zero_obj) },
    { MP_ROM_QSTR(MP_QSTR_samples), MP_ROM_PTR(&tc_samples_obj) },
    { MP_ROM_QSTR(MP_QSTR_sines), MP_ROM_PTR(&tc_sines_obj) },
    { MP_ROM_QSTR(MP_QSTR_options), MP_ROM_PTR(&tc_options_obj) },
    { MP_ROM_QSTR(MP_QSTR_refresh), MP_ROM_PTR(&tc_refresh_obj) },
    { MP_ROM_QSTR(MP_QSTR_refresh_entry), MP_ROM_PTR(&tc_refresh_entry_obj) },
    { MP_ROM_QSTR(MP_QSTR_install), MP_ROM_PTR(&tc_install_obj) },
    { MP_ROM_QSTR(MP_QSTR_floats_in), MP_ROM_PTR(&tc_floats_in_obj) },
    { MP_ROM_QSTR(MP_QSTR_wave_ll), MP_ROM_PTR(&tc_wave_ll_obj) },
    { MP_ROM_QSTR(MP_QSTR_leak_start), MP_ROM_PTR(&tc_leak_start_obj) },
    { MP_ROM_QSTR(MP_QSTR_texel_check), MP_ROM_PTR(&tc_texel_check_obj) },
    { MP_ROM_QSTR(MP_QSTR_region_check), MP_ROM_PTR(&tc_region_check_obj) },
    { MP_ROM_QSTR(MP_QSTR_regions_check), MP_ROM_PTR(&tc_regions_check_obj) },
    { MP_ROM_QSTR(MP_QSTR_describe_regions), MP_ROM_PTR(&tc_describe_regions_obj) },
    { MP_ROM_QSTR(MP_QSTR_plan), MP_ROM_PTR(&tc_plan_obj) },
    #if MICROPY_FLOAT_IMPL == MICROPY_FLOAT_IMPL_FLOAT
    { MP_ROM_QSTR(MP_QSTR_answer), MP_ROM_PTR(&tc_answer_obj) },
    #endif
    { MP_ROM_QSTR(MP_QSTR_scene_json), MP_ROM_PTR(&tc_scene_json_obj) },
    { MP_ROM_QSTR(MP_QSTR_heap_hint), MP_ROM_PTR(&tc_heap_hint_obj) },
    { MP_ROM_QSTR(MP_QSTR_BUILD), MP_ROM_QSTR(MP_QSTR_firmware) },
    { MP_ROM_QSTR(MP_QSTR_API), MP_ROM_INT(TC_API) },
};
static MP_DEFINE_CONST_DICT(texelcore_globals, texelcore_globals_table);

const mp_obj_module_t texelcore_module = {
    .base = { &mp_type_module },
    .globals = (mp_obj_dict_t *)&texelcore_globals,
};

MP_REGISTER_MODULE(MP_QSTR__texelcore, texelcore_module);
