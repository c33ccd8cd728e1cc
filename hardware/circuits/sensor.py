"""The position sensor (hardware/README.md, "Position sensor"): a softpot (membrane
potentiometer, ~10 kOhm over 100 mm) with its ends to the ADC's 3.3 V and AGND and
its wiper to an ADC pin, pulled down by 100 kOhm so a lifted finger reads ~0
(the board file's lift_below)."""
from __future__ import annotations

from . import kicad
from .parts import J_SOFTPOT, R_100K, make

WIPER = "SOFTPOT_WIPER"


def softpot(v33, agnd):
    """The softpot's 3-pin connector (1: end to 3.3 V, 2: wiper, 3: end to AGND) and
    the pull-down; returns the wiper net (to the microcontroller's ADC pin)."""
    sk = kicad.skidl()
    wiper = sk.Net(WIPER)
    j = make(J_SOFTPOT)
    j[1] += v33
    j[2] += wiper
    j[3] += agnd
    r = make(R_100K)     # 100 kOhm >> 10 kOhm track: < 10 % bow of the reading
    r[1] += wiper
    r[2] += agnd
    return wiper
