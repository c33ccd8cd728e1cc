"""The trained rater's matches (seed 000's quantization test), as the lab
published them: study/data/trained_rater.json, made from ../shared/golden/rater
by tools/gen_rater_data.py (a test checks the two agree). For each of the nine
references: the parameters the rater chose and the exact 192 texel pitches
(c/mm, texels of 50 samples, 9,600 samples = half the display) of the rendering
the rater felt.

Seed 000's quantization test plays that very sequence, quantized: the lab's
app (free_exploration_and_quantization_test_app) rebuilds it with buildFine5
from the logged pitches with irregularity 0, so each texel's log10 pitch is
rounded to a multiple of q decades (MATLAB round: halves away from zero) and
nothing else changes; the start phase is buildFine5's rand(), here drawn from
the session's seed, and the phase is continuous across texels.

    rendering(name, quant_db, phase_u) -> the right half as u16 samples

Pure logic: numpy and the package's data file.
"""
from __future__ import annotations

import functools
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from texel.gen.reference import STUDY_NAMES

from ..analysis.calibration import render_pitches

DATA = Path(__file__).with_name("data") / "trained_rater.json"


@functools.lru_cache(maxsize=1)
def data() -> dict[str, Any]:
    return json.loads(DATA.read_text(encoding="utf-8"))


def _name(name: str) -> str:
    if name not in STUDY_NAMES:
        raise ValueError("reference: unknown %r (known: %s)" % (name, ", ".join(STUDY_NAMES)))
    return name


def match(name: str) -> dict[str, float]:
    """{pitch_db, irregularity_db} the rater chose for reference `name`."""
    return dict(data()["matches"][_name(name)])


# The lab's data rows are in its test order (../shared/golden/README.md, "rater/"):
# reference_textures.mat's reference_textures_test_order, 1-based in the family order
# (texel.gen.reference.STUDY_NAMES): data row k holds texture TEST_ORDER[k].
TEST_ORDER = (8, 3, 5, 2, 6, 4, 7, 1, 9)
TEST_ORDER_NAMES = tuple(STUDY_NAMES[i - 1] for i in TEST_ORDER)
# rater_rows: "by_texture" plays each reference beside the rater's rendering OF IT.
# The other two are what session files written before the file was relabelled
# (2026-11-28) played, kept so they replay as they ran (study/legacy.py fills them in):
# "statistics-2026" - rows assigned by their statistics, which cannot tell square's from
# triangle's (identical matches) and swapped those two; "index-2026" - the old mode
# "app": reference k (family order) beside data row k, i.e. texture TEST_ORDER[k].
ROWS = ("by_texture",)
LEGACY_ROWS = ("statistics-2026", "index-2026")


def played(name: str, rows: str) -> str:
    """Whose rendering `rows` plays beside reference `name`."""
    if rows == "by_texture":
        return name
    if rows == "statistics-2026":
        return {"square": "triangle", "triangle": "square"}.get(name, name)
    if rows == "index-2026":
        return TEST_ORDER_NAMES[STUDY_NAMES.index(name)]
    raise ValueError("rater_rows: expected 'by_texture' (each reference beside the rater's "
                     "rendering of it), got %r" % (rows,))


def pitches(name: str, rows: str = "by_texture") -> np.ndarray:
    """The 192 texel pitches (c/mm) of the rater's rendering of `name`
    (rows "by_texture"); a LEGACY_ROWS value gives what a session written
    before the relabelling played beside `name` (above)."""
    return np.array(data()["pitches_cpmm"][played(_name(name), rows)], dtype=np.float64)


def texel_samples() -> int:
    return int(data()["texel_samples"])


def _round_half_away(x: np.ndarray) -> np.ndarray:
    return np.sign(x) * np.floor(np.abs(x) + 0.5)


def quantize(f_cpmm: np.ndarray, quant_db: float) -> np.ndarray:
    """buildFine5.m's quantization: log10 f rounded to a multiple of
    q = quant_db / 10 decades, halves away from zero; 0 = off."""
    if quant_db == 0:
        return np.asarray(f_cpmm, dtype=np.float64)
    q = quant_db / 10.0
    return 10.0 ** (q * _round_half_away(np.log10(f_cpmm) / q))


def rendering(name: str, quant_db: float, phase_u: float,
              rows: str = "by_texture") -> tuple[int, ...]:
    """The rater's rendering of `name`, its pitches quantized at quant_db, as
    display samples (u16, one per 5.3 um position, 9,600 of them): sin of a
    phase that starts at 2 pi phase_u and advances 2 pi f_i DX_MM per sample
    of texel i (continuous across texels), mapped (sin + 1) / 2 to 0..65535
    (round half up)."""
    if not (isinstance(phase_u, float) and 0.0 <= phase_u < 1.0):
        raise ValueError("phase_u: expected a float in [0, 1), got %r" % (phase_u,))
    m = render_pitches(quantize(pitches(name, rows), quant_db), texel_samples(),
                       2.0 * math.pi * phase_u)
    u16 = np.floor(m * 65535.0 + 0.5).astype(np.int64)
    return tuple(int(v) for v in u16)
