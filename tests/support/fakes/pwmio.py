# A recording stand-in for CircuitPython's `pwmio`, modelling 10.2.1's
# raspberrypi port (ports/raspberrypi/common-hal/pwmio/PWMOut.c):
#   TOP = cpu_hz // frequency - 1 (divider 1, period TOP+1 clocks),
#   .frequency = cpu_hz // (TOP+1) (its actual_frequency),
#   compare = TOP + 1 if duty_cycle == 65535 else
#             (duty_cycle * TOP + 32767) // 65534, at least 1 when duty_cycle > 0.
# Every duty_cycle store is counted and its compare value kept; the setter
# allocates nothing. Plain Python: no type hints, no f-strings.
CPU_HZ = 125000000
OUTS = []
IN_USE = {}                 # gpio -> PWMOut


class PWMOut:
    def __init__(self, pin, *, duty_cycle=0, frequency=500, variable_frequency=False):
        if pin.number in IN_USE:
            raise ValueError("%s in use" % pin.name)
        if frequency <= 0 or frequency > CPU_HZ // 2:
            raise ValueError("Invalid frequency")
        self.pin = pin
        self.variable_frequency = variable_frequency
        self.top = min(65534, CPU_HZ // frequency - 1)
        self.frequency = CPU_HZ // (self.top + 1)
        self.writes = 0
        self.compare = 0
        self._duty = 0
        self.deinited = False
        self.duty_cycle = duty_cycle
        self.writes = 0                     # count the backend's writes only
        IN_USE[pin.number] = self
        OUTS.append(self)

    def _get(self):
        return self._duty

    def _set(self, d):
        if not 0 <= d <= 65535:
            raise ValueError("duty_cycle must be 0-65535")
        self._duty = d
        if d == 65535:
            self.compare = self.top + 1
        else:
            self.compare = (d * self.top + 32767) // 65534
            if self.compare == 0 and d:
                self.compare = 1
        self.writes += 1

    duty_cycle = property(_get, _set)

    def level(self, count):
        """Output at counter value count (0..TOP): high while count < compare."""
        if self.deinited:
            return None
        return 1 if count < self.compare else 0

    def deinit(self):
        self.deinited = True
        IN_USE.pop(self.pin.number, None)


def reset():
    global CPU_HZ
    CPU_HZ = 125000000
    del OUTS[:]
    IN_USE.clear()
