"""One digest of integer arrays, on the host and in the device scripts the
emulated-chip tests send (a few bytes back over the link instead of every
value): s = s*31 + (v & 0xFFFFFF) mod 2^24 over every value in order, the
same on CPython and on a 32-bit board (small ints only)."""

# the device's copy, pasted into a script (its own module scope)
DEVICE = """def _dig(arrs):
    s = 0
    for a in arrs:
        for v in a:
            s = (s * 31 + (v & 0xFFFFFF)) & 0xFFFFFF
    return s
"""


def dig(arrs) -> int:
    s = 0
    for a in arrs:
        for v in a:
            s = (s * 31 + (int(v) & 0xFFFFFF)) & 0xFFFFFF
    return s
