# A stand-in for CircuitPython's `analogio`: AnalogIn(pin).value returns
# scripted 16-bit values (cycled); reading allocates nothing.
# Plain Python: no type hints, no f-strings.
VALUES = {}                 # gpio -> list of values
INS = []


def script(pin, values):
    VALUES[pin.number] = list(values)
    for a in INS:
        if a.pin.number == pin.number:
            a._values = VALUES[pin.number]
            a._i = 0


class AnalogIn:
    def __init__(self, pin):
        if not 26 <= pin.number <= 29:
            raise ValueError("%s: Invalid pin" % pin.name)
        self.pin = pin
        self._values = VALUES.get(pin.number) or [0]
        self._i = 0
        self.reads = 0
        INS.append(self)

    def _get(self):
        v = self._values[self._i]
        self._i += 1
        if self._i >= len(self._values):
            self._i = 0
        self.reads += 1
        return v

    value = property(_get)
    reference_voltage = 3.3

    def deinit(self):
        pass


def reset():
    VALUES.clear()
    del INS[:]
