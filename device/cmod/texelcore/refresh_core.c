// See refresh_core.h. Indices are refresh_viper.py's W_* and S_* (refresh_viper.py
// checks its copies against refresh_fast.py's at import; tests/gen/test_texel_core.py
// runs this file and refresh_viper.core on the same W and compares every word).
//
// Speed (issue 32 item 3: <= 3 us per refresh, interrupt included, on the
// emulated Pico at 125 MHz, whatever the scene). Thumb-1 on a Cortex-M0+: a
// load or store 2 cycles (an APB register 4-5 on rp2040js), a taken branch 2,
// an untaken one 1, push/pop 1 + one per register, and each of r8-r11 gcc
// keeps costs a mov in and a mov out. So the body: finds the finger's region
// from the row it held the refresh before (W_ROW) instead of walking the table
// (16 regions: up to 16 rows, ~7 cycles each); adds no BASE on a 32-bit board
// (tc_base); keeps few values live (the position stored as soon as it is
// known, the cold paths out of line: tc_adc_slow, tc_track_cold, tc_row,
// tc_tel); lays the RP2040's path out straight (LIKELY/UNLIKELY: touching,
// START_MANY, a 12-bit RESULT, no clamp); rounds without building 2^13 or 2^15
// (RSHR). Measured with bench/firmware.py's method (the busy loop with the
// refresh interrupt on and off, the finger sweeping): a texel plan 3.42 ->
// 2.87 us, 16 texel regions 3.71 (max 3.79) -> 2.87, a constant 2.86 -> 2.46.
#include "refresh_core.h"

// W: word array indices
#define W_BASE 0
#define W_S 2
#define W_TAB 3
#define W_FINE 4
#define W_TEL_T 5
#define W_TEL_P 6
#define W_TEL_A 7
#define W_IDLE 8
#define W_TIMER 9
#define W_ADC 10
#define W_CC 11
#define W_MUL 12
#define W_SINE 13
#define W_ROW 14
// S: state indices
#define S_TOUCH 0
#define S_LOW 1
#define S_ADC12 2
#define S_F 3
#define S_V 4
#define S_FR 5
#define S_VR 6
#define S_K 7
#define S_KM 8
#define S_KV 9
#define S_KVM 10
#define S_VMAX 11
#define S_QMAX 12
#define S_REV 13
#define S_R0 14
#define S_SPAN 15
#define S_SHI 16
#define S_SLO 17
#define S_LQ8 18
#define S_LIFT 19
#define S_POS1 20
#define S_AMP 21
#define S_DUTY 22
#define S_COUNT 23
#define S_TEL_EVERY 24
#define S_Q 25
#define S_HALF 26
#define S_MAXC 27
#define S_WORST 28
#define S_OVR 29
#define S_PERIOD 30
#define S_ADC_CS 31
#define S_DEB 32
#define S_TEL_DIV 33
#define S_TEL_HEAD 34
#define V_BIAS 0x10000000
#define SLOTS 256
#define FAST_O 32768

#define LIKELY(x) __builtin_expect(!!(x), 1)
#define UNLIKELY(x) __builtin_expect(!!(x), 0)
#define AT(k) (base + (uintptr_t)w[k])
// (a + 2^(n-1)) >> n, rounded as refresh_viper.py writes it: floor((a + 2^(n-1)) / 2^n)
// = floor((floor(a / 2^(n-1)) + 1) / 2) for every int a - 3 Thumb-1 instructions
// with no 2^(n-1) to build (movs + lsls when n > 8)
#define RSHR(a, n) ((((a) >> ((n) - 1)) + 1) >> 1)

// BASE: what W's offsets are from. A 32-bit board's addresses all fit a word, and
// refresh_fast._resolve then makes BASE 0 - W's words are the addresses - so this
// build adds nothing: an RP2040 refresh keeps one register more and ~10 adds fewer
// (~20 cycles of its ~300 on the emulated Pico). A 64-bit port's is two halves.
static inline uintptr_t tc_base(const uint32_t *w) {
#if UINTPTR_MAX > 0xFFFFFFFFu
    return (uintptr_t)w[W_BASE] | (((uintptr_t)w[W_BASE + 1]) << 32);
#else
    (void)w;
    return 0;
#endif
}

// The cold paths, out of line (each in RAM too): kept out of tc_refresh they
// neither push its common path's branches out of a Thumb-1 conditional
// branch's reach (+-256 bytes: each costs a taken branch then) nor add to
// the registers gcc keeps live there.

