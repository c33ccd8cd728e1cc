"""The part choices: one entry a part, with its KiCad 6 symbol and footprint
(both in Debian's kicad-symbols / kicad-footprints 6.0) and the orderable
manufacturer part number. Ratings are in the comments: the bus is designed for
up to 24 V, the tank for the README's estimate (24 V, Q = 20: 306 V amplitude on
the piezo, 3.66 A amplitude in the tank, `texelpad tank -L 390u -C 56n
--bus-volts 24 --q 20`)."""
from __future__ import annotations

from dataclasses import dataclass

from . import kicad


@dataclass(frozen=True)
class Choice:
    lib: str                # KiCad 6 symbol library (file stem in kicad.SYMBOL_DIR)
    symbol: str             # symbol name in that library
    footprint: str          # "Library:Footprint" in kicad.FOOTPRINT_DIR
    value: str
    manufacturer: str
    mpn: str                # manufacturer part number, as ordered


# --- semiconductors -----------------------------------------------------------------
# Half-bridge gate driver, one input with 520 ns built-in dead time, 10-20 V supply,
# 600 V high side; logic input threshold 2.5 V (3.3 V logic works).
IR2104 = Choice("Driver_FET", "IR2104", "Package_SO:SOIC-8_3.9x4.9mm_P1.27mm",
                "IR2104S", "Infineon", "IR2104STRPBF")
# Low-side driver for the minimal stage, non-inverting, 9 A, 4.5-18 V supply, input
# high >= 2.4 V. TC4420's pin-for-pin big brother: KiCad 6 has TC4422's symbol, not
# TC4420's (nor UCC27517's).
TC4422 = Choice("Driver_FET", "TC4422", "Package_DIP:DIP-8_W7.62mm",
                "TC4422", "Microchip", "TC4422AVPA")
# Half-bridge MOSFETs: 100 V (> 4 x a 24 V bus), 36 A, 44 mOhm at V_GS = 10 V,
# logic level (rated at 4.5 V too), TO-220 (G-D-S) for a heatsink.
MOSFET_LEG = Choice("Device", "Q_NMOS_GDS", "Package_TO_SOT_THT:TO-220-3_Vertical",
                    "IRL540N", "Infineon", "IRL540NPBF")
# Minimal (class-E-like) stage: the drain rings to ~3.6 x V_bus = 86 V at 24 V, more
# detuned: 200 V, 17 A, 0.18 Ohm at V_GS = 5 V, logic level, TO-220 (G-D-S).
MOSFET_CLASS_E = Choice("Device", "Q_NMOS_GDS", "Package_TO_SOT_THT:TO-220-3_Vertical",
                        "IRL640", "Vishay", "IRL640PBF")
# Bootstrap diode: V_bus + V_drv < 40 V across it; 200 V, 1 A, 25 ns ultrafast.
D_BOOT = Choice("Device", "D", "Diode_SMD:D_SMB", "MURS120", "onsemi", "MURS120T3G")
# Envelope detector: 30 V, 200 mA Schottky, SOD-323F.
BAT54 = Choice("Diode", "BAT54J", "Diode_SMD:D_SOD-323F", "BAT54J", "Nexperia", "BAT54J,115")

# --- the tank -------------------------------------------------------------------------
# The series inductor, 390 uH (the TPad Fire's value), toroid, horizontal mount.
# Rating to check before ordering: saturation and rms current above the tank's peak
# current (3.66 A amplitude in the 24 V, Q = 20 estimate) at 34 kHz.
L_TANK = Choice("Device", "L", "Inductor_THT:L_Toroid_Horizontal_D21.8mm_P19.10mm_Bourns_2100",
                "390uH", "Bourns", "2100LL-391-H-RC")
# C_block: >= 20 x the tank capacitance (56 nF) -> 2.2 uF; it sees the mean of the
# switch node (<= 24 V) plus a small AC voltage: 100 V metallised polyester film.
C_BLOCK = Choice("Device", "C", "Capacitor_THT:C_Rect_L18.0mm_W8.0mm_P15.00mm_FKS3_FKP3",
                 "2.2uF 100V film", "Panasonic", "ECQ-E1225KF")
# C_tune: the texelpad tank example's 15 nF (measure, then choose: `texelpad tank`);
# it carries the piezo voltage (306 V amplitude, ~216 V rms at 34 kHz): polypropylene,
# 630 V DC.
C_TUNE = Choice("Device", "C", "Capacitor_THT:C_Rect_L13.0mm_W5.0mm_P10.00mm_FKS3_FKP3_MKS4",
                "15nF 630V PP", "Panasonic", "ECW-FA2J153J")
