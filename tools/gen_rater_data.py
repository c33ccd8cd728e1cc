"""Write host/texelpad/study/data/trained_rater.json from ../shared/golden/rater:
the trained rater's matches and the exact 192 texel pitches of each rendering
the rater felt (seed 000's quantization test plays and quantizes these), so the
lab carries them when it is installed without ../shared beside it.

The pitch rows are read by their labels (texelpad.analysis.calibration.rater_pitches;
../shared/golden/README.md: the file was relabelled on 2026-11-28, and
tests/analysis check the labels against the rows' statistics). tests/study/test_paper_designs.py
checks that the shipped file equals what this script makes from ../shared.

    .venv/bin/python tools/gen_rater_data.py
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "host" / "texelpad" / "study" / "data" / "trained_rater.json"


def build() -> dict:
    sys.path[:0] = [str(ROOT / "host"), str(ROOT / "device")]
    from texelpad.analysis.calibration import (NAMES, RATER_TEXEL_SAMPLES, rater_matches,
                                               rater_pitches)
    matches = rater_matches()
    pitches = rater_pitches()
    return {"source": "../shared/golden/rater (NU-Haptics-Lab/SinglePitchTexel, "
                      "trained_rater_results.mat: seed 000's data link)",
            "texel_samples": RATER_TEXEL_SAMPLES,
            "matches": {n: {"pitch_db": matches[n][0], "irregularity_db": matches[n][1]}
                        for n in NAMES},
            "pitches_cpmm": {n: [float(v) for v in pitches[n]] for n in NAMES}}


def main() -> None:
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(build(), indent=1) + "\n", encoding="utf-8")
    print("wrote", OUT.relative_to(ROOT))


if __name__ == "__main__":
    main()
