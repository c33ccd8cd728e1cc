// The fused refresh in C: texel/runtime/refresh_viper.py core(), statement for
// statement, on the same word array W (its layout and the state S are that
// file's; tests/gen/test_texel_core.py runs both on the same inputs and
// compares every word). On the texelpad firmware it is the RP2040's refresh
// interrupt itself (texelcore_api.h refresh_entry, hw/rp2.py's trampoline),
// kept in RAM (TC_IN_RAM: pico-sdk copies .time_critical.* there), so no flash
// cache miss lands in the interrupt. Plain C99, no MicroPython headers.
#ifndef TEXELPAD_REFRESH_CORE_H
#define TEXELPAD_REFRESH_CORE_H
#include <stdint.h>

#ifdef TC_IN_RAM
#define TC_RAMFUNC __attribute__((section(".time_critical.texelcore"), noinline))
#define TC_COLD __attribute__((section(".time_critical.texelcore"), noinline, cold))
#else
#define TC_RAMFUNC
#define TC_COLD __attribute__((noinline, cold))
#endif

// One refresh on W (w: its first word): read the ADC, track the finger, look
// the scene up, apply the duty law, store the CC word, count and record.
void tc_refresh(const uint32_t *w);

#endif
