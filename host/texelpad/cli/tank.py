"""`texelpad tank`: the resonant tank calculator (texelpad.plate.tank)."""
from __future__ import annotations

import argparse

from .errors import EXIT_OK, CliError


def add_tank(p: argparse.ArgumentParser) -> None:
    from ..plate.tank import arg_quantity
    p.description = ("f = 1/(2*pi*sqrt(L*C)) for the series inductor and the piezo plate "
                    "(hardware/README.md). Give two of -L, -C, -f for the third; or the "
                    "piezo's capacitance (--piezo) with -f for the "
                    "series inductor, with -L and -f for the tuning capacitor to add, or with "
                    "-L for the frequency. Values take SI prefixes: 390u, 390uH, 56n, 34k.")
    p.add_argument("-L", "--inductance", type=arg_quantity("H"), metavar="H",
                   help="series inductance, e.g. 390u (the TPad Fire used 390 uH)")
    p.add_argument("-C", "--capacitance", type=arg_quantity("F"), metavar="F",
                   help="total tank capacitance, e.g. 56n")
    p.add_argument("-f", "--frequency", type=arg_quantity("Hz"), metavar="HZ",
                   help="resonant frequency, e.g. 34k (the plate's measured resonance)")
    p.add_argument("--piezo", type=arg_quantity("F"), metavar="F",
                   help="the piezo discs' capacitance (an LCR meter at ~1 kHz gives a first "
                        "value; final tuning is measured)")
    p.add_argument("--bus-volts", type=arg_quantity("V"), metavar="V",
                   help="with --q: estimate the piezo voltage and tank current at full amplitude")
    p.add_argument("--q", type=arg_quantity(""), metavar="Q",
                   help="the loaded tank's quality factor (measure: f0 / -3 dB bandwidth); "
                        "also gives how fast the amplitude follows the duty (tau = Q/(pi f0)) "
                        "and the finest texture period the plate renders")
    p.add_argument("--drive", choices=("single", "bridge"), default="single",
                   help="for the estimate: single-ended or full bridge (default single)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON (SI units)")
    p.set_defaults(func=cmd_tank)


def cmd_tank(args: argparse.Namespace) -> int:
    import json
    from ..plate.tank import TankInputError, report
    try:
        text, data = report(args.inductance, args.capacitance, args.frequency, args.piezo,
                            args.bus_volts, args.q, args.drive)
    except TankInputError as e:
        raise CliError(e.flag, str(e)) from None
    except (ValueError, ArithmeticError) as e:    # report() turns these into the above
        raise CliError("", "cannot compute with these values: %s" % e) from None
    print(json.dumps(data, indent=2) if args.json else text)
    return EXIT_OK

