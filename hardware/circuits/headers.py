"""The microcontroller headers. A Raspberry Pi Pico plugs into two 20-way sockets:
its physical pins 1-20 on one, 21-40 on the other, so a Pico pin is named here by its
physical number (Pico datasheet, pinout). The pyboard v1.1 is wired by a 7-way header
whose pins carry the pyboard's pin names."""
from __future__ import annotations

from .parts import J_PICO_ROW, J_PYBOARD, make

# Pico GPIO -> physical pin (the ones texelpad's board files may name for these circuits)
PICO_GPIO = {16: 21, 17: 22, 26: 31, 27: 32, 28: 34}
PICO_GND = (3, 8, 13, 18, 23, 28, 38)
PICO_AGND = 33
PICO_3V3 = 36          # 3V3(OUT): the Pico's regulator, what the ADC measures against



def pico_pin_names() -> dict:
    """Physical pin -> the Pico's name for it (datasheet pinout)."""
    names = {3: "GND", 8: "GND", 13: "GND", 18: "GND", 23: "GND", 28: "GND", 38: "GND",
             30: "RUN", 31: "GP26_ADC0", 32: "GP27_ADC1", 33: "AGND", 34: "GP28_ADC2",
             35: "ADC_VREF", 36: "3V3_OUT", 37: "3V3_EN", 39: "VSYS", 40: "VBUS"}
    gpio = iter(list(range(0, 23)))
    for phys in range(1, 30):
        if phys not in names:
            names[phys] = "GP%d" % next(gpio)
    return names


# pyboard v1.1 pin name -> header pin
PYBOARD_PINS = {"Y1": 1, "X8": 2, "X19": 3, "X20": 4, "X23": 5, "X24": 6, "GND": 7}
PYBOARD_TITLES = {"X23": "X23 (A3.3V)", "X24": "X24 (AGND)"}


class Header:
    """A header: which connector pin a board pin name lands on."""

    def __init__(self, parts: list, where: dict):
        self.parts = parts
        self.where = where                  # board pin name -> (part, pin number)

    def pin(self, name):
        part, num = self.where[name]
        return part[num]

    def connect(self, nets: dict) -> None:
        """nets: board pin name -> net; every other header pin is marked unused (NC)."""
        used = set()
        for name, net in nets.items():
            pin = self.pin(name)
            pin += net
            used.add(self.where[name])
        for part in self.parts:
            for p in part.pins:
                if (part, int(p.num)) not in used:
                    p += part.circuit.NC    # unused: marked, so ERC stays strict


def pico() -> Header:
    """Two 1x20 sockets: the first holds physical pins 1-20, the second 21-40."""
    low, high = make(J_PICO_ROW), make(J_PICO_ROW)
    where: dict = {}
    for phys in range(1, 41):
        where["pin%d" % phys] = (low, phys) if phys <= 20 else (high, phys - 20)
    for phys, name in pico_pin_names().items():
        part, num = where["pin%d" % phys]
        part[num].name = name               # the socket pins carry the Pico's names
    for gpio, phys in PICO_GPIO.items():
        where[gpio] = where["pin%d" % phys]
    return Header([low, high], where)


def pico_nets(nets: dict, v33, agnd, gnd) -> dict:
    """The Pico's power pins added to nets (GPIO number -> net)."""
    out = dict(nets)
    out["pin%d" % PICO_3V3] = v33
    out["pin%d" % PICO_AGND] = agnd
    for phys in PICO_GND:
        out["pin%d" % phys] = gnd
    return out


def pyboard() -> Header:
    j = make(J_PYBOARD)
    for name, num in PYBOARD_PINS.items():
        j[num].name = PYBOARD_TITLES.get(name, name)
    return Header([j], {name: (j, num) for name, num in PYBOARD_PINS.items()})
