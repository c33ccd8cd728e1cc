"""texelpad's driver boards as code (SKiDL 3.0 on KiCad 6's libraries).

parts     the part choices: symbol, footprint, manufacturer and part number
stages    the power stages: half-bridge leg, full bridge, the minimal low-side stage, the tank
sensor    the softpot input with its 100 kOhm pull-down
pickup    the pickup disc's envelope detector (tuning only)
headers   the microcontroller headers: a Pico by physical pin, the pyboard by pin name
boards    one circuit per board file, and the check that the two agree on every pin
erc       the electrical rules check, strict: any warning fails
export    the KiCad netlist, the BOM CSV and the netlistsvg drawing

hardware/build.py writes them all to hardware/design/.
"""
