# The brush's painting loops (gen/brush.py: draws, fill + ifft, ola_emit)
# compiled by viper, with the same integers. A ptr32 load is zero-extended
# where the machine word is 64 bits (the unix port), so nothing stored and
# loaded again may be negative: FFT values are held + FB (2^20 > 2 x their
# largest |value|, < 2^19: brush.SUM_MAX, brush.fill), the ring of partial sums + RBIAS
# (2^23), the mean magnitude + MBIAS (2^16), ll + 3 * 2^29. Every product is below
# 2^31: the same integers on 32- and 64-bit words (tests/brush/test_paint.py
# compares them with the Python loops on every interpreter). The log2 and 2^x
# of a draw are written out in draws() rather than called: a viper function
# calling another goes through the runtime with boxed ints (measured: most of
# a window's time on the RP2040 when they were calls). Kept alone in this file:
# ports without a native emitter cannot compile it (texel.compat.native).
import micropython


@micropython.viper
def draws(st: ptr16, invk: ptr32, llo: ptr32, mag: ptr32, ph: ptr32, tab: ptr32,
          t: ptr32, so: ptr32):
    """gen/brush.py draws: one window's K = 97 draws (the texture generator
    in 16-bit halves, gen/rng.py; its state in st[0..7], written back: the
    step is plan_int_viper.texels' statement for statement), the phase from
    the low byte, the Weibull quantile in integers (weibull_q: log2_q24
    twice, round_exp2 once, inline), the sum bound. so = [sign, off] of the
    range; llo holds ll + 3 * 2^29 (LL_NONE: 0); mag[0] is written + MBIAS
    (65536)."""
    a_hi = int(st[0]); a_lo = int(st[1]); b_hi = int(st[2]); b_lo = int(st[3])
    c_hi = int(st[4]); c_lo = int(st[5]); d_hi = int(st[6]); d_lo = int(st[7])
    sign = int(so[0]) - 1
    off = int(so[1]) - 1048576
    b3 = 536870912                          # 3 * 2^29, added up: a literal (or a folded
    b3 += 536870912                         # constant) that large is no small int on a
    b3 += 536870912                         # 32-bit port, and viper cannot use it
    nb3 = 0 - b3
    s = 0
    k = 0
    while k < 97:
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
        ph[k] = x_lo & 0xFF
        ll = int(llo[k]) - b3               # LL_NONE is -b3
        v = 0
        if ll != nb3:
            # a = 25 * 2^24 - log2_q24(2 x + 1), x = the top 24 bits
            w = (((x_hi << 8) | (x_lo >> 8)) << 1) | 1
            y = w
            n = 0
            if y >= 65536:
                y = y >> 16
                n += 16
            if y >= 256:
                y = y >> 8
                n += 8
            if y >= 16:
                y = y >> 4
                n += 4
            if y >= 4:
                y = y >> 2
                n += 2
            if y >= 2:
                n += 1
            m = w << (29 - n)
            i = (m >> 21) & 0xFF
            q = int(t[i])
            a = 419430400 - ((n << 24) + q + (((int(t[i + 1]) - q) * ((m >> 9) & 0xFFF)) >> 12))
            if a < 1:
                a = 1
            # L = (log2_q24(a) - 24 * 2^24 + LOG2_LN2) >> 4
            y = a
            n = 0
            if y >= 65536:
                y = y >> 16
                n += 16
            if y >= 256:
                y = y >> 8
                n += 8
            if y >= 16:
                y = y >> 4
                n += 4
            if y >= 4:
                y = y >> 2
                n += 2
            if y >= 2:
                n += 1
            m = a << (29 - n)
            i = (m >> 21) & 0xFF
            q = int(t[i])
            L = (((n << 24) + q + (((int(t[i + 1]) - q) * ((m >> 9) & 0xFFF)) >> 12))
                 - 402653184 - 8871228) >> 4
            ik = int(invk[k])
            hp = (L >> 12) * ik
            if hp >= -33554432:
                if hp > 87031808:           # 83 octaves
                    hp = 87031808
                z = ll + (hp << 4) + (((L & 0xFFF) * ik) >> 8)
                # round_exp2(z, emax): 16 for the mean, 14 (MAG_CLIP) for a wave
                emax = 14
                if k == 0:
                    emax = 16
                e = z >> 24
                if e >= emax:
                    v = 1 << emax
                elif e >= -2:
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
                    v = (m + (1 << (27 - e))) >> (28 - e)
        if k == 0:
            v = sign * v + off
            if v > 32768:                   # MEAN_CLIP
                v = 32768
            elif v < -32768:
                v = -32768
            v += 65536                      # MBIAS
        else:
            if k == 96:                     # the Nyquist: halved (brush.draws)
                v = (v + 1) >> 1
            s += v
        mag[k] = v
        k += 1
    while s > 65536:                        # SUM_MAX
        s = 0
        k = 1
        while k < 97:
            v = int(mag[k]) >> 1
            mag[k] = v
            s += v
            k += 1
    st[0] = a_hi; st[1] = a_lo; st[2] = b_hi; st[3] = b_lo
    st[4] = c_hi; st[5] = c_lo; st[6] = d_hi; st[7] = d_lo


