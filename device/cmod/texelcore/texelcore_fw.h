// _texelcore's functions that only the texelpad firmware has (modtexelcore.c
// includes this after texelcore_api.h): what needs the runtime's own number
// parser. Not in natmod.c's sources (Makefile): mpy_ld reads every MP_QSTR_ name
// in the files it is given into the native module's qstrs, which a stock Pico
// keeps in its heap.
// scene_json(text) -> what json.loads(text) gives, or None where this leaves
// the text to it: texel/wire.py staged's parse of a pushed scene. MicroPython's
// json reads its text through the stream protocol a byte at a time (4.4 us a
// byte on the RP2040: 3.2 ms of the shipped texel-sweep's 701 bytes, 8.4 of 16
// texel regions'). This reads strict JSON (what the host's json.dumps writes,
// separators "," and ":") from the buffer and makes every value with the calls
// extmod/modjson.c makes - mp_obj_new_str, mp_parse_num_float on the same
// characters, mp_parse_num_integer, a dict and a list grown item by item - so
// the same objects. Anything else - a \u escape, a syntax modjson would read
// leniently (a comma or colon out of place), a syntax error, more than
// TC_JSON_DEPTH levels - returns None and json.loads reads it (and words its
// refusal). Firmware only: a native module has no number parser to call.
#include "py/parsenum.h"
#define TC_JSON_DEPTH 24

typedef struct {
    const char *p, *end;
} tc_js_t;

// A scene's keys and words as the firmware's own qstrs (static: MP_QSTR_ in this
// file puts them in its qstr pool): what mp_obj_new_str returns for that text
// (it finds the qstr), without its search through every qstr pool: 29 % of an
// rp2emu --profile of 40 reads (and 10 json.loads) of 16 texel regions' JSON.
// NUL-separated, in tc_js_qs's order.
static const char tc_js_words[] = "start_mm\0end_mm\0texture\0kind\0seed\0pitch_db\0"
    "irregularity_db\0v\0texel\0name\0regions\0reference\0texel_samples\0constant\0level\0"
    "min_cpmm\0phase\0reset\0continuous\0gain\0quant_db\0band_limit_cpmm\0brush\0k\0lam\0"
    "range\0samples\0u16\0values\0fit\0tile\0stretch\0idle\0";
static const uint16_t tc_js_qs[] = {MP_QSTR_start_mm, MP_QSTR_end_mm, MP_QSTR_texture,
    MP_QSTR_kind, MP_QSTR_seed, MP_QSTR_pitch_db, MP_QSTR_irregularity_db, MP_QSTR_v,
    MP_QSTR_texel, MP_QSTR_name, MP_QSTR_regions, MP_QSTR_reference, MP_QSTR_texel_samples,
    MP_QSTR_constant, MP_QSTR_level, MP_QSTR_min_cpmm, MP_QSTR_phase, MP_QSTR_reset,
    MP_QSTR_continuous, MP_QSTR_gain, MP_QSTR_quant_db, MP_QSTR_band_limit_cpmm, MP_QSTR_brush,
    MP_QSTR_k, MP_QSTR_lam, MP_QSTR_range, MP_QSTR_samples, MP_QSTR_u16, MP_QSTR_values,
    MP_QSTR_fit, MP_QSTR_tile, MP_QSTR_stretch, MP_QSTR_idle};

static mp_obj_t tc_js_str(const char *s, size_t n) {
    const char *w = tc_js_words;
    for (size_t i = 0; i < sizeof(tc_js_qs) / sizeof(tc_js_qs[0]); i++) {
        if (tc_ck_is(s, n, w)) {
            return MP_OBJ_NEW_QSTR(tc_js_qs[i]);
        }
        while (*w++ != 0) {
        }
    }
    return mp_obj_new_str(s, n);
}

static void tc_js_ws(tc_js_t *j) {
    while (j->p < j->end && (*j->p == ' ' || *j->p == '\t' || *j->p == '\n' || *j->p == '\r')) {
        j->p++;
    }
}

