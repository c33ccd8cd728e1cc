"""The space-frequency transform of the Tactile Paintbrush (seed 002 §III-A:
"each Fourier analysis is conducted within a window of 1mm, and the texture
is sampled in space with a resolution of 0.25mm"), on the display's 5.3 um
sample (texel.gen.params.DX_MM).

Geometry, fixed in device/texel/gen/brush.py and imported from there (the
painting on host and board uses the same constants):

    WINDOW = 192 samples = 1.0176 mm   (the paper's 1 mm)
    HOP    =  48 samples = 0.2544 mm   (the paper's 0.25 mm; 4 windows overlap)
    K      =  97 wavenumbers 0 .. 96   (k cycles per window: wavelength
                                        1.0176 mm / k; 96 = NYQ = 10.6 um,
                                        the display's Nyquist; the paper's
                                        101 on 5 um went to 10 um)

Window: the periodic Hann w[n] = 0.5 - 0.5 cos(2 pi n / WINDOW), n = 0 ..
WINDOW-1 (periodic, not symmetric, so that the four windows overlapping at a
sample add to exactly 2: the synthesis' overlap-add has no ripple);
W = sum w = WINDOW / 2 = 96.

Magnitudes (brush.py): X_k = sum_n x[n] w[n] e^(-2 pi i k n / WINDOW) (numpy's
rfft of the windowed samples: exactly K = WINDOW/2 + 1 = 97 bins), and

    m_0 = |X_0| / W          the window's (Hann-weighted) mean friction
    m_k = 2 |X_k| / W        k = 1 .. 96

so a constant c gives m_0 = |c| and a sinusoid A sin(2 pi k n / WINDOW + phi)
at a whole wavenumber 1 <= k <= 95 gives m_k = A. The exception is k = 96,
the Nyquist bin: there the sampled sinusoid is A cos(phi) (-1)^n, the bin is
real and has no negative-frequency twin, so m_96 = 2 A |cos phi| (anything
from 0 to 2A); a painter that draws m_96 and a random phase must halve it
(or draw the sign only) to get amplitude m_96 / 2 back. A wavenumber between
bins leaks into its neighbours by the Hann main lobe (4 bins wide).

Windows start at samples 0, HOP, 2 HOP, ... while a whole window fits: a map
of N >= WINDOW samples gives 1 + (N - WINDOW) // HOP windows, and its last
(N - WINDOW) % HOP samples (fewer than HOP = 0.2544 mm) are not analysed -
never padded, since zero padding would put a false step into the last window.

Recordings (a tribometer's CSV, position in mm and friction, any step, as
the paper recorded at 3.86 um and resampled to 5 um): `read_recording` reads
one, its columns found by header name (`recording_columns`), `resample` puts
it on the display's 5.3 um grid.

Pure logic: numpy and texel only (docs/architecture.md).
"""
from __future__ import annotations

import csv
import math
import os
from typing import Sequence

import numpy as np

from texel.gen.brush import HOP, K, WINDOW
from texel.gen.params import DX_MM, LENGTH_MAX

DX_UM = round(DX_MM * 1000.0, 9)        # 5.3 um: the display's map sample
WINDOW_MM = WINDOW * DX_MM              # 1.0176 mm
HOP_MM = HOP * DX_MM                    # 0.2544 mm
# Sanity of the imported geometry: rfft of WINDOW samples has WINDOW/2 + 1 bins,
# and that is the brush's K (brush.py: 0 = mean .. 96 = NYQ, the Nyquist).
assert K == WINDOW // 2 + 1 and WINDOW % 4 == 0 and HOP * 4 == WINDOW, (WINDOW, HOP, K)


def window() -> np.ndarray:
    """The periodic Hann window, WINDOW samples: 0.5 - 0.5 cos(2 pi n / WINDOW)."""
    n = np.arange(WINDOW)
    return 0.5 - 0.5 * np.cos(2.0 * math.pi * n / WINDOW)