@micropython.viper
def frames(ma: ptr32, pa: ptr32, mb: ptr32, pb: ptr32, P: ptr16, pos: ptr32, re: ptr32,
           im: ptr32, tw: ptr16):
    """gen/brush.py fill then ifft: two windows' doubled frames, re and im
    held + FB (2^20). Twiddles 1 (j = 0) and i (t = 48) multiply exactly in
    ifft's rounding, so they are adds here. The cosine tables P and tw are
    array('h'): a ptr16 load is zero-extended everywhere, so a value from
    32768 up is taken 65536 down."""
    FB = 1048576
    re[0] = 2 * (int(ma[0]) - 65536) + FB   # the means (mag[0] held + MBIAS)
    im[0] = 2 * (int(mb[0]) - 65536) + FB
    k = 1
    while k < 96:
        m = int(ma[k])
        p = int(pa[k])
        c = int(P[p])
        if c >= 32768:
            c -= 65536
        q = int(P[(p - 64) & 255])
        if q >= 32768:
            q -= 65536
        ca = (m * c + 8192) >> 14
        sa = (m * q + 8192) >> 14
        m = int(mb[k])
        p = int(pb[k])
        c = int(P[p])
        if c >= 32768:
            c -= 65536
        q = int(P[(p - 64) & 255])
        if q >= 32768:
            q -= 65536
        cb = (m * c + 8192) >> 14
        sb = (m * q + 8192) >> 14
        j = int(pos[k])
        re[j] = ca - sb + FB
        im[j] = sa + cb + FB
        j = int(pos[192 - k])
        re[j] = ca + sb + FB
        im[j] = cb - sa + FB
        k += 1
    j = int(pos[96])
    m = 2 * int(ma[96])
    if int(pa[96]) >= 128:
        m = 0 - m
    re[j] = m + FB
    m = 2 * int(mb[96])
    if int(pb[96]) >= 128:
        m = 0 - m
    im[j] = m + FB
    # three 64-point radix-2 transforms
    base = 0
    while base < 192:
        s = 2
        ts = 96                             # 192 / s
        while s <= 64:
            half = s >> 1
            g = base
            while g < base + 64:
                j = 0
                while j < half:
                    a = g + j
                    b = a + half
                    br = int(re[b]) - FB
                    bi = int(im[b]) - FB
                    t = j * ts
                    if t == 0:
                        xr = br
                        xi = bi
                    elif t == 48:
                        xr = 0 - bi
                        xi = br
                    else:
                        wr = int(tw[t])
                        if wr >= 32768:
                            wr -= 65536
                        if t < 48:                  # (t + 144) % 192, t < 96 here
                            wi = int(tw[t + 144])
                        else:
                            wi = int(tw[t - 48])
                        if wi >= 32768:
                            wi -= 65536
                        xr = ((br * wr + 2048) >> 12) - ((bi * wi + 2048) >> 12)
                        xi = ((br * wi + 2048) >> 12) + ((bi * wr + 2048) >> 12)
                    ar = int(re[a])
                    ai = int(im[a])
                    re[b] = ar - xr
                    im[b] = ai - xi
                    re[a] = ar + xr
                    im[a] = ai + xi
                    j += 1
                g += s
            s = s << 1
            ts = ts >> 1
        base += 64
    # the radix-3 pass
    n = 0
    while n < 64:
        f0r = int(re[n]) - FB
        f0i = int(im[n]) - FB
        br = int(re[64 + n]) - FB
        bi = int(im[64 + n]) - FB
        wr = int(tw[n])
        if wr >= 32768:
            wr -= 65536
        if n < 48:                          # (n + 144) % 192
            wi = int(tw[n + 144])
        else:
            wi = int(tw[n - 48])
        if wi >= 32768:
            wi -= 65536
        f1r = ((br * wr + 2048) >> 12) - ((bi * wi + 2048) >> 12)
        f1i = ((br * wi + 2048) >> 12) + ((bi * wr + 2048) >> 12)
        br = int(re[128 + n]) - FB
        bi = int(im[128 + n]) - FB
        t = 2 * n
        wr = int(tw[t])
        if wr >= 32768:
            wr -= 65536
        if t < 48:
            wi = int(tw[t + 144])
        else:
            wi = int(tw[t - 48])
        if wi >= 32768:
            wi -= 65536
        f2r = ((br * wr + 2048) >> 12) - ((bi * wi + 2048) >> 12)
        f2i = ((br * wi + 2048) >> 12) + ((bi * wr + 2048) >> 12)
        sr = f1r + f2r
        si = f1i + f2i
        tr = ((f1r - f2r) * 3547 + 2048) >> 12          # SQRT3_2
        ti = ((f1i - f2i) * 3547 + 2048) >> 12
        hr = f0r - (sr >> 1)
        hi = f0i - (si >> 1)
        re[n] = f0r + sr + FB
        im[n] = f0i + si + FB
        re[64 + n] = hr - ti + FB
        im[64 + n] = hi + tr + FB
        re[128 + n] = hr + ti + FB
        im[128 + n] = hi - tr + FB
        n += 1