// the value at j->p, or MP_OBJ_NULL where this leaves the text to json.loads
static mp_obj_t tc_js_value(tc_js_t *j, int depth) {
    tc_js_ws(j);
    if (j->p >= j->end || depth > TC_JSON_DEPTH) {
        return MP_OBJ_NULL;
    }
    char c = *j->p;
    if (c == '{' || c == '[') {
        int obj = c == '{';
        mp_obj_t out = obj ? mp_obj_new_dict(0) : mp_obj_new_list(0, NULL);
        j->p++;
        tc_js_ws(j);
        if (j->p < j->end && *j->p == (obj ? '}' : ']')) {
            j->p++;
            return out;
        }
        for (;;) {
            mp_obj_t key = MP_OBJ_NULL;
            if (obj) {
                tc_js_ws(j);
                if (j->p >= j->end || *j->p != '"') {
                    return MP_OBJ_NULL;
                }
                key = tc_js_value(j, depth + 1);
                tc_js_ws(j);
                if (key == MP_OBJ_NULL || j->p >= j->end || *j->p != ':') {
                    return MP_OBJ_NULL;
                }
                j->p++;
            }
            mp_obj_t v = tc_js_value(j, depth + 1);
            if (v == MP_OBJ_NULL) {
                return MP_OBJ_NULL;
            }
            if (obj) {
                mp_obj_dict_store(out, key, v);
            } else {
                mp_obj_list_append(out, v);
            }
            tc_js_ws(j);
            if (j->p >= j->end) {
                return MP_OBJ_NULL;
            }
            c = *j->p++;
            if (c == (obj ? '}' : ']')) {
                return out;
            }
            if (c != ',') {
                return MP_OBJ_NULL;
            }
        }
    }
    if (c == '"') {
        // the text up to the closing quote: taken as it is when it has no escape
        // (the common case), else copied with modjson's escapes
        const char *s = ++j->p;
        while (j->p < j->end && *j->p != '"' && *j->p != '\\' && *j->p != 0) {
            j->p++;
        }
        if (j->p >= j->end || *j->p == 0) {
            return MP_OBJ_NULL;                 // a NUL: modjson's end of text (json.loads's)
        }
        if (*j->p == '"') {
            return tc_js_str(s, (size_t)(j->p++ - s));
        }
        vstr_t vstr;
        vstr_init(&vstr, 32);
        vstr_add_strn(&vstr, s, (size_t)(j->p - s));
        while (j->p < j->end && *j->p != '"') {
            char ch = *j->p;
            if (ch == '\\') {
                if (++j->p >= j->end || *j->p == 0) {
                    break;
                }
                ch = *j->p;
                switch (ch) {
                    case 'b': ch = 0x08; break;
                    case 'f': ch = 0x0c; break;
                    case 'n': ch = 0x0a; break;
                    case 'r': ch = 0x0d; break;
                    case 't': ch = 0x09; break;
                    case 'u': vstr_clear(&vstr); return MP_OBJ_NULL;   // json.loads's own
                    default: break;                                     // \" \\ \/: itself
                }
            }
            if (ch == 0) {
                break;
            }
            vstr_add_byte(&vstr, (byte)ch);
            j->p++;
        }
        if (j->p >= j->end || *j->p != '"') {  // the end, or a NUL: json.loads's to read
            vstr_clear(&vstr);
            return MP_OBJ_NULL;
        }
        j->p++;
        mp_obj_t str = mp_obj_new_str(vstr.buf, vstr.len);
        vstr_clear(&vstr);
        return str;
    }
    if (c == '-' || (c >= '0' && c <= '9')) {
        // modjson's token: a sign or digit, then + - . e E and digits; a float if
        // it has . e or E
        const char *s = j->p++;
        int flt = 0;
        while (j->p < j->end) {
            char d = *j->p;
            if (d == '.' || d == 'e' || d == 'E') {
                flt = 1;
            } else if (!(d == '+' || d == '-' || (d >= '0' && d <= '9'))) {
                break;
            }
            j->p++;
        }
        return flt ? mp_parse_num_float(s, (size_t)(j->p - s), false, NULL)
                   : mp_parse_num_integer(s, (size_t)(j->p - s), 10, NULL);
    }
    static const char words[] = "null\0true\0false";
    static const unsigned char at[3] = {0, 5, 10};
    for (int w = 0; w < 3; w++) {
        const char *k = words + at[w];
        const char *q = j->p;
        while (*k && q < j->end && *q == *k) {
            k++;
            q++;
        }
        if (*k == 0) {
            j->p = q;
            return w == 0 ? mp_const_none : w == 1 ? mp_const_true : mp_const_false;
        }
    }
    return MP_OBJ_NULL;
}

