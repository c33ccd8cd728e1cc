"""One circuit per board file (boards/<name>/board.json), plus the minimal low-side
variant, and the check that a board file and its circuit agree on every pin."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from . import headers, kicad, pickup, sensor, stages

ROOT = Path(__file__).resolve().parents[2]
CARRIER_NETS = ("CARRIER_A", "CARRIER_B")       # carrier.pins[0] -> leg A, [1] -> leg B
DRIVER_INPUTS = ("IN", "INPUT")                 # IR2104's IN, TC4422's INPUT

# circuit name -> (board file, power stage, microcontroller)
CIRCUITS = {
    "pico": ("pico", "single", "pico"),
    "pico_bridge": ("pico_bridge", "bridge", "pico"),
    "pyboard": ("pyboard", "bridge", "pyboard"),
    "pico_minimal": ("pico", "minimal", "pico"),
}
TITLES = {
    "pico": "Raspberry Pi Pico, one half-bridge leg (IR2104)",
    "pico_bridge": "Raspberry Pi Pico, full bridge (2 x IR2104)",
    "pyboard": "pyboard v1.1, full bridge (2 x IR2104), TIM8 CH1/CH1N",
    "pico_minimal": "Raspberry Pi Pico, minimal low-side stage (TC4422, one MOSFET)",
}


@dataclass
class Built:
    name: str
    circuit: object
    header: headers.Header
    stage: str

    def net_at(self, board_pin):
        """The net the header pin for this board pin name is on (None: unconnected)."""
        pin = self.header.pin(board_pin)
        return None if pin.net is None or pin.net is self.circuit.NC else pin.net

    def nets(self) -> dict:
        return {n.name: n for n in self.circuit.get_nets()}


def build(name: str) -> Built:
    """A fresh SKiDL circuit for CIRCUITS[name]."""
    sk = kicad.skidl()
    _, stage, mcu = CIRCUITS[name]
    circuit = sk.Circuit()
    with circuit:
        rails = stages.power_input()
        v33, agnd = sk.Net("+3V3A"), sk.Net("AGND")     # from the microcontroller board
        for net in (v33, agnd):
            net.drive = sk.POWER
        wiper = sensor.softpot(v33, agnd)
        env = pickup.envelope(agnd)
        carrier = [sk.Net(n) for n in CARRIER_NETS[:2 if stage == "bridge" else 1]]
        if stage == "single":
            stages.single_leg(carrier[0], rails)
        elif stage == "bridge":
            stages.full_bridge(carrier[0], carrier[1], rails)
        else:
            stages.minimal_low_side(carrier[0], rails)
        if mcu == "pico":
            header = headers.pico()
            mine = {16: carrier[0], 26: wiper, 27: env}
            if len(carrier) > 1:
                mine[17] = carrier[1]
            header.connect(headers.pico_nets(mine, v33, agnd, rails.gnd))
        else:
            header = headers.pyboard()
            header.connect({"Y1": carrier[0], "X8": carrier[1], "X19": wiper, "X20": env,
                            "X23": v33, "X24": agnd, "GND": rails.gnd})
    return Built(name, circuit, header, stage)


def read_board(board: str) -> tuple[dict, str]:
    path = ROOT / "boards" / board / "board.json"
    return json.loads(path.read_text()), str(path.relative_to(ROOT))


def _label(pin) -> str:
    return "GP%d (pin %d)" % (pin, headers.PICO_GPIO[pin]) if isinstance(pin, int) and \
        pin in headers.PICO_GPIO else str(pin)


def disagreements(built: Built, board: dict, source: str) -> list[str]:
    """Where the board file and the circuit disagree, one message a pin, each naming
    the file, the key and the pin ([] when they agree)."""
    out = []
    drive = board["carrier"]["drive"]
    legs = {"single": 1, "minimal": 1, "bridge": 2}[built.stage]
    if {"single": 1, "bridge": 2}.get(drive) != legs:
        out.append("%s: carrier.drive: %r, but circuit %r has %d leg(s)"
                   % (source, drive, built.name, legs))
    want = [("carrier.pins[%d]" % i, p, CARRIER_NETS[i])
            for i, p in enumerate(board["carrier"]["pins"][:2])]
    want += [("sensor.pins[0]", board["sensor"]["pins"][0], sensor.WIPER)]
    for key, pin, net_name in want:
        try:
            net = built.net_at(pin)
        except KeyError:
            out.append("%s: %s: %s is not on circuit %r's header"
                       % (source, key, _label(pin), built.name))
            continue
        got = net.name if net is not None else "nothing"
        if got != net_name:
            out.append("%s: %s: %s: circuit %r connects it to %s, the board file means %s"
                       % (source, key, _label(pin), built.name, got, net_name))
    out += _driver_inputs(built, source)
    return out


def _driver_inputs(built: Built, source: str) -> list[str]:
    """Each carrier net reaches one gate driver's input."""
    out = []
    nets = built.nets()
    legs = 2 if built.stage == "bridge" else 1
    for name in CARRIER_NETS[:legs]:
        net = nets.get(name)
        inputs = [p for p in (net.pins if net is not None else [])
                  if p.name in DRIVER_INPUTS and p.part.name in ("IR2104", "TC4422")]
        if len(inputs) != 1:
            out.append("%s: circuit %r: net %s reaches %d gate-driver inputs, not 1"
                       % (source, built.name, name, len(inputs)))
    return out
