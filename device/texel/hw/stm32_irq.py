# hw/stm32_irq.py - the fused refresh as an STM32's refresh interrupt (hw/stm32.py, pyb.Timer's hard callback):
# one viper call into the refresh core - the C core's refresh(W) where the firmware or the
# native module has it, else refresh_viper.core(W's address) - on the word array W that
# refresh_fast.FastRefresh.use_stm32_registers() pointed at the chip's registers (ADC1, TIM2's
# microsecond counter, the carrier's CCR). No Python between the timer and the core: the
# Python refresh (FastRefresh.step around pyb.ADC.read) took 92 us a refresh on the emulated
# F405 (bench/stm32.py). Imported only where app.py found a board with stm32_registers() and
# a native emitter (the stm32 port has viper: armv7emsp).
import micropython

_rf = None          # texel.runtime.refresh_fast, handed over by arm() (hw/ imports no runtime)
_CORE = None        # the core's entry: _texelcore.refresh or refresh_viper.core
ENGINE = None       # which: "c" or "viper"


def arm(refresh_fast):
    """Choose the core (refresh_fast._engine(): the C core where it is) and
    return the interrupt's callback: a viper function of the timer that reads
    refresh_fast's current W at each call."""
    global _rf, _CORE, ENGINE
    _rf = refresh_fast
    c, v = _rf._engine()
    if c is not None:
        _CORE, ENGINE = c.refresh, "c"
        return _irq_c
    _CORE, ENGINE = v, "viper"
    return _irq_viper


# W (or its address) is read at each call: a push swaps in a new array (refresh_fast._install)
@micropython.viper
def _irq_c(t):
    _CORE(_rf._W)


@micropython.viper
def _irq_viper(t):
    _CORE(_rf._WA)