# Bleed: 1 MOhm across the piezo as two 510 kOhm 1206 in series (200 V working each,
# 306 V peak across the pair).
R_BLEED = Choice("Device", "R", "Resistor_SMD:R_1206_3216Metric", "510k", "Yageo",
                 "RC1206JR-07510KL")

# --- passives ---------------------------------------------------------------------------
R_GATE = Choice("Device", "R", "Resistor_SMD:R_0805_2012Metric", "10R", "Yageo",
                "RC0805FR-0710RL")             # gate resistors: ringing damping
R_10K = Choice("Device", "R", "Resistor_SMD:R_0805_2012Metric", "10k", "Yageo",
               "RC0805FR-0710KL")              # driver-input pull-downs (stage off in reset)
R_100K = Choice("Device", "R", "Resistor_SMD:R_0805_2012Metric", "100k", "Yageo",
                "RC0805FR-07100KL")            # softpot pull-down, pickup divider and load
C_1U = Choice("Device", "C", "Capacitor_SMD:C_0805_2012Metric", "1uF 50V X7R", "Murata",
              "GRM21BR71H105KA12L")            # driver supply decoupling and bootstrap
C_10N = Choice("Device", "C", "Capacitor_SMD:C_0805_2012Metric", "10nF 50V X7R", "Murata",
               "GRM21BR71H103KA01L")           # envelope hold: 10 nF x 100 kOhm = 1 ms
C_BUS_FILM = Choice("Device", "C", "Capacitor_THT:C_Rect_L18.0mm_W8.0mm_P15.00mm_FKS3_FKP3",
                    "1uF 250V film", "Panasonic", "ECQ-E2105KF")   # at the MOSFETs
C_BULK = Choice("Device", "C_Polarized", "Capacitor_THT:CP_Radial_D8.0mm_P3.50mm",
                "100uF 50V", "Panasonic", "EEU-FR1H101")   # bus bulk, 50 V for a 24 V bus

# --- connectors ---------------------------------------------------------------------------
# Bus in: V_bus, V_drv (12 V for the drivers), GND.
J_POWER = Choice("Connector_Generic", "Conn_01x03",
                 "TerminalBlock_Phoenix:TerminalBlock_Phoenix_MKDS-1,5-3-5.08_1x03_P5.08mm_Horizontal",
                 "MKDS 1,5/3-5,08", "Phoenix Contact", "1935174")
# To the piezo discs (hundreds of volts: wire rated for it, see README Safety).
J_PIEZO = Choice("Connector_Generic", "Conn_01x02",
                 "TerminalBlock_Phoenix:TerminalBlock_Phoenix_MKDS-1,5-2-5.08_1x02_P5.08mm_Horizontal",
                 "MKDS 1,5/2-5,08", "Phoenix Contact", "1935161")
# The softpot's three pins (Spectra Symbol SP-L-0100-103-3%-RH, 100 mm, 10 kOhm, off board).
J_SOFTPOT = Choice("Connector_Generic", "Conn_01x03",
                   "Connector_PinHeader_2.54mm:PinHeader_1x03_P2.54mm_Vertical",
                   "softpot", "Samtec", "TSW-103-07-G-S")
# The pickup disc's two leads (off board).
J_PICKUP = Choice("Connector_Generic", "Conn_01x02",
                  "Connector_PinHeader_2.54mm:PinHeader_1x02_P2.54mm_Vertical",
                  "pickup disc", "Samtec", "TSW-102-07-G-S")
# A Pico plugs into two 20-way sockets, 17.78 mm apart (its pins 1-20 and 21-40).
J_PICO_ROW = Choice("Connector_Generic", "Conn_01x20",
                    "Connector_PinSocket_2.54mm:PinSocket_1x20_P2.54mm_Vertical",
                    "Pico socket", "Sullins", "PPTC201LFBN-RC")
# The pyboard is wired to the board by a 7-way header (its pins named on the silk).
J_PYBOARD = Choice("Connector_Generic", "Conn_01x07",
                   "Connector_PinHeader_2.54mm:PinHeader_1x07_P2.54mm_Vertical",
                   "pyboard", "Samtec", "TSW-107-07-G-S")

ALL = {name: c for name, c in globals().items() if isinstance(c, Choice)}


def make(choice: Choice, **kw):
    """A SKiDL part for this choice, with its footprint, value, manufacturer and MPN."""
    sk = kicad.skidl()
    part = sk.Part(choice.lib, choice.symbol, footprint=choice.footprint,
                   value=choice.value, **kw)
    part.fields["Manufacturer"] = choice.manufacturer
    part.fields["MPN"] = choice.mpn
    return part
