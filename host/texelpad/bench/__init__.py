"""Benchmarks: scripts that print figures (and JSON); they never fail on time.

    engines   speed against error of every render engine on every runtime
    refresh   the cost of one refresh, scene memory, push/swap latency
    link      deploy time, push latency, bytes on the wire, a push soak
    opcount   the op-count model (a cross-check, labelled an estimate)
    device/   the scripts that run under MicroPython (package data, not modules)
"""
