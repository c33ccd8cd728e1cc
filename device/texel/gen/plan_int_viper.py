# Format 2's per-texel loop compiled by viper: plan_int.texels_py, statement
# for statement (the generator's warm-up and start phase, then per texel the
# generator, the inverse normal, sigma*z, the clamp and quantization, 2^x and
# the phase step), in machine words. Every value stays
# below 2^31 in magnitude (plan_int.py states the bounds), so 32-bit (rp2,
# stm32) and 64-bit (unix) words give the same results as Python's ints;
# tests/gen/test_plan_int.py compares the two on every interpreter.
# Kept alone in this file: ports without a native emitter cannot compile it.
import micropython


@micropython.viper
def texels(st: ptr16, count: int, L: int, mu: int, sigma: int, q: int, dcap: int,
           tab: ptr32, t28: ptr32, d28: ptr32, ys: ptr32, zs: ptr32, keep: int) -> int:
    above = 0
    t = 0
    tf = 0
    a_hi = int(st[0]); a_lo = int(st[1]); b_hi = int(st[2]); b_lo = int(st[3])
    c_hi = int(st[4]); c_lo = int(st[5]); d_hi = int(st[6]); d_lo = int(st[7])
    s1 = sigma >> 14
    s0 = sigma & 0x3FFF
    ll = L & 0x3FFF
    lh = L >> 14
    i = -17                             # the warm-up (16) and the start phase's draw
    while i < count:
        # xoshiro128++ in 16-bit halves (gen/rng.py)
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
        if i < 0:
            if i == -1:                 # the start phase (rng.phase_fraction_u28)
                st[8] = x_hi
                st[9] = x_lo
                t = (((x_hi << 12) | (x_lo >> 4)) + ((x_lo >> 3) & 1)) & 0x0FFFFFFF
            i += 1
            continue
        # inverse normal (plan_int.norm_q24)
        if x_hi >= 0x8000:
            x_hi = 0xFFFF - x_hi
            x_lo = 0xFFFF - x_lo
            sgn = 1
        else:
            sgn = -1
        wh = (x_hi << 1) | (x_lo >> 15)
        wl = ((x_lo << 1) & 0xFFFF) | 1
        if wh:
            b = wh
            e = 16
        else:
            b = wl
            e = 0
        if b >= 0x100:
            b = b >> 8
            e += 8
        if b >= 0x10:
            b = b >> 4
            e += 4
        if b >= 0x4:
            b = b >> 2
            e += 2
        if b >= 0x2:
            e += 1
        if e >= 16:
            k = e - 16
            top = ((wh << (16 - k)) | (wl >> k)) & 0xFFFF
        else:
            top = (wl << (16 - e)) & 0xFFFF
        j = 512 + (e << 5) + (top >> 11)
        t0 = int(tab[j])
        za = t0 + (((int(tab[j + 1]) - t0) * (top & 0x7FF) + 1024) >> 11)
        if keep & 1:
            zs[i] = za * sgn
        # y = mu +- round(sigma * |z| / 2^24)
        z1 = za >> 14
        z0 = za & 0x3FFF
        m = s1 * z0 + s0 * z1 + ((s0 * z0 + 0x800000) >> 14)
        p = ((s1 * z1) << 4) + (m >> 10)
        if sgn < 0:
            y = mu - p
        else:
            y = mu + p
        if y < -369098752:              # Y_LO = -22 * 2^24
            y = -369098752
        elif y > 251658240:             # Y_HI = 15 * 2^24
            y = 251658240
        if q:
            if y < 0:
                n = (q - 2 * y) // (2 * q)
                y = 0 - n * q
            else:
                n = (2 * y + q) // (2 * q)
                y = n * q
        if keep & 2:
            ys[i] = y
        # D = round(2^(y + LOG2_STEP0)) in 2^-28 turns (plan_int.step_d)
        w = y + 342929786               # LOG2_STEP0
        e = w >> 24
        r = w & 0xFFFFFF
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
        mm = ((a1 * b1) << 2) + ((a1 * b0 + a0 * b1 + ((a0 * b0) >> 15) + 4096) >> 13)
        if e >= 28:
            k = e - 28
            d = (mm & (0x0FFFFFFF >> k)) << k
            a = d
            af = 0
        elif e < -2:
            d = 0
            a = 0
            af = 0
        else:
            d = (mm + (1 << (27 - e))) >> (28 - e)
            if e >= 20:
                k = e - 20
                a = mm >> (28 - e)
                af = (mm & (0xFF >> k)) << k
            else:
                a = (mm + (1 << (19 - e))) >> (20 - e)
                af = a & 0xFF
                a = a >> 8
        if e >= 27:
            above += 1
        if dcap:
            if e >= 28 or d > dcap:
                d = dcap
                a = dcap
                af = 0
        d = d & 0x0FFFFFFF
        d28[i] = d
        t28[i] = t
        # t += L * (a + af/256) mod 2^28 (plan_int.mulmod28 and the carry)
        tf += L * af
        dh = a >> 14
        dl = a & 0x3FFF
        t = (t + ll * dl + (((ll * dh + lh * dl) & 0x3FFF) << 14) + (tf >> 8)) & 0x0FFFFFFF
        tf = tf & 0xFF
        i += 1
    return above