_W = window()
_WSUM = float(_W.sum())                 # = WINDOW / 2 = 96 (to rounding)
# m_0 = |X_0| / W, m_k = 2 |X_k| / W: one scale per bin
_SCALE = np.full(K, 2.0 / _WSUM)
_SCALE[0] = 1.0 / _WSUM


def wavelengths_mm() -> np.ndarray:
    """Wavelength of each wavenumber in mm (inf for k = 0): WINDOW_MM / k."""
    k = np.arange(K, dtype=float)
    with np.errstate(divide="ignore"):
        return np.where(k > 0, WINDOW_MM / np.maximum(k, 1.0), np.inf)


def n_windows(n_samples: int) -> int:
    """Windows a map of n_samples gives (0 when shorter than one window)."""
    return 0 if n_samples < WINDOW else 1 + (n_samples - WINDOW) // HOP


def stft_magnitudes(x, demean: bool = False) -> np.ndarray:
    """The magnitudes m[window, k] of a friction map sampled every 5.3 um:
    shape (n_windows, K), windows at samples 0, HOP, 2 HOP ... (module
    docstring: the tail of fewer than HOP samples after the last whole window
    is not analysed). Raises ValueError for anything but a 1-D array of
    finite numbers at least WINDOW (192 samples = 1.0176 mm) long.

    demean: the k >= 1 magnitudes of each window minus its own m_0 (the
    Hann-weighted mean), so the mean does not leak into k = 1. The paper's
    comparison (compare.py) uses the plain transform, where k = 1 carries the
    mean as in seed 002; a brush is fitted on the de-meaned one
    (host/texelpad/brush/document.py), because the painter draws the mean and
    the k = 1 wave apart (device/texel/gen/brush.py)."""
    a = np.asarray(x, dtype=float)
    if a.ndim != 1:
        raise ValueError("map: expected a 1-D array of friction samples, got shape %r"
                         % (a.shape,))
    if a.size < WINDOW:
        raise ValueError("map: %d samples is less than one window (%d samples = %.4f mm at "
                         "%.1f um)" % (a.size, WINDOW, WINDOW_MM, DX_UM))
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise ValueError("map: sample %d is %r (%d non-finite samples); the transform needs "
                         "finite friction values" % (bad[0], float(a[bad[0]]), bad.size))
    frames = np.lib.stride_tricks.sliding_window_view(a, WINDOW)[::HOP]
    if demean:
        m0 = (frames * _W).sum(axis=1, keepdims=True) / _WSUM
        out = np.abs(np.fft.rfft((frames - m0) * _W, axis=1)) * _SCALE
        out[:, 0] = np.abs(m0[:, 0])
        return out
    return np.abs(np.fft.rfft(frames * _W, axis=1)) * _SCALE


