# Format 2's parameter grid (gen/plan_int.py): pitch_db, irregularity_db and
# quant_db on 0.001 dB, band_limit_cpmm and min_cpmm on 0.001 c/mm. params.validate puts a
# format-2 parameter set on it, so host and board hold the same values and the
# plan's integer millidecibels (mdb) are the same on every
# runtime. A value within GRID_TIE of a half-way point is refused: a board's
# float32 (error of x*1000 for |x| <= 95 below 0.006) could round it the other
# way. Kept out of params.py: format 1 never loads it.
GRID_KEYS = ("pitch_db", "irregularity_db", "quant_db", "band_limit_cpmm", "min_cpmm")
GRID_TIE = 0.01


def mdb(value):
    """value in thousandths, rounded half away from zero: the grid's integer
    (millidecibels; milli-cycles/mm for the band limit). plan_int reads its
    parameters through this."""
    v = value * 1000.0
    return int(v + 0.5) if v >= 0 else -int(-v + 0.5)


def on_grid(key, value):
    """value rounded to the 0.001 grid (half away from zero), or ValueError."""
    v = value * 1000.0
    a = -v if v < 0 else v
    if abs(a - int(a) - 0.5) < GRID_TIE:
        lo = int(a) / 1000.0
        hi = (int(a) + 1) / 1000.0
        if v < 0:
            lo, hi = -lo, -hi
        raise ValueError("%s: %r is half-way between two points of format 2's 0.001 grid "
                         "(give %r or %r)" % (key, value, lo, hi))
    return mdb(value) / 1000.0


# A value on the grid never leaves its key's range: the display's Nyquist
# pitch 94.33962 c/mm (the c/mm keys' top, params.SPEC) would round up to
# 94.34, out of range, and a canonical dict would not validate again (a pulled
# scene refused on push); it takes the grid point below, 94.339. (The other
# keys' limits are grid points: -20.0 .. 19.747 dB, -30.0 .. 5.0, 20.0.)
def _in_range(g, lo, hi):
    if g > hi:
        return int(hi * 1000.0 + 1e-6) / 1000.0         # the grid point below (hi > 0)
    if g < lo:
        return -int(-lo * 1000.0 + 1e-6) / 1000.0 if lo < 0 else \
            (int(lo * 1000.0 - 1e-6) + 1) / 1000.0      # the grid point above
    return g


def to_grid(p, range_of):
    """Put a validated format-2 parameter dict on the grid, in place, each
    value within its key's range: range_of(key) -> (lo, hi) (params hands in
    its own; this module imports nothing of params, which imports it)."""
    for key in GRID_KEYS:
        # (min_cpmm is in a canonical dict only when set: params.SPARSE)
        if p.get(key) is not None:
            # (quant_db is 0 or >= 0.001: params refuses finer, so a
            # quantization that is on stays on)
            lo, hi = range_of(key)
            p[key] = _in_range(on_grid(key, p[key]), lo, hi)
