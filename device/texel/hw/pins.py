# The classroom kit's button and LED (texel/kit.py) on the ports with
# machine.Pin (rp2, stm32). The virtual board has its own (hw/virtual.py
# kit_button, kit_led). Read and written from the kit's main loop only,
# never from the refresh interrupt.
import machine


def bootsel():
    """The Pico's BOOTSEL button, 1 while pressed. MicroPython reads it with
    interrupts off for ~9 us (ports/rp2/modrp2.c: MICROPY_HW_BOOTSEL_DELAY_US
    8): at the kit's 10 ms poll one refresh in 83 starts up to that late.
    A module attribute, looked up at every read: tests replace it."""
    import rp2
    return rp2.bootsel_button()


def _bootsel_read():
    return 1 if bootsel() else 0


def button(spec):
    """A function returning 1 while the button of `spec` ({"pin", "active_low"},
    runtime/boards.py BUTTON_KEYS) is pressed, 0 otherwise."""
    pin = spec["pin"]
    if pin == "bootsel":
        return _bootsel_read
    low = spec.get("active_low", 1)
    p = machine.Pin(pin, machine.Pin.IN, machine.Pin.PULL_UP if low else machine.Pin.PULL_DOWN)
    if low:
        return lambda: 1 - p.value()
    return p.value


def led(spec):
    """A function setting the LED of `spec` on (1) or off (0)."""
    low = spec.get("active_low", 0)
    p = machine.Pin(spec["pin"], machine.Pin.OUT)
    if low:
        return lambda on: p.value(0 if on else 1)
    return lambda on: p.value(1 if on else 0)
