"""What build.py writes for a circuit: the KiCad 6 netlist, the BOM CSV and the
netlistsvg input (its SVG drawn by the npm package netlistsvg). Everything is
deterministic - no dates, no paths, parts and nets sorted - so the committed files in
hardware/design/ can be compared with a fresh build."""
from __future__ import annotations

import csv
import io
import json
import re

from . import boards, erc

SOURCE = "hardware/circuits/boards.py"
POWER_NETS = {"GND": "gnd", "AGND": "gnd", "VBUS": "vcc", "VDRV": "vcc", "+3V3A": "vcc"}


def stable_tags(circuit) -> None:
    """SKiDL tags parts with random strings unless told; the reference is stable."""
    for part in circuit.parts:
        part.tag = str(part.ref)


def netlist(built: boards.Built) -> str:
    circuit = built.circuit
    stable_tags(circuit)
    circuit.no_files = True
    from skidl.logger import rt_logger
    # quiet: the one warning left is SKiDL's about the top sheet having no tag
    with erc.collecting(rt_logger):
        text = str(circuit.generate_netlist(do_backup=False, track_src=False))
    text = re.sub(r'\(source "[^"]*"\)', '(source "%s")' % SOURCE, text)
    text = re.sub(r'\(date "[^"]*"\)', '(date "")', text)
    return text


def _natural(ref: str):
    m = re.match(r"([A-Za-z_]+)(\d+)$", ref)
    return (m.group(1), int(m.group(2))) if m else (ref, 0)


BOM_COLUMNS = ("references", "part", "value", "footprint", "manufacturer",
               "manufacturer part", "quantity")


def bom_rows(built: boards.Built) -> list[dict]:
    """One row a distinct part (same symbol, value, footprint and MPN), grouped."""
    groups: dict = {}
    for p in built.circuit.parts:
        key = ("%s:%s" % (p.lib.filename if hasattr(p.lib, "filename") else p.lib, p.name),
               str(p.value), str(p.footprint), p.fields.get("Manufacturer", ""),
               p.fields.get("MPN", ""))
        groups.setdefault(key, []).append(str(p.ref))
    rows = []
    for key, refs in groups.items():
        refs.sort(key=_natural)
        rows.append(dict(zip(BOM_COLUMNS, (" ".join(refs),) + key + (len(refs),))))
    rows.sort(key=lambda r: _natural(r["references"].split()[0]))
    return rows


def bom_csv(built: boards.Built) -> str:
    out = io.StringIO()
    w = csv.DictWriter(out, BOM_COLUMNS, lineterminator="\n")
    w.writeheader()
    w.writerows(bom_rows(built))
    return out.getvalue()


def _cell_type(part) -> str:
    """The netlistsvg analog skin's symbol for a part (its aliases r_v, c_v, l_v, d_v,
    d_sk_v); anything else is drawn as a box titled with its reference and value."""
    two = {"R": "r_v", "C": "c_v", "C_Polarized": "c_v", "L": "l_v", "D": "d_v"}
    if part.name in two:
        return two[part.name]
    if part.name.startswith("BAT54"):
        return "d_sk_v"
    return "%s %s" % (part.ref, part.value)


def _ports(part) -> dict:
    """port name -> pin, for the skin's two-terminal symbols A/B or +/-."""
    kind = _cell_type(part)
    pins = [p for p in part.pins if p.net is not None and p.net is not part.circuit.NC]
    if kind.startswith("d_"):
        return {"+": part["A"], "-": part["K"]}
    if kind in ("r_v", "c_v", "l_v"):
        return {"A": part.pins[0], "B": part.pins[1]}
    out = {}
    for p in sorted(pins, key=lambda p: int(p.num)):
        label = p.name if p.name not in ("~", "") else "%s" % p.num
        out["%s_%s" % (p.num, label) if list(x.name for x in pins).count(p.name) > 1
            else label] = p
    return out


def netlistsvg_json(built: boards.Built) -> str:
    """The circuit as netlistsvg's (Yosys) JSON: one cell a part, one bit a net;
    a power net becomes a vcc/gnd symbol at each pin rather than a long wire."""
    bits: dict = {}
    cells: dict = {}
    counter = [1]

    def fresh() -> int:
        counter[0] += 1
        return counter[0]

    for part in sorted(built.circuit.parts, key=lambda p: _natural(str(p.ref))):
        conns, dirs = {}, {}
        for port, pin in _ports(part).items():
            name = pin.net.name if pin.net is not None else None
            if name in POWER_NETS:
                bit = fresh()
                # a plain identifier: the skin uses the cell id as a CSS class
                cell = re.sub(r"\W", "_", "%s_%s_%s" % (name, part.ref, port))
                cells[cell] = {
                    "type": POWER_NETS[name], "connections": {"A": [bit]},
                    "port_directions": {"A": "input"}, "attributes": {"name": name}}
            else:
                bit = bits.setdefault(name, None) or bits.__setitem__(name, fresh()) \
                    or bits[name]
            conns[port] = [bit]
            dirs[port] = "output" if pin.func.name in ("OUTPUT", "PWROUT") else "input"
        cells[str(part.ref)] = {"type": _cell_type(part), "connections": conns,
                                "port_directions": dirs,
                                "attributes": {"ref": str(part.ref), "value": str(part.value)}}
    doc = {"modules": {built.name: {"ports": {}, "cells": cells,
                                    "netnames": {n: {"bits": [b]} for n, b in sorted(bits.items())
                                                 if n}}}}
    return json.dumps(doc, indent=1, sort_keys=True) + "\n"
