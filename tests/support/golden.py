"""Loading ../shared/golden/spt runs as (params, draws, expected)."""
import csv
import math
from pathlib import Path

import numpy as np


def runs(golden_dir: Path):
    spt = golden_dir / "spt"
    out = []
    with open(spt / "runs.csv") as fh:
        for row in csv.DictReader(fh):
            i = int(row["id"])
            # dB from the exact linear columns (golden README: the dB columns
            # are rounded to 10 digits, too coarse for 1e-9 agreement).
            P = float(row["pitch_cpmm"])
            s = float(row["sigma_log10"])
            q = float(row["quant_log10"])
            n, L = int(row["texelnum"]), int(row["texellength"])
            params = {"pitch_db": 10 * math.log10(P), "irregularity_db": 10 * math.log10(s),
                      "quant_db": 10 * q, "texel_samples": L, "length_samples": n * L,
                      "v": 1}     # the lab's float generator (format 1): what replays draws
            u = float((spt / f"run{i:02d}_u.csv").read_text())
            z = np.loadtxt(spt / f"run{i:02d}_z.csv")
            out.append({
                "id": i, "params": params, "draws": (u, list(z)),
                "map": np.loadtxt(spt / f"run{i:02d}_map.csv"),
                "pitch": np.loadtxt(spt / f"run{i:02d}_pitchlog.csv"),
                "phase": np.loadtxt(spt / f"run{i:02d}_phaselog.csv"),
            })
    return out
