# The brush's per-window synthesis (gen/brush.py frame_py) compiled by viper,
# The brush's painting loops (gen/brush.py: magnitudes, frame_py, the
# overlap-add and the emission in paint) compiled by viper, with the same
# integers. A ptr32 load is zero-extended where the machine word is 64 bits
# (the unix port), so nothing stored and loaded again may be negative: frame
# values are held + FBIAS (2^21 > the largest |frame value|, 1.57e6), the
# ring of partial sums + RBIAS (2^23 > its largest |value|, 6.3e6), ll + 2^29;
# the cosine table is cosp = COS + 16384 and a term ((a * cosp) >> 14) - a,
# floor(a * COS / 2^14) exactly for an integer a >= 0 (magnitudes are). Every
# product is below 2^31: the same integers on 32- and 64-bit words
# (tests/brush/test_paint.py compares them with the Python loops on every
# interpreter). Kept alone in this file: ports without a native emitter
# cannot compile it (texel.compat.native).
import micropython


@micropython.viper
def frame(mag: ptr32, ph: ptr32, out: ptr32, cosp: ptr32):
    """frame_py + FBIAS (2^21): every partial sum stays positive; mag[0]
    is held + MBIAS (65536), as magnitudes() here writes it."""
    m0 = int(mag[0]) - 65536 + 2097152
    n = 0
    while n < 188:
        out[n] = m0
        n += 1
    k = 1
    while k < 95:
        a = mag[k]
        if a:
            j = ph[k]
            n = 0
            while n < 188:
                out[n] += ((a * cosp[j]) >> 14) - a
                j += k
                if j >= 188:
                    j -= 188
                n += 1
        k += 1


@micropython.viper
def log2q(v: int, t: ptr32) -> int:
    """gen/brush.py log2_q24, statement for statement (1 <= v < 2^30)."""
    n = 0
    w = v
    if w >= 65536:
        w = w >> 16
        n += 16
    if w >= 256:
        w = w >> 8
        n += 8
    if w >= 16:
        w = w >> 4
        n += 4
    if w >= 4:
        w = w >> 2
        n += 2
    if w >= 2:
        n += 1
    m = v << (29 - n)
    i = (m >> 21) & 0xFF
    lo = int(t[i])
    return (n << 24) + lo + (((int(t[i + 1]) - lo) * ((m >> 9) & 0xFFF)) >> 12)


@micropython.viper
def exp2r(z: int, emax: int, tab: ptr32) -> int:
    """gen/brush.py round_exp2 (plan_int.exp2_m's two Q28 products in
    15-bit limbs): round(2^(z / 2^24)), saturated at 2^emax."""
    e = z >> 24
    if e >= emax:
        return 1 << emax
    if e < -2:
        return 0
    r = z & 0xFFFFFF
    a = int(tab[r >> 16])                   # EXP_HI
    b = int(tab[256 + ((r >> 8) & 0xFF)])  # EXP_MID
    a1 = a >> 15
    a0 = a & 0x7FFF
    b1 = b >> 15
    b0 = b & 0x7FFF
    a = ((a1 * b1) << 2) + ((a1 * b0 + a0 * b1 + ((a0 * b0) >> 15) + 4096) >> 13)
    b = 268435456 + (((r & 0xFF) * 726817 + 32768) >> 16)     # 2^28, LN2_Q20
    a1 = a >> 15
    a0 = a & 0x7FFF
    b1 = b >> 15
    b0 = b & 0x7FFF
    m = ((a1 * b1) << 2) + ((a1 * b0 + a0 * b1 + ((a0 * b0) >> 15) + 4096) >> 13)
    return (m + (1 << (27 - e))) >> (28 - e)


