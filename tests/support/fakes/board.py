# A stand-in for CircuitPython's `board` module (Raspberry Pi Pico):
# GP0..GP28, A0..A2 (= GP26..GP28), LED (= GP25). Pin objects carry the
# GPIO number so the pwmio/analogio fakes can model the RP2040.
# Plain Python: no type hints, no f-strings.


class Pin:
    def __init__(self, number, name):
        self.number = number
        self.name = name

    def __repr__(self):
        return "board.%s" % self.name


for _n in range(29):
    globals()["GP%d" % _n] = Pin(_n, "GP%d" % _n)
A0 = GP26   # noqa: F821 (made in the loop above)
A1 = GP27   # noqa: F821
A2 = GP28   # noqa: F821
LED = GP25  # noqa: F821
