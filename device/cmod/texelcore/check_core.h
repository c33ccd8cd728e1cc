// Format 2's parameter grid in C: device/texel/gen/grid.py on_grid and mdb,
// statement for statement, for the texel check's fast path (texelcore_api.h
// texel_check: a scene's texel regions checked without the Python validators'
// interpretive cost, about 2.6 ms a region on an RP2040). TC_FLOAT is the
// runtime's float, as Python's arithmetic on it is: mp_float_t in the
// MicroPython builds (float on the RP2040 and STM32F4, double on the unix
// port), double in the CPython build (tests/support/core_c.py). The constants
// 1000.0 and 0.5 are exact in both; the tie width and the ranges come from the
// caller (Python's own float objects: parsed by its parser, not by the C
// compiler). Plain C99, no MicroPython headers.
#ifndef TEXELPAD_CHECK_CORE_H
#define TEXELPAD_CHECK_CORE_H
#include <stdint.h>

#ifndef TC_FLOAT
#define TC_FLOAT double
#endif

// value on the 0.001 grid: 1 and *out = mdb(value) / 1000.0 where grid.py's
// on_grid gives that point without refusing and _in_range keeps it in
// [lo, hi]; 0 where the Python path must decide (a value within `tie` of a
// half-way point - on_grid's refusal - or a point outside the range, which
// _in_range moves). value: finite, |value| < 10^6 (the caller's range check).
static inline int tc_grid(TC_FLOAT value, TC_FLOAT tie, TC_FLOAT lo, TC_FLOAT hi,
                          TC_FLOAT *out) {
    TC_FLOAT v = value * (TC_FLOAT)1000.0;
    TC_FLOAT a = v < 0 ? -v : v;
    if (!(a < (TC_FLOAT)1.0e9)) {
        return 0;
    }
    // on_grid: abs(a - int(a) - 0.5) < GRID_TIE refuses (int() truncates a >= 0)
    TC_FLOAT d = a - (TC_FLOAT)(int32_t)a;
    d = d - (TC_FLOAT)0.5;
    if (d < 0) {
        d = -d;
    }
    if (d < tie) {
        return 0;
    }
    // mdb: half away from zero, then the int over 1000.0 (int / float: the
    // int converted to the float, as Python and MicroPython do)
    int32_t m = v >= 0 ? (int32_t)(v + (TC_FLOAT)0.5) : -(int32_t)(-v + (TC_FLOAT)0.5);
    TC_FLOAT g = (TC_FLOAT)m / (TC_FLOAT)1000.0;
    if (g > hi || g < lo) {
        return 0;
    }
    *out = g;
    return 1;
}

// grid.py mdb: value * 1000.0 rounded half away from zero (|value| < 10^6)
static inline int32_t tc_mdb(TC_FLOAT value) {
    TC_FLOAT v = value * (TC_FLOAT)1000.0;
    return v >= 0 ? (int32_t)(v + (TC_FLOAT)0.5) : -(int32_t)(-v + (TC_FLOAT)0.5);
}

// For the CPython build (ctypes cannot call a static inline): the same.
int tc_grid_c(TC_FLOAT value, TC_FLOAT tie, TC_FLOAT lo, TC_FLOAT hi, TC_FLOAT *out);
int32_t tc_mdb_c(TC_FLOAT value);

#endif