def resample(positions_mm: Sequence[float] | np.ndarray, friction: Sequence[float] | np.ndarray,
             dx_um: float = DX_UM) -> np.ndarray:
    """A recording (friction at positions in mm, any step, in any order,
    repeats allowed) on a regular grid of dx_um: sorted by position (stable),
    the friction of repeated positions averaged, then linearly interpolated
    at p0 + i * dx for i = 0, 1, ... while <= the last position (p0 = the
    smallest position; a gap is bridged by the straight line across it).
    Returns the friction samples; sample i sits at p0 + i * dx_um / 1000 mm.

    The transform's geometry assumes the display's 5.3 um (the default):
    another dx_um is for other uses. Raises ValueError when the inputs are
    not two 1-D sequences of the same length, hold a NaN or an infinity, or
    span less than one window (192 samples of dx) or more than LENGTH_MAX
    (texel.gen.params) samples."""
    p = np.asarray(positions_mm, dtype=float)
    f = np.asarray(friction, dtype=float)
    if p.ndim != 1 or f.ndim != 1 or p.size != f.size:
        raise ValueError("recording: positions and friction must be 1-D and of one length, "
                         "got shapes %r and %r" % (p.shape, f.shape))
    if not (isinstance(dx_um, (int, float)) and math.isfinite(dx_um) and dx_um > 0):
        raise ValueError("dx_um: expected a positive finite step in um, got %r" % (dx_um,))
    for name, v in (("position", p), ("friction", f)):
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            raise ValueError("recording: %s of row %d is %r; every position and friction must "
                             "be a finite number" % (name, bad[0], float(v[bad[0]])))
    dx_mm = dx_um / 1000.0
    need_mm = (WINDOW - 1) * dx_mm
    if p.size == 0:
        raise ValueError("recording: no rows")
    order = np.argsort(p, kind="stable")
    p, f = p[order], f[order]
    # repeated positions (an encoder standing still while the force is sampled): one
    # point, their mean friction
    uniq, start = np.unique(p, return_index=True)
    counts = np.diff(np.append(start, p.size))
    fm = np.add.reduceat(f, start) / counts
    span = float(uniq[-1] - uniq[0])
    if not span >= need_mm:
        raise ValueError("recording: spans %.6g mm (%d distinct positions); one window needs "
                         "%.4f mm (%d samples of %.4g um)"
                         % (span, uniq.size, need_mm, WINDOW, dx_um))
    n = int(math.floor(span / dx_mm * (1.0 + 1e-12))) + 1
    if n > LENGTH_MAX:
        raise ValueError("recording: spans %.6g mm = %s samples of %.4g um, more than the "
                         "longest map (%d samples)"
                         % (span, "%d" % n if n < 10 ** 12 else "%.3g" % n, dx_um, LENGTH_MAX))
    # positions so large that float64 cannot place a grid point to 1/1000 of a step
    # (beyond ~2e10 mm for 5.3 um): the grid would be uneven or stand still
    if float(np.spacing(max(abs(uniq[0]), abs(uniq[-1])))) > dx_mm * 1e-3:
        raise ValueError("recording: positions near %.6g mm are too large for a %.4g um grid "
                         "in floating point" % (uniq[0], dx_um))
    grid = uniq[0] + np.arange(n) * dx_mm
    grid[-1] = min(grid[-1], uniq[-1])      # rounding must not step past the last point
    return np.interp(grid, uniq, fm)


def _cell(text: str) -> float:
    v = float(text)                         # ValueError for words; "nan", "inf" parse
    if not math.isfinite(v):
        raise ValueError("not finite")
    return v


# Columns are found by their header names (case and spaces ignored), as
# `texelpad encode` finds its friction column: `texelpad render --out m.csv`
# writes "sample,x_mm,friction", `texelpad brush paint --out` writes
# "position_mm,friction", a tribometer export "position_mm,friction,normal_N".
# The position must be in millimetres: a column named in mm, or "position" /
# "x" (taken as mm). A sample number is never a position.
POSITION_NAMES = ("position_mm", "x_mm", "pos_mm", "distance_mm", "displacement_mm", "mm",
                  "position", "x", "pos", "distance", "displacement")
# friction by name (the names texelpad encode takes, and a tribometer's mu or
# cof); without one, the column right after the position (the old
# "position, then friction" order)
FRICTION_NAMES = ("friction", "mu", "cof", "coefficient_of_friction", "friction_coefficient",
                  "map", "value", "amplitude")
_DELIMITERS = (",", ";", "\t")


def _name(cell: str) -> str:
    return cell.strip().strip('"').strip().lower().replace(" ", "_")


