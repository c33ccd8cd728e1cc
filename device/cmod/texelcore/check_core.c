// check_core.h's grid as a plain function, for the CPython build's ctypes
// (tests/support/core_c.py): the MicroPython builds inline the header's.
#include "check_core.h"

int tc_grid_c(TC_FLOAT value, TC_FLOAT tie, TC_FLOAT lo, TC_FLOAT hi, TC_FLOAT *out) {
    return tc_grid(value, tie, lo, hi, out);
}

int32_t tc_mdb_c(TC_FLOAT value) {
    return tc_mdb(value);
}