// The ADC's reading where it is not START_MANY's last conversion as expected:
// START_MANY with CS changed (convert once, then run again), one conversion
// started by tc_refresh (wait for READY), or an STM32's DR.
TC_COLD static int32_t tc_adc_slow(volatile uint32_t *adc, int32_t cs) {
    int32_t mode = cs & 24, raw;
    if (mode & 16) {
        // STM32 (texel/hw/stm32_irq.py): W_ADC is ADC1's base; DR (word 19) holds the
        // conversion the refresh before started, then CR2 (word 2) |= ADON | SWSTART
        // starts the next one - no wait (a conversion takes ~1.5 us, a period 120)
        raw = (int32_t)(adc[19] & 0xFFF);
        adc[2] = adc[2] | 0x40000001u;
    } else if (mode) {                          // START_MANY, CS changed by other code
        adc[0] = (uint32_t)((cs ^ 8) | 4);
        while ((adc[0] & 0x100) == 0) {
        }
        raw = (int32_t)adc[1];
        adc[0] = (uint32_t)cs;
    } else {
        while ((adc[0] & 0x100) == 0) {         // READY after ~2 us
        }
        raw = (int32_t)adc[1];
    }
    return raw;
}

// _Tracker._track but for a touching finger read above the lift level: the
// touch-down (re-seed) and a reading below the lift level (a dropout, dead-
// reckoned, or the lift). Returns the position (-1: not touching; S_TOUCH says).
TC_COLD static int32_t tc_track_cold(int32_t *s, int32_t raw) {
    if (raw >= s[S_LIFT]) {                     // touch-down: re-seed
        s[S_LOW] = 0;
        int32_t d = raw - s[S_R0];
        if (s[S_REV]) {
            d = -d;
        }
        if ((uint32_t)d > (uint32_t)s[S_SPAN]) {
            d = d < 0 ? 0 : s[S_SPAN];
        }
        int32_t x = d * s[S_SHI] + ((d * s[S_SLO] + 8192) >> 14);
        if (x > s[S_QMAX]) {
            x = s[S_QMAX];
        }
        s[S_TOUCH] = 1;
        s[S_F] = x;
        s[S_FR] = 0;
        s[S_V] = V_BIAS;
        s[S_VR] = 0;
        return x;                               // v = 0: no lead
    }
    if (!s[S_TOUCH]) {
        return -1;
    }
    int32_t n = s[S_LOW] + 1;
    if (n >= s[S_DEB]) {
        s[S_TOUCH] = 0;
        s[S_LOW] = 0;
        return -1;
    }
    s[S_LOW] = n;                               // a dropout: dead-reckon
    int32_t v = s[S_V] - V_BIAS;
    int32_t nf = s[S_F] + v;
    if ((uint32_t)nf > (uint32_t)s[S_QMAX]) {
        nf = nf < 0 ? 0 : s[S_QMAX];
    }
    s[S_F] = nf;
    return nf + ((v * s[S_LQ8] + 128) >> 8);
}

// The first row of the table whose end is above p (Scene.amp's walk), from a
// row that does not hold p: forward past every row ending at or below p, or
// back while the row before also ends above p (the rows are sorted and
// disjoint, so their ends rise). The sentinel's end (2^30 - 1) stops the walk.
TC_COLD static const int32_t *tc_row(const int32_t *tab, const int32_t *row, int32_t p) {
    if (p >= row[1]) {
        do {
            row += 4;
        } while (p >= row[1]);
    } else {
        while (row != tab && p < row[-3]) {
            row -= 4;
        }
    }
    return row;
}

// A few samples played where they are (kinds/samples.py plan(): the 5 words at
// sp), out of line (not cold: gcc optimizes a cold function for size): in
// tc_refresh itself these two kinds cost every other kind 10-20 cycles
// (registers and branch reach; measured on the emulated Pico).
// K_TILE (vals, m, R = 65536 // m + 1): vals[o mod m], the mod by reciprocal
// as K_PLAN's j below offset 32,768. K_STRETCH (vals, A, B, n - 1, C =
// (B << 17) // (n - 1)): q = o*A + floor(o*B / (n-1)); floor(o*C / 2^17) is
// that floor or one less (o <= 2^15: the error is below o / 2^17 <= 1/4, and
// o*C < 2^32), one compare corrects it - no divider in the interrupt.
TC_RAMFUNC static int32_t tc_few(const uint32_t *w, int32_t kind, const uint32_t *sp, int32_t o) {
    const uint16_t *v = (const uint16_t *)(tc_base(w) + (uintptr_t)sp[0]);
    if (kind == 5) {
        uint32_t u = (uint32_t)o;
        uint32_t d = sp[3];
        uint32_t x = u * sp[2];
        uint32_t f = (u * sp[4]) >> 17;
        if (x - f * d >= d) {
            f += 1;
        }
        uint32_t q = u * sp[1] + f;
        v += q >> 15;
        int32_t a = v[0];
        return a + RSHR((v[1] - a) * (int32_t)(((q & 0x7FFF) + 1) >> 1), 14);
    }
    int32_t m = (int32_t)sp[1];
    int32_t k;
    if (LIKELY(o < FAST_O)) {
        k = o - ((o * (int32_t)sp[2]) >> 16) * m;
        if (k < 0) {
            k += m;
        }
    } else {
        k = o % m;
    }
    return v[k];
}

