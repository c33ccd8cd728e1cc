# Sine table shared by the integer engines: (sin(theta)+1)/2 in Q16
# (0..65535 = 0..1) at 1024 points per turn plus one guard entry, so linear
# interpolation never wraps. 2 KB as uint16.
# Error of linear interpolation on sin: (2*pi/1024)^2/8 = 4.7e-6 in y,
# 2.4e-6 in the map (0.009 PWM step); Q16 rounding adds <= 0.5/65535.
import math
from .compat import u16_buffer

BITS = 10
SIZE = 1 << BITS
_table = None


def table():
    global _table
    if _table is None:
        t = u16_buffer(SIZE + 1)
        for i in range(SIZE + 1):
            v = (math.sin(2 * math.pi * i / SIZE) + 1.0) * 32767.5
            t[i] = int(v + 0.5)
        _table = t
    return _table