@micropython.viper
def magnitudes(st: ptr16, invk: ptr32, llo: ptr32, mag: ptr32, tab: ptr32, t: ptr32,
               sign: int, off: int):
    """gen/brush.py magnitudes: one window's K draws (the texture generator
    in 16-bit halves, gen/rng.py; its state in st[0..7], written back: the
    step is plan_int_viper.texels' statement for statement - viper cannot
    call a shared step that updates eight words without a Python call per
    draw), the
    Weibull quantile in integers (weibull_q) and round_exp2. llo holds ll +
    2^29; mag[0] is written + MBIAS (65536) for frame()."""
    a_hi = int(st[0]); a_lo = int(st[1]); b_hi = int(st[2]); b_lo = int(st[3])
    c_hi = int(st[4]); c_lo = int(st[5]); d_hi = int(st[6]); d_lo = int(st[7])
    k = 0
    while k < 95:
        lo = a_lo + d_lo
        hi = (a_hi + d_hi + (lo >> 16)) & 0xFFFF
        lo = lo & 0xFFFF
        r_hi = ((hi << 7) | (lo >> 9)) & 0xFFFF
        r_lo = ((lo << 7) | (hi >> 9)) & 0xFFFF
        lo = r_lo + a_lo
        x_hi = (r_hi + a_hi + (lo >> 16)) & 0xFFFF
        x_lo = lo & 0xFFFF
        u_hi = ((b_hi << 9) | (b_lo >> 7)) & 0xFFFF
        u_lo = (b_lo << 9) & 0xFFFF
        c_hi = c_hi ^ a_hi
        c_lo = c_lo ^ a_lo
        d_hi = d_hi ^ b_hi
        d_lo = d_lo ^ b_lo
        b_hi = b_hi ^ c_hi
        b_lo = b_lo ^ c_lo
        a_hi = a_hi ^ d_hi
        a_lo = a_lo ^ d_lo
        c_hi = c_hi ^ u_hi
        c_lo = c_lo ^ u_lo
        hi = d_hi
        d_hi = ((hi << 11) | (d_lo >> 5)) & 0xFFFF
        d_lo = ((d_lo << 11) | (hi >> 5)) & 0xFFFF
        # weibull_q
        ll = int(llo[k]) - 536870912        # 2^29: LL_NONE is -2^29, i.e. 0 here
        v = 0
        if ll != -536870912:
            x3 = (x_hi << 13) | (x_lo >> 3)
            a = 503316480 - int(log2q(2 * x3 + 1, t))
            if a < 1:
                a = 1
            L = (int(log2q(a, t)) - 402653184 - 8871228) >> 4     # LOG2_LN2
            hp = (L >> 12) * int(invk[k])
            if hp >= -33554432:
                if hp > 33554432:
                    hp = 33554432
                z = ll + (hp << 4) + (((L & 0xFFF) * int(invk[k])) >> 8)
                if k == 0:
                    v = int(exp2r(z, 16, tab))
                else:
                    v = int(exp2r(z, 14, tab))
        if k == 0:
            v = sign * v + off
            if v > 32768:                   # MEAN_CLIP
                v = 32768
            elif v < -32768:
                v = -32768
            v += 65536                      # MBIAS: frame() reads it so
        mag[k] = v
        k += 1
    mag[94] = (int(mag[94]) + 1) >> 1       # Nyquist: brush.phases() says why
    st[0] = a_hi; st[1] = a_lo; st[2] = b_hi; st[3] = b_lo
    st[4] = c_hi; st[5] = c_lo; st[6] = d_hi; st[7] = d_lo


@micropython.viper
def ola(buf: ptr32, hann: ptr32, ring: ptr32, r0: int):
    """ring[(r0 + i) mod 188] += ((frame[i] * HANN[i]) >> 9), i = 0 .. 187,
    from the biased frame (buf = frame + 2^21 > 0): (buf * h) >> 9 - h << 12
    is floor(frame * h / 512) exactly; buf * h < 2^22 * 2^9 = 2^31."""
    i = 0
    r = r0
    while i < 188:
        h = int(hann[i])
        ring[r] += ((int(buf[i]) * h) >> 9) - (h << 12)
        r += 1
        if r >= 188:
            r = 0
        i += 1


@micropython.viper
def emit(ring: ptr32, r0: int, out: ptr16):
    """paint()'s emission of HOP = 47 whole samples: v = (ring - RBIAS) >> 1
    (the four windows' Hann weights sum to 2), clipped to [0, 8192] (Q13),
    scaled to uint16 into out[0 .. 46]; the ring entries back to RBIAS."""
    i = 0
    r = r0
    while i < 47:
        v = (int(ring[r]) - 8388608) >> 1   # RBIAS = 2^23
        if v <= 0:
            out[i] = 0
        elif v >= 8192:
            out[i] = 65535
        else:
            out[i] = (v * 65535 + 4096) >> 13
        ring[r] = 8388608
        r += 1
        if r >= 188:
            r = 0
        i += 1