// One telemetry sample into the ring (every S_TEL_EVERY refreshes).
TC_COLD static void tc_tel(const uint32_t *w, int32_t *s, uint32_t t0, int32_t p, int32_t amp) {
    uintptr_t base = tc_base(w);
    int32_t h = s[S_TEL_HEAD];
    int32_t k = h & (SLOTS - 1);
    ((int32_t *)AT(W_TEL_T))[k] = (int32_t)(t0 & 0x3FFFFFFF);
    ((int32_t *)AT(W_TEL_P))[k] = p;
    ((uint16_t *)AT(W_TEL_A))[k] = (uint16_t)amp;
    s[S_TEL_HEAD] = (h + 1) & 0x3FFFFFFF;
}

TC_RAMFUNC void tc_refresh(const uint32_t *w) {
    uintptr_t base = tc_base(w);
    int32_t *s = (int32_t *)AT(W_S);
    volatile uint32_t *adc = (volatile uint32_t *)AT(W_ADC);
    int32_t cs = s[S_ADC_CS];
    if (!(cs & 24)) {
        adc[0] = (uint32_t)cs;                  // start one conversion
    }
    uint32_t t0 = *(volatile uint32_t *)AT(W_TIMER);
    int32_t raw;
    if (LIKELY((cs & 24) == 8)) {               // START_MANY: its last conversion
        raw = (int32_t)adc[1];
        if (UNLIKELY((int32_t)(adc[0] & 0x1F700F) != cs)) {
            raw = tc_adc_slow(adc, cs);
        }
    } else {
        raw = tc_adc_slow(adc, cs);
    }
    if (LIKELY(s[S_ADC12])) {
        raw = (raw << 4) | (raw >> 8);
    }
    // --- sensor: AdcLinearSensor.read + _Tracker._track
    int32_t p, touch = s[S_TOUCH];
    if (LIKELY(touch && raw >= s[S_LIFT])) {
        s[S_LOW] = 0;
        int32_t d = raw - s[S_R0];
        if (s[S_REV]) {
            d = -d;
        }
        int32_t span = s[S_SPAN];
        if (UNLIKELY((uint32_t)d > (uint32_t)span)) {
            d = d < 0 ? 0 : span;
        }
        int32_t x = d * s[S_SHI] + RSHR(d * s[S_SLO], 14);
        int32_t qmax = s[S_QMAX];
        if (UNLIKELY(x > qmax)) {
            x = qmax;
        }
        int32_t f = s[S_F];
        int32_t e = s[S_FR] + x - f;
        int32_t nf = f + (e >> s[S_K]);
        s[S_FR] = e & s[S_KM];
        s[S_F] = nf;
        int32_t v = s[S_V] - V_BIAS;
        e = s[S_VR] + (nf - f) - v;
        v += e >> s[S_KV];
        int32_t vmax = s[S_VMAX];
        if (UNLIKELY((uint32_t)(v + vmax) > (uint32_t)(vmax << 1))) {
            v = v > 0 ? vmax : -vmax;
            e = 0;
        }
        s[S_VR] = e & s[S_KVM];
        s[S_V] = v + V_BIAS;
        p = nf + ((v * s[S_LQ8] + 128) >> 8);
    } else {
        p = tc_track_cold(s, raw);
        touch = s[S_TOUCH];
    }
    // --- scene: Scene.amp
    int32_t amp;
    if (LIKELY(touch)) {
        int32_t qmax = s[S_QMAX];
        if (UNLIKELY((uint32_t)p > (uint32_t)qmax)) {
            p = p < 0 ? 0 : qmax;
        }
        p = (p + 128) >> 8;
        s[S_POS1] = p + 1;                      // (stored now: one register fewer below)
        // W_ROW (bytes from the table's start; 0 in a fresh W: row 0) is the row the
        // refresh before found: the finger moves a fraction of a position per refresh,
        // so it nearly always holds p again - 2 loads to check instead of a walk of up
        // to 16 rows (~7 cycles each). Each W is one scene's: a swap starts at row 0.
        const int32_t *tab = (const int32_t *)AT(W_TAB);
        uint32_t *wrow = (uint32_t *)(uintptr_t)&w[W_ROW];
        const int32_t *row = (const int32_t *)((uintptr_t)tab + *wrow);
        int32_t st = row[0];
        if (UNLIKELY(p >= row[1] || p < st)) {
            row = tc_row(tab, row, p);
            *wrow = (uint32_t)((uintptr_t)row - (uintptr_t)tab);
            st = row[0];
        }
        int32_t kind = row[2];
        if (UNLIKELY(p < st)) {                 // a gap (or before the first region)
            amp = (int32_t)w[W_IDLE];
        } else if (kind == 2) {                 // scene.K_PLAN: engine_int's sample
            const uint32_t *pl = w + row[3];    // t28, d28, L, gain Q14, R
            int32_t o = p - st;
            int32_t ln = (int32_t)pl[2];
            int32_t j, k;
            if (LIKELY(o < FAST_O)) {
                j = (o * (int32_t)pl[4]) >> 16;
                k = o - j * ln;
                if (k < 0) {
                    j -= 1;
                    k += ln;
                }
            } else {
                j = o / ln;
                k = o - j * ln;
            }
            const int32_t *t28 = (const int32_t *)(base + (uintptr_t)pl[0]);
            const int32_t *d28 = (const int32_t *)(base + (uintptr_t)pl[1]);
            uint32_t ph = ((uint32_t)t28[j] + (uint32_t)(k + 1) * (uint32_t)d28[j]) & 0x0FFFFFFF;
            const uint16_t *sine = (const uint16_t *)AT(W_SINE) + (ph >> 18);
            int32_t y0 = sine[0];
            int32_t sv = y0 + RSHR((sine[1] - y0) * (int32_t)((ph >> 2) & 0xFFFF), 16);
            amp = RSHR(sv * (int32_t)pl[3], 14);
        } else if (kind == 1) {
            amp = ((const uint16_t *)(base + (uintptr_t)(uint32_t)row[3]))[p - st];
        } else if (kind == 0) {
            amp = row[3];
        } else if (kind == 3) {                 // scene.K_CHUNK: the chunks' offsets
            int32_t o = p - st;
            const uint32_t *ct = (const uint32_t *)(base + (uintptr_t)(uint32_t)row[3]);
            amp = ((const uint16_t *)(base + (uintptr_t)ct[o >> 9]))[o & 511];
        } else {                                // scene.K_TILE, K_STRETCH
            amp = tc_few(w, kind, (const uint32_t *)(w + row[3]), p - st);
        }
    } else {
        s[S_POS1] = 0;                          // p + 1, p = -1
        amp = (int32_t)w[W_IDLE];
    }
    // --- duty: DutyLaw.duty
    const uint16_t *fine = (const uint16_t *)AT(W_FINE) + (amp >> 6);
    int32_t lo = fine[0];
    int32_t dc = (lo + (((fine[1] - lo) * (amp & 63)) >> 6) + s[S_HALF]) >> s[S_Q];
    int32_t maxc = s[S_MAXC];
    if (UNLIKELY(dc > maxc)) {
        dc = maxc;
    }
    *(volatile uint32_t *)AT(W_CC) = (uint32_t)dc * w[W_MUL];
    // --- bookkeeping and telemetry
    s[S_AMP] = amp;
    s[S_DUTY] = dc;
    s[S_COUNT] = (s[S_COUNT] + 1) & 0x3FFFFFFF;
    int32_t every = s[S_TEL_EVERY];
    if (every) {
        int32_t n = s[S_TEL_DIV] + 1;
        if (n >= every) {
            n = 0;
            tc_tel(w, s, t0, s[S_POS1] - 1, amp);
        }
        s[S_TEL_DIV] = n;
    }
    int32_t dt = (int32_t)(*(volatile uint32_t *)AT(W_TIMER) - t0);
    if (UNLIKELY(dt > s[S_WORST])) {
        s[S_WORST] = dt;
    }
    if (UNLIKELY(dt > s[S_PERIOD])) {
        s[S_OVR] = (s[S_OVR] + 1) & 0x3FFFFFFF;
    }
}
