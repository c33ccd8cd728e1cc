"""The power stages (hardware/README.md, "Power stage"): a half-bridge leg with an
IR2104-class driver, the full bridge (two legs), the minimal low-side stage, and the
series tank they drive into the piezo discs."""
from __future__ import annotations

from dataclasses import dataclass

from . import kicad
from .parts import (C_1U, C_BLOCK, C_BULK, C_BUS_FILM, C_TUNE, D_BOOT, IR2104, J_PIEZO,
                    J_POWER, L_TANK, MOSFET_CLASS_E, MOSFET_LEG, R_10K, R_BLEED, R_GATE,
                    TC4422, make)


@dataclass
class Rails:
    """The power nets: V_bus (12-24 V, the tank's supply), V_drv (12 V for the gate
    drivers: IR2104 10-20 V, TC4422 4.5-18 V) and GND."""
    vbus: object
    vdrv: object
    gnd: object


def power_input() -> Rails:
    """The bus terminal block with the bulk capacitor. The supply is off board, so
    the nets are marked as driven (KiCad's PWR_FLAG)."""
    sk = kicad.skidl()
    rails = Rails(sk.Net("VBUS"), sk.Net("VDRV"), sk.Net("GND"))
    for net in (rails.vbus, rails.vdrv, rails.gnd):
        net.drive = sk.POWER
    j = make(J_POWER)
    j[1] += rails.vbus
    j[2] += rails.vdrv
    j[3] += rails.gnd
    bulk = make(C_BULK)                         # 100 uF at the bus input
    bulk[1] += rails.vbus
    bulk[2] += rails.gnd
    return rails


def pull_down(net, gnd, choice=R_10K) -> None:
    """A resistor from net to gnd (10 kOhm: the stage stays off while the
    microcontroller resets and its pins float)."""
    r = make(choice)
    r[1] += net
    r[2] += gnd


def in_series(top, bottom, a, mid, b) -> None:
    """Two two-pin parts in series from net a to net b through mid (a divider,
    or the bleed's two resistors that share its voltage)."""
    top[1] += a
    top[2] += mid
    bottom[1] += mid
    bottom[2] += b


def decouple(net, gnd, choice=C_1U) -> None:
    c = make(choice)
    c[1] += net
    c[2] += gnd


def half_bridge_leg(name: str, inp, rails: Rails):
    """One leg: IR2104 (one input, built-in dead time) -> two N-MOSFETs between
    V_bus and GND. Returns the switch node net SW_<name>."""
    sk = kicad.skidl()
    sw = sk.Net("SW_" + name)
    drv = make(IR2104)
    drv["IN"] += inp
    pull_down(inp, rails.gnd)
    drv["VCC"] += rails.vdrv
    drv["~{SD}"] += rails.vdrv               # always enabled: the input's pull-down is the off state
    drv["COM"] += rails.gnd
    drv["VS"] += sw
    decouple(rails.vdrv, rails.gnd)          # 1 uF at the driver's supply pin
    boot = make(D_BOOT)                      # bootstrap: V_drv -> VB while the low side is on
    boot["A"] += rails.vdrv
    boot["K"] += drv["VB"]
    cboot = make(C_1U)                       # 1 uF >> the high-side gate charge
    cboot[1] += drv["VB"]
    cboot[2] += sw
    hi, lo = make(MOSFET_LEG), make(MOSFET_LEG)
    for q, out, drain, source in ((hi, "HO", rails.vbus, sw), (lo, "LO", sw, rails.gnd)):
        rg = make(R_GATE)
        rg[1] += drv[out]
        rg[2] += q["G"]
        q["D"] += drain
        q["S"] += source
    decouple(rails.vbus, rails.gnd, C_BUS_FILM)   # 1 uF film across the leg: short loop
    return sw


def piezo(hot, ret) -> None:
    """The piezo terminal with C_tune and the 1 MOhm bleed across it."""
    sk = kicad.skidl()
    ctune = make(C_TUNE)
    ctune[1] += hot
    ctune[2] += ret
    mid = sk.Net("BLEED_MID")
    in_series(make(R_BLEED), make(R_BLEED), hot, mid, ret)
    j = make(J_PIEZO)
    j[1] += hot
    j[2] += ret


def tank(drive, ret) -> None:
    """Series inductor and C_block from the drive node into the piezo; the piezo's
    other side is ret (GND for one leg, the other leg's switch node for a bridge)."""
    sk = kicad.skidl()
    lc, hot = sk.Net("TANK_LC"), sk.Net("PIEZO_HOT")
    ind, cblock = make(L_TANK), make(C_BLOCK)
    ind[1] += drive
    ind[2] += lc
    cblock[1] += lc
    cblock[2] += hot
    piezo(hot, ret)


def single_leg(carrier, rails: Rails) -> None:
    """drive "single": one leg, the piezo to GND."""
    tank(half_bridge_leg("A", carrier, rails), rails.gnd)


def full_bridge(carrier_a, carrier_b, rails: Rails) -> None:
    """drive "bridge": leg A and leg B (its input the complement of A's), the tank
    between the two switch nodes."""
    sw_a = half_bridge_leg("A", carrier_a, rails)
    sw_b = half_bridge_leg("B", carrier_b, rails)
    tank(sw_a, sw_b)


def minimal_low_side(carrier, rails: Rails) -> None:
    """The minimal variant: V_bus -> L -> drain, one MOSFET to GND driven by a
    low-side driver; the piezo through C_block from the drain to GND. The drain rings
    to ~3.6 x V_bus (class-E-like): the 200 V MOSFET."""
    sk = kicad.skidl()
    drain, hot = sk.Net("DRAIN"), sk.Net("PIEZO_HOT")
    drv = make(TC4422)
    drv["INPUT"] += carrier
    pull_down(carrier, rails.gnd)
    drv["VDD"] += rails.vdrv
    drv["GND"] += rails.gnd
    decouple(rails.vdrv, rails.gnd)
    q, rg = make(MOSFET_CLASS_E), make(R_GATE)
    rg[1] += drv["OUTPUT"]
    rg[2] += q["G"]
    q["S"] += rails.gnd
    q["D"] += drain
    ind = make(L_TANK)
    ind[1] += rails.vbus
    ind[2] += drain
    decouple(rails.vbus, rails.gnd, C_BUS_FILM)
    cblock = make(C_BLOCK)
    cblock[1] += drain
    cblock[2] += hot
    piezo(hot, rails.gnd)