def read_csv_table(path: str | os.PathLike, min_columns: int = 1,
                   columns: str = "") -> tuple[list[str], list[tuple[int, list[str]]]]:
    """A CSV file with a header row: (the header's cells, [(line number,
    cells)] of the data rows). The delimiter is the header's (a comma, else
    a semicolon or a tab); blank lines and lines starting with '#' are
    skipped; the header has at least min_columns cells (`columns` says
    which) and every row as many fields as the header. Errors
    (ValueError) name the file and line: no header (the first row is numbers),
    a short row, an empty file, no data rows. OSError when it cannot be read;
    a file that is not UTF-8 text is a ValueError."""
    name = os.fspath(path)
    header: list[str] | None = None
    rows: list[tuple[int, list[str]]] = []
    try:
        with open(name, newline="", encoding="utf-8-sig") as fh:
            lines = fh.read().splitlines()
    except UnicodeDecodeError:
        raise ValueError("%s is not UTF-8 text (expected a CSV file with a header)"
                         % name) from None
    delimiter = ","
    for line_no, line in enumerate(lines, start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if header is None:
            delimiter = next((d for d in _DELIMITERS if d in line), ",")
        row = next(csv.reader([line], delimiter=delimiter))
        if header is None:
            try:
                [float(c) for c in row[:2]]
                numeric = True
            except ValueError:
                numeric = False
            if numeric:
                raise ValueError("%s line %d: expected a header (the column names, e.g. "
                                 "position_mm,friction), got a row of numbers %r"
                                 % (name, line_no, row[:4]))
            if len(row) < min_columns:
                raise ValueError("%s line %d: the header has %d column(s); expected %s"
                                 % (name, line_no, len(row), columns or "%d" % min_columns))
            header = row
            continue
        if len(row) != len(header):
            raise ValueError("%s line %d: %d field(s), the header has %d (%s)"
                             % (name, line_no, len(row), len(header), ",".join(header)))
        rows.append((line_no, row))
    if header is None:
        raise ValueError("%s: empty (expected a header, then rows of position in mm, "
                         "friction)" % name)
    if not rows:
        raise ValueError("%s: a header and no data rows" % name)
    return header, rows


def recording_columns(header: Sequence[str], where: str = "recording") -> tuple[int, int]:
    """(position column, friction column) of a recording's header, by name
    (POSITION_NAMES, FRICTION_NAMES); ValueError when there is no position
    column in mm, or no friction column."""
    names = [_name(c) for c in header]
    shown = ", ".join(repr(c.strip()[:40]) for c in header[:8]) + (", ..." if len(header) > 8
                                                                   else "")
    pos = next((names.index(n) for n in POSITION_NAMES if n in names), None)
    if pos is None:
        raise ValueError("%s: no position column in its header (%s); name the position in mm "
                         "position_mm or x_mm (a sample number is not a position)"
                         % (where, shown))
    fri = next((names.index(n) for n in FRICTION_NAMES if n in names), None)
    if fri is None:
        if pos + 1 >= len(names):
            raise ValueError("%s: no friction column in its header (%s); name it friction"
                             % (where, shown))
        fri = pos + 1
    return pos, fri


def read_recording(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """(positions_mm, friction) of a CSV recording (read_csv_table): a
    header row first naming the columns, then one row per sample. The
    position and friction columns are found by name (recording_columns:
    "x_mm" of `texelpad render --out m.csv`, "position_mm", ...; never by
    place, so "sample,x_mm,friction" reads x_mm as the position); other
    columns are ignored. Errors name the file (and line): a missing header or
    position column, a short row, a cell that is not a finite number, no data
    rows."""
    name = os.fspath(path)
    header, rows = read_csv_table(name, 2, "position in mm, then friction")
    pcol, fcol = recording_columns(header, name)
    pos: list[float] = []
    fri: list[float] = []
    for line_no, row in rows:
        for col, what, out in ((pcol, "position", pos), (fcol, "friction", fri)):
            try:
                out.append(_cell(row[col]))
            except ValueError:
                raise ValueError("%s line %d: %s %r is not a finite number"
                                 % (name, line_no, what, row[col].strip()[:40])) from None
    return np.asarray(pos), np.asarray(fri)
