"""Benchmarks: scripts that print figures (and JSON); they never fail on time.
The user's commands `texelpad bench | bench-refresh | bench-link`:

    engines   speed against error of every render engine on every runtime
    refresh   the cost of one refresh, scene memory, push/swap latency
    link      deploy time, push latency, bytes on the wire, a push soak
    opcount   the op-count model (a cross-check, labelled an estimate)
    chip      the emulated RP2040's own clock: plan, push and refresh on the chip
    device/   the scripts that run under MicroPython (package data, not modules)

The research benchmarks (study comparison, encoder, brush fits, ...) are not
shipped: the repository's top-level bench/ (bench/README.md).
"""
