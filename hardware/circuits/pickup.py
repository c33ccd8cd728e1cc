"""The pickup disc's envelope detector, for finding the resonance (hardware/README.md,
"Finding and setting the resonance"): pickup -> 100 kOhm : 10 kOhm divider ->
BAT54 Schottky -> 10 nF || 100 kOhm to AGND -> ADC. RC = 1 ms: much longer than a
carrier period (29 us at 34 kHz), much shorter than a sweep step."""
from __future__ import annotations

from . import kicad
from .parts import BAT54, C_10N, J_PICKUP, R_10K, R_100K, make
from .stages import in_series

ENVELOPE = "PICKUP_ENV"


def envelope(agnd):
    """The pickup connector (1: disc, 2: AGND) and the detector; returns the envelope
    net (to a spare ADC pin). The divider is 11:1: a ringing plate's pickup can exceed
    the ADC's 3.3 V (measure, then change the 100 kOhm)."""
    sk = kicad.skidl()
    raw, tap, env = sk.Net("PICKUP_RAW"), sk.Net("PICKUP_DIV"), sk.Net(ENVELOPE)
    j = make(J_PICKUP)
    j[1] += raw
    j[2] += agnd
    in_series(make(R_100K), make(R_10K), raw, tap, agnd)      # 100k:10k: 1/11 of the pickup
    d = make(BAT54)
    d["A"] += tap
    d["K"] += env
    hold, load = make(C_10N), make(R_100K)
    for part in (hold, load):
        part[1] += env
        part[2] += agnd
    return env