@micropython.viper
def ola_emit(fr: ptr32, hann: ptr32, ring: ptr32, r0: int, out: ptr16, at: int, a: int,
             b: int):
    """gen/brush.py ola_emit: ring[(r0 + i) mod 192] += (frame[i] * HANN[i])
    >> 10 from the doubled frame held + FB ((fr * h) >> 10 - (h << 10) is
    floor(frame * h / 1024) exactly), then the hop's samples a .. b-1 (of 48) emitted as
    uint16 into out[at ..], every hop entry of the ring back to RBIAS."""
    i = 0
    r = r0
    while i < 192:
        h = int(hann[i])
        ring[r] += ((int(fr[i]) * h) >> 10) - (h << 10)
        r += 1
        if r >= 192:
            r = 0
        i += 1
    i = 0
    r = r0
    while i < 48:
        if i >= a:
            if i < b:
                v = (int(ring[r]) - 8388608) >> 1   # RBIAS = 2^23
                if v <= 0:
                    out[at + i - a] = 0
                elif v >= 8192:
                    out[at + i - a] = 65535
                else:
                    out[at + i - a] = (v * 65535 + 4096) >> 13
        ring[r] = 8388608
        r += 1
        i += 1


@micropython.viper
def leak(q: ptr32, a: ptr32, n: int, sweeps: int, c: ptr32):
    """gen/brush.py leakage's sweeps: a[i] = max(0, q[i] - C1 (a[i-1] +
    a[i+1]) - C2 (..) - C3 (..)) over a padded array, _mulq in Q14 (every
    value >= 0: no bias needed)."""
    c1 = int(c[0])
    c2 = int(c[1])
    c3 = int(c[2])
    s = 0
    while s < sweeps:
        i = 3
        while i < n + 3:
            x = int(a[i - 1]) + int(a[i + 1])
            v = int(q[i]) - ((x >> 14) * c1 + (((x & 16383) * c1) >> 14))
            x = int(a[i - 2]) + int(a[i + 2])
            v -= (x >> 14) * c2 + (((x & 16383) * c2) >> 14)
            x = int(a[i - 3]) + int(a[i + 3])
            v -= (x >> 14) * c3 + (((x & 16383) * c3) >> 14)
            if v > 0:
                a[i] = v
            else:
                a[i] = 0
            i += 1
        s += 1
