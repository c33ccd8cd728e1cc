// See refresh_core.h. Indices are refresh_viper.py's W_* and S_* (checked there
// against this file's copies at import: _C_LAYOUT).
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

TC_RAMFUNC void tc_refresh(const uint32_t *w) {
    uintptr_t base = (uintptr_t)w[W_BASE];
#if UINTPTR_MAX > 0xFFFFFFFFu
    base |= ((uintptr_t)w[W_BASE + 1]) << 32;
#endif
#define AT(k) (base + (uintptr_t)w[k])
    int32_t *s = (int32_t *)AT(W_S);
    volatile uint32_t *adc = (volatile uint32_t *)AT(W_ADC);
    int32_t cs = s[S_ADC_CS];
    if (!(cs & 24)) {
        adc[0] = (uint32_t)cs;                  // start one conversion
    }
    volatile uint32_t *clock = (volatile uint32_t *)AT(W_TIMER);
    uint32_t t0 = clock[0];
    int32_t touch = s[S_TOUCH];
    int32_t raw;
    if (cs & 16) {
        // STM32 (texel/hw/stm32_irq.py): W_ADC is ADC1's base; DR (word 19) holds the
        // conversion the refresh before started, then CR2 (word 2) |= ADON | SWSTART
        // starts the next one - no wait (a conversion takes ~1.5 us, a period 120)
        raw = (int32_t)(adc[19] & 0xFFF);
        adc[2] = adc[2] | 0x40000001u;
    } else if (cs & 8) {                        // START_MANY: its last conversion
        raw = (int32_t)adc[1];
        if ((int32_t)(adc[0] & 0x1F700F) != cs) {
            adc[0] = (uint32_t)((cs ^ 8) | 4);
            while ((adc[0] & 0x100) == 0) {
            }
            raw = (int32_t)adc[1];
            adc[0] = (uint32_t)cs;
        }
    } else {
        while ((adc[0] & 0x100) == 0) {         // READY after ~2 us
        }
        raw = (int32_t)adc[1];
    }
    if (s[S_ADC12]) {
        raw = (raw << 4) | (raw >> 8);
    }
    // --- sensor: AdcLinearSensor.read + _Tracker._track
    int32_t p = -1, nf = 0, v = 0;
    if (raw < s[S_LIFT]) {
        if (touch) {
            int32_t n = s[S_LOW] + 1;
            if (n >= s[S_DEB]) {
                touch = 0;
                s[S_TOUCH] = 0;
                s[S_LOW] = 0;
            } else {                            // a dropout: dead-reckon
                s[S_LOW] = n;
                v = s[S_V] - V_BIAS;
                nf = s[S_F] + v;
                if ((uint32_t)nf > (uint32_t)s[S_QMAX]) {
                    nf = nf < 0 ? 0 : s[S_QMAX];
                }
                s[S_F] = nf;
                p = nf + ((v * s[S_LQ8] + 128) >> 8);
            }
        }
    } else {
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
        if (touch) {
            int32_t f = s[S_F];
            int32_t e = s[S_FR] + x - f;
            nf = f + (e >> s[S_K]);
            s[S_FR] = e & s[S_KM];
            v = s[S_V] - V_BIAS;
            e = s[S_VR] + (nf - f) - v;
            v += e >> s[S_KV];
            if ((uint32_t)(v + s[S_VMAX]) > (uint32_t)(s[S_VMAX] << 1)) {
                v = v > 0 ? s[S_VMAX] : -s[S_VMAX];
                e = 0;
            }
            s[S_VR] = e & s[S_KVM];
            s[S_F] = nf;
            s[S_V] = v + V_BIAS;
        } else {                                // touch-down: re-seed
            touch = 1;
            s[S_TOUCH] = 1;
            s[S_F] = x;
            s[S_FR] = 0;
            s[S_V] = V_BIAS;
            s[S_VR] = 0;
            nf = x;
            v = 0;
        }
        p = nf + ((v * s[S_LQ8] + 128) >> 8);
    }
    // --- scene: Scene.amp
    int32_t amp;
    if (touch) {
        if ((uint32_t)p > (uint32_t)s[S_QMAX]) {
            p = p < 0 ? 0 : s[S_QMAX];
        }
        p = (p + 128) >> 8;
        const int32_t *tab = (const int32_t *)AT(W_TAB);
        int32_t i = 1;
        while (p >= tab[i]) {
            i += 4;
        }
        int32_t st = tab[i - 1], kind = tab[i + 1];
        if (p < st) {
            amp = (int32_t)w[W_IDLE];
        } else if (kind == 2) {                 // scene.K_PLAN: engine_int's sample
            int32_t b = tab[i + 2];
            int32_t o = p - st;
            int32_t ln = (int32_t)w[b + 2];
            int32_t j, k;
            if (o < FAST_O) {
                j = (o * (int32_t)w[b + 4]) >> 16;
                k = o - j * ln;
                if (k < 0) {
                    j -= 1;
                    k += ln;
                }
            } else {
                j = o / ln;
                k = o - j * ln;
            }
            const int32_t *t28 = (const int32_t *)AT(b);
            const int32_t *d28 = (const int32_t *)AT(b + 1);
            uint32_t ph = ((uint32_t)t28[j] + (uint32_t)(k + 1) * (uint32_t)d28[j]) & 0x0FFFFFFF;
            const uint16_t *sine = (const uint16_t *)AT(W_SINE);
            int32_t ii = (int32_t)(ph >> 18);
            int32_t y0 = sine[ii];
            int32_t sv = y0 + (((sine[ii + 1] - y0) * (int32_t)((ph >> 2) & 0xFFFF) + 32768) >> 16);
            amp = (sv * (int32_t)w[b + 3] + 8192) >> 14;
        } else if (kind == 1) {
            amp = ((const uint16_t *)(base + (uintptr_t)(uint32_t)tab[i + 2]))[p - st];
        } else if (kind == 0) {
            amp = tab[i + 2];
        } else {                                // scene.K_CHUNK: the chunks' offsets
            int32_t o = p - st;
            const uint32_t *ct = (const uint32_t *)(base + (uintptr_t)(uint32_t)tab[i + 2]);
            amp = ((const uint16_t *)(base + (uintptr_t)ct[o >> 9]))[o & 511];
        }
    } else {
        amp = (int32_t)w[W_IDLE];
    }
    // --- duty: DutyLaw.duty
    const uint16_t *fine = (const uint16_t *)AT(W_FINE);
    int32_t j = amp >> 6;
    int32_t lo = fine[j];
    int32_t dc = (lo + (((fine[j + 1] - lo) * (amp & 63)) >> 6) + s[S_HALF]) >> s[S_Q];
    if (dc > s[S_MAXC]) {
        dc = s[S_MAXC];
    }
    *(volatile uint32_t *)AT(W_CC) = (uint32_t)dc * w[W_MUL];
    // --- bookkeeping and telemetry
    s[S_POS1] = p + 1;
    s[S_AMP] = amp;
    s[S_DUTY] = dc;
    s[S_COUNT] = (s[S_COUNT] + 1) & 0x3FFFFFFF;
    if (s[S_TEL_EVERY]) {
        int32_t n = s[S_TEL_DIV] + 1;
        if (n >= s[S_TEL_EVERY]) {
            n = 0;
            int32_t h = s[S_TEL_HEAD];
            int32_t k = h & (SLOTS - 1);
            ((int32_t *)AT(W_TEL_T))[k] = (int32_t)(t0 & 0x3FFFFFFF);
            ((int32_t *)AT(W_TEL_P))[k] = p;
            ((uint16_t *)AT(W_TEL_A))[k] = (uint16_t)amp;
            s[S_TEL_HEAD] = (h + 1) & 0x3FFFFFFF;
        }
        s[S_TEL_DIV] = n;
    }
    int32_t dt = (int32_t)(clock[0] - t0);
    if (dt > s[S_WORST]) {
        s[S_WORST] = dt;
    }
    if (dt > s[S_PERIOD]) {
        s[S_OVR] = (s[S_OVR] + 1) & 0x3FFFFFFF;
    }
#undef AT
}
