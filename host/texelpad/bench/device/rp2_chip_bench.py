# rp2_chip_bench.py -- run on the (emulated) RP2040 by `texelpad bench-refresh
# --chip rp2040` (host/texelpad/bench/chip.py), sent through the raw REPL while
# texel.app plays board file 'pico'. It defines functions in the REPL's
# namespace (every name starts with _tpb_) that the host then calls one by
# one; each returns a tuple of small ints and strings that the host reads as a
# literal. Everything is measured with the chip's own clock: on the emulated
# Pico the TIMER counts emulated microseconds (cycle-counted), so the figures
# do not depend on the host's speed.
import time
import machine
import micropython
from micropython import const
import texel.app as _tpb_app

_TPB_TIMERAWH = const(0x40054024)
_TPB_TIMERAWL = const(0x40054028)


def _tpb_now():
    # microseconds since power-on, 64-bit: TIMERAWH:TIMERAWL read as pico-sdk's
    # time_us_64 does (high, low, high again; a carry in between re-reads)
    m = machine.mem32
    while True:
        hi = m[_TPB_TIMERAWH] & 0xFFFFFFFF
        lo = m[_TPB_TIMERAWL] & 0xFFFFFFFF
        if m[_TPB_TIMERAWH] & 0xFFFFFFFF == hi:
            return (hi << 32) | lo


def _tpb_sleep_until(t_us):
    # the busy wait on ticks_us (small ints): _tpb_now's 64-bit ints are an
    # allocation each, and a collection in the wait can outlast a hold's last
    # 10 ms on a stock Pico's heap (a CI run read the 12th hold 20-30 ms late,
    # in the next sweep)
    d = t_us - _tpb_now()
    end = time.ticks_add(time.ticks_us(), d)
    if d > 2000:
        time.sleep_ms((d - 1000) // 1000)
    while time.ticks_diff(end, time.ticks_us()) > 0:
        pass


@micropython.viper
def _tpb_spin(n: int) -> int:
    # a fixed amount of work that touches no memory: its duration grows by
    # exactly the time the IRQs steal from it
    i = 0
    while i < n:
        i += 1
    return i


def _tpb_callback():
    rt = _tpb_app._rt
    if rt.mode == "viper-irq":
        from texel.runtime.refresh_viper import irq_rp2
        return irq_rp2
    return rt.refresh.step


def _tpb_irq_cost(n, reps, gap_ms):
    # (on_us, off_us, refreshes, position) per repeat: the busy loop timed with
    # the refresh running and again with its interrupt stopped; the
    # difference is what the refreshes took from the loop, entry and exit
    # included. ticks_us: 1 us resolution over ~30 ms per window. gap_ms
    # between repeats spreads them over the finger's sweep (the cost depends
    # on the region under the finger).
    rt = _tpb_app._rt
    cb = _tpb_callback()
    out = []
    for k in range(reps):
        if k:
            time.sleep_ms(gap_ms)
        c0 = rt.refresh.count
        t0 = time.ticks_us()
        _tpb_spin(n)
        on = time.ticks_diff(time.ticks_us(), t0)
        c1 = rt.refresh.count
        pos = rt.refresh.pos
        rt.hw.stop_timer()
        t0 = time.ticks_us()
        _tpb_spin(n)
        off = time.ticks_diff(time.ticks_us(), t0)
        rt.hw.start(cb, rt.hz)
        out.append((on, off, (c1 - c0) & 0x3FFFFFFF, pos))
    return out


def _tpb_holds(period_us, first_us, step_us, n, at_us, cc_addr, cc_shift):
    # The finger (the emulator's --adc-js) holds still at n known ADC values
    # from first_us into every period_us cycle of emulated time, step_us each.
    # Wait for the next cycle whose first plateau is still ahead and read, at
    # at_us into each plateau, what plays: (t_us, position, amplitude, duty,
    # the slice's CC register as the PWM latches it).
    r = _tpb_app._rt.refresh
    import gc
    gc.collect()                    # none due during the holds
    t = _tpb_now()
    base = (t // period_us) * period_us + first_us
    if base + at_us <= t + 2000:
        base += period_us
    out = []
    for i in range(n):
        _tpb_sleep_until(base + i * step_us + at_us)
        t = _tpb_now()
        cc = (machine.mem32[cc_addr] >> cc_shift) & 0xFFFF
        out.append((t, r.pos, r.amp, r.duty, cc))
    return out


def _tpb_snap(reset_worst=False):
    # (t_us, refreshes, overruns, worst_us, faults, mem_free); reset_worst
    # starts a new window for the refresh's own worst_us
    r = _tpb_app._rt.refresh
    if reset_worst:
        r.worst_us = 0
    import gc
    return (_tpb_now(), r.count, r.overruns, r.worst_us, r.faults, gc.mem_free())


def _tpb_info():
    rt = _tpb_app._rt
    regs = rt.hw.direct_registers() if hasattr(rt.hw, "direct_registers") else None
    return (rt.mode, getattr(rt.hw, "irq_source", "machine.Timer"), rt.hw.top,
            rt.hw.freq_hz, rt.hz, rt.period_us, regs[0] if regs else 0,
            regs[1] if regs else 0, machine.freq())