static mp_obj_t tc_scene_json_fn(mp_obj_t text) {
    mp_buffer_info_t b;
    mp_get_buffer_raise(text, &b, MP_BUFFER_READ);
    tc_js_t j = {(const char *)b.buf, (const char *)b.buf + b.len};
    mp_obj_t v = tc_js_value(&j, 0);
    tc_js_ws(&j);
    return v == MP_OBJ_NULL || j.p != j.end ? mp_const_none : v;
}
static MP_DEFINE_CONST_FUN_OBJ_1(tc_scene_json_obj, tc_scene_json_fn);

// heap_hint(blocks) -> the allocation table bytes it skipped: where MicroPython's
// allocator starts looking for free blocks (gc_last_free_atb_index, py/gc.c),
// moved up to the first run of at least `blocks` free blocks. gc_alloc looks for
// every allocation of more than one block (16 bytes) from that index on, a
// table byte (4 blocks) at a time; after a collection (the tidy after every
// answer) it is the first free block, under ~40 KB of modules, functions and the
// playing scene with small holes between them - so a push paid that walk on
// each of its dicts, plans and buffers: a 512-byte bytearray took 175 us on the
// emulated Pico, and gc_alloc was 9-13 % of an rp2emu --profile of pushes.
// Moving the index up is safe: the allocator only looks from it on (py/gc.c
// gc_alloc), gc_free moves it back down to a freed block, and a collection -
// the tidy's, or gc_alloc's own when nothing above has room - resets it to 0.
// The holes below stay free for after that collection. Not with gc.disable() (no
// collection would ever look below). Firmware only (a native module cannot reach
// the allocator's state).
static mp_obj_t tc_heap_hint_fn(mp_obj_t blocks_in) {
    mp_int_t want = mp_obj_get_int(blocks_in);
    #if MICROPY_GC_SPLIT_HEAP
    (void)want;
    return MP_OBJ_NEW_SMALL_INT(0);
    #else
    if (!MP_STATE_MEM(gc_auto_collect_enabled)) {
        // gc.disable(): gc_alloc would not collect and look below the hint again, and
        // a block that fits only there would be a MemoryError
        return MP_OBJ_NEW_SMALL_INT(0);
    }
    mp_state_mem_area_t *area = &MP_STATE_MEM(area);
    const byte *atb = area->gc_alloc_table_start;
    size_t len = area->gc_alloc_table_byte_len;
    size_t from = area->gc_last_free_atb_index, run = 0;
    for (size_t i = from; i < len; i++) {
        if (atb[i] != 0) {                   // a table byte with any block in use
            run = 0;
        } else if (++run * 4 >= (size_t)want) {
            area->gc_last_free_atb_index = i + 1 - run;
            return MP_OBJ_NEW_SMALL_INT(i + 1 - run - from);
        }
    }
    return MP_OBJ_NEW_SMALL_INT(0);
    #endif
}
static MP_DEFINE_CONST_FUN_OBJ_1(tc_heap_hint_obj, tc_heap_hint_fn);
