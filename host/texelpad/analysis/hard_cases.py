"""The hard-case suite: parameter sets where generators break. Shared by the
tests (tests/gen/test_precision.py) and the benchmark (texelpad bench)."""
from __future__ import annotations

FULL = 19200  # samples on the whole TPaD screen (101.76 mm)

# name -> (parameter set, why it is hard). Every set says "v": 1: the suite
# measures format 1's float engines against the float64 reference (format 2,
# the integer plan, is bit-identical everywhere: tests/gen/test_plan_int.py
# reads the same sets with v=2).
HARD_CASES: dict[str, tuple[dict, str]] = {
    "study": ({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "length_samples": FULL, "v": 1},
              "the study's split-screen texel rendering, full screen"),
    "pitch-min": ({"pitch_db": -20.0, "irregularity_db": -10.0, "seed": 2, "length_samples": FULL, "v": 1},
                  "0.01 c/mm: less than a cycle per screen"),
    "pitch-nyquist": ({"pitch_db": 19.7, "irregularity_db": -30.0, "seed": 3, "length_samples": FULL, "v": 1},
                      "93.3 c/mm, 2 samples per cycle: fastest phase growth the display shows"),
    "irreg-min": ({"pitch_db": 6.0, "irregularity_db": -30.0, "seed": 4, "length_samples": FULL, "v": 1},
                  "sigma = 0.001 decade: a near-pure tone"),
    "irreg-max": ({"pitch_db": 6.0, "irregularity_db": 5.0, "seed": 5, "length_samples": FULL, "v": 1},
                  "sigma = 3.16 decades: draws up to 10^10 c/mm, far beyond Nyquist"),
    "white-like": ({"pitch_db": 17.0, "irregularity_db": 0.0, "seed": 6, "length_samples": FULL, "v": 1},
                   "P = 50 c/mm, sigma = 1 decade: ~half the texels alias (the lab's white-noise match)"),
    "quant-coarse": ({"pitch_db": 5.0, "irregularity_db": -20.0, "quant_db": 5.0, "seed": 8,
                      "length_samples": FULL, "v": 1},
                     "5 dB grid, far coarser than the 0.01-decade spread: every texel on one grid step"),
    "texel-1": ({"pitch_db": 10.0, "irregularity_db": -5.0, "texel_samples": 1, "seed": 9,
                 "length_samples": FULL, "v": 1},
                "1-sample texels: 19,200 draws, phase carried through every sample"),
    "texel-long": ({"pitch_db": 10.0, "irregularity_db": -10.0, "texel_samples": 30000, "seed": 10,
                    "length_samples": FULL, "v": 1},
                   "one texel longer than the map: 19,200 samples of one phase ramp"),
    "seed-0": ({"pitch_db": 8.0, "irregularity_db": -8.0, "seed": 0, "length_samples": FULL, "v": 1},
               "seed 0"),
    "seed-max": ({"pitch_db": 8.0, "irregularity_db": -8.0, "seed": 4294967295, "length_samples": FULL, "v": 1},
                 "seed 2^32-1 (a heap bigint on MicroPython)"),
    "ragged": ({"pitch_db": 4.0, "irregularity_db": -10.0, "seed": 12, "length_samples": 19199, "v": 1},
               "map length not a multiple of the texel: last texel cut short"),
    "gain-half": ({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 13, "gain": 0.5,
                   "length_samples": FULL, "v": 1}, "gain 0.5"),
    "long-map": ({"pitch_db": 19.0, "irregularity_db": -20.0, "seed": 11, "length_samples": 262144, "v": 1},
                 "13.6 screens at 79 c/mm: 1.1e5 turns of phase, where float32 accumulation drifts"),
}

# Cases where the float64 reference's own sine argument stays small enough
# (the error bound of precision.error_bound is < 1 PWM step): every device
# engine must be within 1 PWM step here. irreg-max draws pitches up to
# ~1e10 c/mm, where the reference's argument has an ulp of ~1e-6 rad and the
# bound grows past a step: there only the bound itself is asserted.
WELL_CONDITIONED = [n for n in HARD_CASES if n != "irreg-max"]
