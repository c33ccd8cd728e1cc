"""Figures for the command line (matplotlib, drawn off-screen with the Agg
canvas; pyplot and its global backend state are never touched)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import texel
from texel.runtime import kinds

from .spectrum import pitch_normal_pdf, spectrum


def render_figure(fmap: np.ndarray, plan: Any, path: str | Path, engine: str = "") -> None:
    """Map, spectrum and texel pitch histogram of one rendering, as a PNG."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    p = plan.params
    fig = Figure(figsize=(10, 11.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax_map, ax_zoom, ax_spec, ax_hist = fig.subplots(4, 1)
    sigma = 10.0 ** (p["irregularity_db"] / 10.0)
    fig.suptitle("pitch %.2f dB (%.3g c/mm), irregularity %.2f dB (%.3g decade), seed %d, "
                 "%d texel%s of %d samples%s" % (
                     p["pitch_db"], 10 ** (p["pitch_db"] / 10), p["irregularity_db"], sigma,
                     p["seed"], plan.count, "" if plan.count == 1 else "s", plan.L,
                     (", " + engine) if engine else ""))

    x = np.arange(fmap.size) * texel.DX_MM
    ax_map.plot(x, fmap, lw=0.4, color="C0")
    ax_map.set_xlim(0, max(x[-1], texel.DX_MM))
    ax_map.set_ylim(-0.02, 1.02)
    ax_map.set_xlabel("position (mm)")
    ax_map.set_ylabel("friction reduction")
    ax_map.set_title("friction map (%d samples, %.2f mm)" % (fmap.size, fmap.size * texel.DX_MM))

    # zoom: the first 8 texels (at least 100 samples), texel borders marked
    nz = int(min(fmap.size, max(100, 8 * plan.L)))
    ax_zoom.plot(x[:nz], fmap[:nz], lw=0.8, color="C0", marker="." if nz <= 400 else None,
                 ms=2)
    for k in range(plan.L, nz, plan.L):
        if nz // plan.L <= 40:
            ax_zoom.axvline(k * texel.DX_MM, color="0.8", lw=0.6, zorder=0)
    ax_zoom.set_xlim(0, max(x[nz - 1], texel.DX_MM))
    ax_zoom.set_ylim(-0.02, 1.02)
    ax_zoom.set_xlabel("position (mm)")
    ax_zoom.set_ylabel("friction reduction")
    ax_zoom.set_title("first %d samples (%.3g mm)%s" % (
        nz, nz * texel.DX_MM, ", texel borders in grey" if plan.L < nz else ""))

    f, a = spectrum(fmap)
    keep = f > 0
    if keep.any():
        ax_spec.loglog(f[keep], np.maximum(a[keep], 1e-12), lw=0.5, color="C0")
    ax_spec.axvline(texel.NYQUIST_CPMM, color="C3", ls="--", lw=1,
                    label="Nyquist %.1f c/mm" % texel.NYQUIST_CPMM)
    ax_spec.axvline(10 ** (p["pitch_db"] / 10), color="C2", ls=":", lw=1.2,
                    label="central pitch %.3g c/mm" % 10 ** (p["pitch_db"] / 10))
    ax_spec.set_xlabel("spatial frequency (cycles/mm)")
    ax_spec.set_ylabel("amplitude")
    ax_spec.set_title("spectrum (Hann window, mean removed)")
    ax_spec.legend(loc="lower left", fontsize="small")

    db = 10.0 * np.log10(np.asarray(plan.f, dtype=np.float64))
    sd = 10.0 * sigma
    lo = min(db.min(), p["pitch_db"] - 4 * sd)
    hi = max(db.max(), p["pitch_db"] + 4 * sd)
    if hi - lo < 1e-6:
        lo, hi = lo - 0.5, hi + 0.5
    bins = int(min(80, max(10, math.sqrt(db.size) * 2)))
    ax_hist.hist(db, bins=np.linspace(lo, hi, bins + 1), density=True, color="C0", alpha=0.6,
                 label="texel pitches (%d)" % db.size)
    grid = np.linspace(lo, hi, 400)
    ax_hist.plot(grid, pitch_normal_pdf(grid, p["pitch_db"], p["irregularity_db"]), color="C1",
                 lw=1.5, label="Normal(%.2f dB, %.3g dB)" % (p["pitch_db"], sd))
    nyq_db = 10 * math.log10(texel.NYQUIST_CPMM)
    if lo <= nyq_db <= hi:
        ax_hist.axvline(nyq_db, color="C3", ls="--", lw=1, label="Nyquist (%.0f%% of texels above)"
                        % (100 * plan.fraction_above_nyquist()))
    ax_hist.set_xlim(lo, hi)
    ax_hist.set_xlabel("texel pitch (dB re 1 cycle/mm)")
    ax_hist.set_ylabel("density (1/dB)")
    ax_hist.set_title("texel pitch histogram against the drawing distribution"
                      + (" (quantized %g dB)" % p["quant_db"] if p["quant_db"] > 0 else ""))
    ax_hist.legend(loc="upper right", fontsize="small")
    fig.savefig(str(path), dpi=110)


# --- the `texelpad demo` figure ---------------------------------------------------

DEFAULT_DISPLAY = {"positions": 19200, "dx_um": 5.3}   # the TPaD screen: 19,200 x 5.3 um = 101.76 mm
_T_WRAP = 1 << 30           # board clocks in telemetry (t_us) wrap here (refresh._WRAP + 1)
_U16 = 65535.0              # uint16 amplitude of friction reduction 1.0


def _built(scene: Any, display: dict | None) -> tuple[dict, Any]:
    """(canonical scene, texel.runtime.scene.Scene) exactly as a board builds it (idle
    default 0, every board's carrier.idle_amplitude). ValueError from validate."""
    from texel.runtime import scene as tscene
    disp = dict(DEFAULT_DISPLAY if display is None else display)
    canonical = tscene.validate(scene, disp)
    return canonical, tscene.build(canonical, disp)


def _u16_map(sc: Any) -> np.ndarray:
    """uint16 amplitude at every display position: Scene.amp itself, so
    plan-backed texel regions, gaps and the idle level are what a board plays."""
    amp = sc.amp
    return np.fromiter((amp(i) for i in range(sc.positions)), dtype=np.uint16,
                       count=sc.positions)


def scene_map(scene: Any, display: dict | None = None) -> np.ndarray:
    """The friction map a board plays for `scene`: float64 in [0, 1] (uint16 / 65535),
    one value per display position (display default 19,200 x 5.3 um)."""
    return _u16_map(_built(scene, display)[1]) / _U16


def _rows(name: str, data: Any, cols: int, what: str) -> np.ndarray:
    """data as an int64 (n, cols) array of finite integers, or ValueError."""
    try:
        a = np.asarray(data, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError("%s: expected a sequence of %s rows of %d numbers each, got %s"
                         % (name, what, cols, type(data).__name__)) from None
    if a.size == 0 and a.shape in ((0,), (0, cols)):
        return np.zeros((0, cols), dtype=np.int64)
    if a.ndim != 2 or a.shape[1] != cols:
        raise ValueError("%s: expected shape (n, %d) of %s rows, got shape %s"
                         % (name, cols, what, a.shape))
    bad = ~np.isfinite(a) | (a != np.round(a))
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise ValueError("%s[%d][%d]: %r is not a finite integer" % (name, r, c, float(a[r, c])))
    return a.astype(np.int64)


def _unwrap_us(t: np.ndarray) -> np.ndarray:
    """Board microsecond stamps (wrapping at 2^30) -> monotonic us from t[0]."""
    if t.size == 0:
        return t.astype(np.float64)
    return t[0] + np.concatenate(([0], np.cumsum(np.diff(t) % _T_WRAP))).astype(np.float64)


def _label(k: int, tex: dict, short: bool) -> str:
    """'R2 texel pitch 6.3 dB, irregularity -12.9 dB, seed 7, format 2' (short:
    'R2 texel 6.3/-12.9 dB, seed 7'): the kind's own words (texel/runtime/kinds/)."""
    d = dict(kinds.get(tex["kind"]).describe(tex), kind=tex["kind"])
    s = kinds.label(d) if short else kinds.words(d)
    return ("R%d " % (k + 1) + s).replace("-", "\u2212")


def _note(ax: Any, text: str) -> None:
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center",
            fontsize="large", color="0.35",
            bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.9))


def _n(k: int, word: str) -> str:
    """"1 sample", "1,800 samples"."""
    return "%s %s%s" % (format(k, ","), word, "" if k == 1 else "s")


def played_words(amp_err_max: int | None, mismatches: int, down: int) -> str | None:
    """What the board played against the map at the sensed finger, in words a
    teacher reads (the demo figure's title, `texelpad demo`'s summary): "the
    board played exactly the map (0 of 1,800 samples differ)", or "the
    board's played friction differed from the map by at most 7 steps of
    65,535 at 1 of 1,800 samples" - friction is played in 65,535 steps from
    none to full, and the samples are those taken with the finger down.
    None when the finger was never down (nothing to compare)."""
    if amp_err_max is None:
        return None
    if amp_err_max == 0:
        return "the board played exactly the map (0 of %s differ)" % _n(down, "sample")
    return ("the board's played friction differed from the map by at most %s of 65,535 at "
            "%s of %s" % (_n(amp_err_max, "step"), format(mismatches, ","), _n(down, "sample")))


def finger_words(pos_err_max: int | None, dx_um: float) -> str | None:
    """Where the board sensed the finger against where it truly was (the
    virtual board's scripted finger), in words: "the board sensed the finger
    at most 4 positions (21.2 \u00b5m) from where it truly was"; None without
    the truth or any sample with the finger down in both."""
    if pos_err_max is None:
        return None
    if pos_err_max == 0:
        return "the board sensed the finger exactly where it truly was"
    return ("the board sensed the finger at most %s (%.4g \u00b5m) from where it truly was"
            % (_n(pos_err_max, "position"), pos_err_max * dx_um))


def demo_figure(path: str | Path, scene: Any, telemetry: Any, *, display: dict | None = None,
                title: str = "", truth: Any = None, plate: dict | None = None) -> dict:
    """One PNG for `texelpad demo`: what the scene should play against what the
    board's refresh played (telemetry rows (t_us, position, amplitude u16);
    position -1 = lifted), spectra, texel pitch histograms, and amplitude and
    finger over time. truth: optional rows (t_us, true position or negative =
    lifted) of the simulated finger, in time order, in the same clock as t_us.

    Returns {"path", "samples", "down" (finger-down samples), "amp_err_max"
    (max |played - map[position]| over finger-down samples, uint16 counts; None
    without any), "amp_mismatches" (samples with a nonzero error)} and with
    truth also "pos_err_max" (max |sensed - true| in positions, nearest t_us,
    both down; None without any pair) and "lift_mismatches" (sensed and true
    finger disagree on lifted). plate: {"f0_hz", "q", "speed_mm_s"}: the zoom
    also draws what the plate plays, the map through the tank's envelope at
    that swipe speed (texelpad.plate.tank.plate_plays; hardware/README.md,
    "The envelope"). Raises ValueError on malformed inputs."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    d = _demo_data(scene, display, telemetry)
    out: dict = {"path": str(path), "samples": int(len(d.tel)), "down": int(d.down.sum()),
                 "amp_err_max": int(d.err[d.down].max()) if d.down.any() else None,
                 "amp_mismatches": int((d.err != 0).sum())}
    if truth is not None:
        out.update(_demo_truth(d, truth))

    fig = Figure(figsize=(12, 14.5), layout="constrained")
    FigureCanvasAgg(fig)
    gs = fig.add_gridspec(4, 2, height_ratios=[1.15, 1, 1, 1])
    ax_map = fig.add_subplot(gs[0, :])
    ax_zoom = fig.add_subplot(gs[1, :])
    ax_spec = fig.add_subplot(gs[2, 0])
    ax_hist = fig.add_subplot(gs[2, 1])
    ax_time = fig.add_subplot(gs[3, :])
    _demo_title(fig, title, out, d.sc.dx_um)
    _demo_map(ax_map, d)
    _demo_zoom(ax_zoom, d, plate)
    _demo_spectra(ax_spec, d)
    _demo_histograms(ax_hist, d)
    _demo_time(ax_time, d)
    fig.savefig(str(path), dpi=100)
    return out


@dataclass
class _Demo:
    """What the demo figure's panels share: the scene as built (sc), its map
    (u16 and 0..1), positions in mm, regions, and the telemetry (and truth)."""
    sc: Any
    u16: np.ndarray
    fmap: np.ndarray
    dx: float                                   # mm per position
    x: np.ndarray                               # mm
    spans: list
    texs: list
    edges: list
    textured: list
    colors: list
    short: bool
    tel: np.ndarray
    pos: np.ndarray
    amp: np.ndarray
    down: np.ndarray
    err: np.ndarray                             # |played - map[position]|, uint16 counts
    t0: float | None
    ts: np.ndarray                              # s from the first telemetry sample
    tr: np.ndarray | None = None
    tr_s: np.ndarray | None = None

    @property
    def npos(self) -> int:
        return self.sc.positions


_PLAYED_KW = dict(s=14, color="C3", zorder=3, edgecolors="none")


def _demo_data(scene: Any, display: dict | None, telemetry: Any) -> _Demo:
    """The scene built and the telemetry checked (ValueError naming the bad row)."""
    canonical, sc = _built(scene, display)
    u16 = _u16_map(sc)
    fmap = u16 / _U16                             # friction reduction 0..1 per position
    npos = sc.positions
    dx = sc.dx_um / 1000.0                        # mm per position
    regions = canonical["regions"]
    spans = [(s, e) for (s, e, _, _) in sc.spans()]
    tel = _rows("telemetry", telemetry, 3, "(t_us, position, amplitude)")
    t_us, pos, amp = tel[:, 0], tel[:, 1], tel[:, 2]
    if ((pos < -1) | (pos >= npos)).any():
        i = int(np.argmax((pos < -1) | (pos >= npos)))
        raise ValueError("telemetry[%d]: position %d outside -1 (lifted) .. %d"
                         % (i, pos[i], npos - 1))
    if ((amp < 0) | (amp > 65535)).any():
        i = int(np.argmax((amp < 0) | (amp > 65535)))
        raise ValueError("telemetry[%d]: amplitude %d outside 0 .. 65535" % (i, amp[i]))
    down = pos >= 0
    err = np.zeros(len(tel), dtype=np.int64)
    err[down] = np.abs(amp[down] - u16[pos[down]].astype(np.int64))
    t0 = float(t_us[0]) if len(tel) else None
    # one colour per region: tab10, then the light tab20 shades (16 regions at most)
    from matplotlib import colormaps
    t20 = colormaps["tab20"].colors            # type: ignore[attr-defined]  # a ListedColormap
    return _Demo(sc=sc, u16=u16, fmap=fmap, dx=dx, x=np.arange(npos) * dx, spans=spans,
                 texs=[r["texture"] for r in regions],
                 edges=sorted({s for s, _ in spans} | {e for _, e in spans}),
                 textured=[bool(np.ptp(fmap[s:e]) > 0) for s, e in spans],
                 colors=[t20[2 * k] if k < 10 else t20[2 * (k - 10) + 1]
                         for k in range(len(regions))],
                 short=len(regions) > 3, tel=tel, pos=pos, amp=amp, down=down, err=err, t0=t0,
                 ts=(_unwrap_us(t_us) - (t0 or 0.0)) / 1e6)


def _demo_truth(d: _Demo, truth: Any) -> dict:
    """The simulated finger against the sensed one: pos_err_max, lift_mismatches
    (and d.tr, d.tr_s for panel 5)."""
    tr = _rows("truth", truth, 2, "(t_us, true position)")
    tr_t = _unwrap_us(tr[:, 0])                   # rows in time order, stamps may wrap like t_us
    t0 = d.t0
    if t0 is None and len(tr):
        t0 = float(tr[0, 0])
    d.tr, d.tr_s = tr, (tr_t - (t0 or 0.0)) / 1e6     # s, same origin as ts
    out: dict = {"pos_err_max": None, "lift_mismatches": 0}
    if len(d.tel) and len(tr):
        # the truth row nearest in time to each telemetry sample
        ts, tr_s = d.ts, d.tr_s
        near = np.zeros(len(ts), dtype=np.int64)
        if len(tr) > 1:
            j = np.clip(np.searchsorted(tr_s, ts), 1, len(tr) - 1)
            near = np.where(ts - tr_s[j - 1] <= tr_s[j] - ts, j - 1, j)
        tpos = tr[near, 1]
        both = d.down & (tpos >= 0)
        if both.any():
            out["pos_err_max"] = int(np.abs(d.pos[both] - tpos[both]).max())
        out["lift_mismatches"] = int((d.down != (tpos >= 0)).sum())
    return out


def _demo_title(fig: Any, title: str, out: dict, dx_um: float) -> None:
    summary = ["%d telemetry samples, %d with the finger down" % (out["samples"], out["down"])]
    played = played_words(out["amp_err_max"], out["amp_mismatches"], out["down"])
    if played is not None:
        summary.append(played)
    finger = finger_words(out.get("pos_err_max"), dx_um)
    if finger is not None:
        summary.append(finger)
    import textwrap
    # every line wrapped to the figure's width (a long played-words line was cut at both edges)
    fig.suptitle("\n".join(textwrap.fill(line, 130) for line in
                           [title or "texelpad demo", "; ".join(summary[:2])] + summary[2:3]))


def _demo_map(ax_map: Any, d: _Demo) -> None:
    """1. the whole display: the map, regions, played samples at their positions."""
    dx, npos, spans, pos, amp, down = d.dx, d.npos, d.spans, d.pos, d.amp, d.down
    ax_map.plot(d.x, d.fmap, lw=0.4, color="C0", label="map (what should play)")
    for b in d.edges:
        ax_map.axvline(b * dx, color="0.5", lw=0.8, ls="--", zorder=1)
    gaps = [(0, spans[0][0])] + [(spans[k][1], spans[k + 1][0]) for k in range(len(spans) - 1)] \
        + [(spans[-1][1], npos)]
    for a, b in gaps:
        if b > a:
            ax_map.axvspan(a * dx, b * dx, color="0.85", zorder=0)
    if down.any():
        ax_map.scatter(pos[down] * dx, amp[down] / _U16, label="played (telemetry, finger down)",
                       **_PLAYED_KW)
        bad = down & (d.err != 0)
        if bad.any():
            ax_map.scatter(pos[bad] * dx, amp[bad] / _U16, marker="x", s=40, color="k", zorder=4,
                           label="played \u2260 map (%d)" % bad.sum())
    else:
        ax_map.text(0.99, 0.97, "no telemetry" if not len(d.tel) else "finger never down",
                    transform=ax_map.transAxes, ha="right", va="top", color="C3")
    ax_map.set_xlim(0, npos * dx)
    ax_map.set_ylim(-0.03, 1.3)
    ax_map.set_yticks([0, 0.25, 0.5, 0.75, 1])
    ax_map.set_xlabel("position (mm)")
    ax_map.set_ylabel("friction reduction")
    ax_map.set_title("friction map over the display (%d positions \u00d7 %.3g \u00b5m = %.2f mm)%s"
                     % (npos, d.sc.dx_um, npos * dx,
                        ", grey = no region (idle)" if any(b > a for a, b in gaps) else ""),
                     fontsize="medium")
    ax_map.legend(loc="upper left", ncol=3, fontsize="small", framealpha=0.9)
    top = ax_map.secondary_xaxis("top")
    top.set_xticks([(s + e) / 2 * dx for s, e in spans],
                   labels=[_label(k, t, d.short) for k, t in enumerate(d.texs)])
    top.tick_params(axis="x", length=0, labelsize="small" if not d.short else 7,
                    rotation=0 if not d.short else 90)


def _demo_zoom(ax_zoom: Any, d: _Demo, plate: dict | None = None) -> None:
    """2. zoom: a few mm around the first border touching a textured region;
    with plate, what the plate plays there (_plate_line)."""
    dx, npos, spans, textured, x = d.dx, d.npos, d.spans, d.textured, d.x
    half = int(round(1.5 / dx))                   # positions in 1.5 mm
    centre, what = None, ""
    for k in range(len(spans) - 1):
        if textured[k] or textured[k + 1]:
            centre = (spans[k][1] + spans[k + 1][0]) // 2
            what = "around the border of R%d and R%d" % (k + 1, k + 2)
            break
    if centre is None:
        k = textured.index(True) if any(textured) else 0
        centre = spans[k][0] + half
        what = "start of R%d" % (k + 1)
    a = max(0, min(centre - half, npos - 2 * half))
    b = min(npos, a + 2 * half)
    ax_zoom.plot(x[a:b], d.fmap[a:b], lw=0.9, color="C0", label="map")
    if plate is not None:
        _plate_line(ax_zoom, d, a, b, plate)
    for e in d.edges:
        if a <= e <= b:
            ax_zoom.axvline(e * dx, color="0.5", lw=0.8, ls="--")
    inz = d.down & (d.pos >= a) & (d.pos < b)
    if inz.any():
        ax_zoom.scatter(d.pos[inz] * dx, d.amp[inz] / _U16, label="played", **_PLAYED_KW)
    ax_zoom.set_xlim(x[a], x[b - 1] if b - a > 1 else x[a] + dx)
    ax_zoom.set_ylim(-0.03, 1.03)
    ax_zoom.set_xlabel("position (mm)")
    ax_zoom.set_ylabel("friction reduction")
    ax_zoom.set_title("zoom %.2f \u2013 %.2f mm, %s (%d played samples here)"
                      % (x[a], x[b - 1], what, inz.sum()), fontsize="medium")
    ax_zoom.legend(loc="upper right", fontsize="small", framealpha=0.9)


def _plate_line(ax: Any, d: _Demo, a: int, b: int, plate: dict) -> None:
    """The map from a to b as the plate plays it at a swipe speed: the tank's
    envelope, a first-order low-pass of tau = Q/(pi f0), run from 200
    positions before a (its transient settles in ~tau*speed, 4 positions at
    100 mm/s and Q 20)."""
    from ..plate.tank import envelope_time_constant, plate_plays
    a0 = max(0, a - 200)
    y = plate_plays(d.fmap[a0:b].tolist(), d.dx / 1000.0, plate["speed_mm_s"] / 1000.0,
                    plate["f0_hz"], plate["q"])
    tau = envelope_time_constant(plate["f0_hz"], plate["q"])
    ax.plot(d.x[a:b], y[a - a0:], lw=0.9, color="C3", ls=":",
            label="what the plate plays, swiping right at %g mm/s (Q %g: tau %.0f \u00b5s = %.1f \u00b5m)"
                  % (plate["speed_mm_s"], plate["q"], tau * 1e6, tau * plate["speed_mm_s"] * 1e3))


def _demo_spectra(ax_spec: Any, d: _Demo) -> None:
    """3. spectrum of every non-constant region (c/mm on this display's spacing)."""
    texs, colors = d.texs, d.colors
    nyq = 1.0 / (2.0 * d.dx)                      # c/mm
    scale = texel.DX_MM / d.dx                    # spectrum() assumes 5.3 um samples
    peak, shown = 0.0, 0
    for k, (s, e) in enumerate(d.spans):
        if not d.textured[k] or e - s < 2:
            continue
        f, am = spectrum(d.fmap[s:e])
        f = f * scale
        keep = f > 0
        peak = max(peak, float(am[keep].max()))
        ax_spec.loglog(f[keep], np.maximum(am[keep], 1e-12), lw=0.5, color=colors[k],
                       label=_label(k, texs[k], True) if shown < 6 else None)
        if texs[k]["kind"] == "texel":
            ax_spec.axvline(10 ** (texs[k]["pitch_db"] / 10) * scale, color=colors[k], ls=":",
                            lw=1.4, label=("R%d central pitch %.3g c/mm" % (
                                k + 1, 10 ** (texs[k]["pitch_db"] / 10) * scale))
                            if shown < 6 else None)
        shown += 1
    if shown > 6:
        ax_spec.plot([], [], " ", label="(+%d more regions)" % (shown - 6))
    if shown:
        ax_spec.axvline(nyq, color="C3", ls="--", lw=1, label="Nyquist %.1f c/mm" % nyq)
        ax_spec.set_ylim(max(peak, 1e-9) * 1e-5, max(peak, 1e-9) * 3)
        ax_spec.legend(loc="lower left", fontsize="x-small", framealpha=0.9)
    else:
        _note(ax_spec, "no textured region\n(constant levels only)")
    ax_spec.set_xlabel("spatial frequency (cycles/mm)")
    ax_spec.set_ylabel("amplitude")
    ax_spec.set_title("spectrum per region (Hann, mean removed)", fontsize="medium")


def _demo_histograms(ax_hist: Any, d: _Demo) -> None:
    """4. texel pitch histograms against the drawing distribution (first 4 texel regions)."""
    texs, colors = d.texs, d.colors
    tk = [k for k, t in enumerate(texs) if t["kind"] == "texel"]
    if not tk:
        _note(ax_hist, "no texel region in this scene")
        ax_hist.set_title("texel pitch histogram", fontsize="medium")
        ax_hist.set_xlabel("texel pitch (dB re 1 cycle/mm)")
        ax_hist.set_ylabel("density (1/dB)")
        return
    plans = []
    for k in tk[:4]:
        p = {key: v for key, v in texs[k].items() if key != "kind"}
        p["length_samples"] = d.spans[k][1] - d.spans[k][0]   # the region sets the length
        plans.append((k, texel.make_plan(p)))
    lo = min(min(10 * np.log10(np.asarray(pl.f, dtype=np.float64)).min(),
                 pl.params["pitch_db"] - 4 * 10 * 10 ** (pl.params["irregularity_db"] / 10))
             for _, pl in plans)
    hi = max(max(10 * np.log10(np.asarray(pl.f, dtype=np.float64)).max(),
                 pl.params["pitch_db"] + 4 * 10 * 10 ** (pl.params["irregularity_db"] / 10))
             for _, pl in plans)
    if hi - lo < 1e-6:
        lo, hi = lo - 0.5, hi + 0.5
    grid = np.linspace(lo, hi, 400)                           # dB re 1 c/mm
    fracs = []
    for k, pl in plans:
        db = 10 * np.log10(np.asarray(pl.f, dtype=np.float64))
        bins = int(min(60, max(10, math.sqrt(db.size) * 2)))
        ax_hist.hist(db, bins=np.linspace(lo, hi, bins + 1), density=True, color=colors[k],
                     **(dict(alpha=0.45) if len(plans) == 1 else dict(histtype="step", lw=1.5)),
                     label="R%d: %d texels" % (k + 1, db.size))
        ax_hist.plot(grid, pitch_normal_pdf(grid, pl.params["pitch_db"],
                                            pl.params["irregularity_db"]),
                     color=colors[k], lw=1.5)
        fracs.append("R%d %.0f%%" % (k + 1, 100 * pl.fraction_above_nyquist()))
    nyq_db = 10 * math.log10(texel.NYQUIST_CPMM)              # the plan's own sample spacing
    if lo <= nyq_db <= hi:
        ax_hist.axvline(nyq_db, color="C3", ls="--", lw=1,
                        label="Nyquist (above: %s)" % ", ".join(fracs))
    else:
        ax_hist.plot([], [], " ", label="above Nyquist: %s" % ", ".join(fracs))
    ax_hist.plot([], [], color="0.3", lw=1.5, label="drawing distribution (lines)")
    ax_hist.set_xlim(lo, hi)
    ax_hist.set_ylim(0, ax_hist.get_ylim()[1] * 1.3)             # headroom for the legend
    ax_hist.legend(loc="upper right", fontsize="x-small", framealpha=0.9)
    ax_hist.set_title("texel pitch histogram%s" % (
        " (first 4 of %d texel regions)" % len(tk) if len(tk) > 4 else ""), fontsize="medium")
    ax_hist.set_xlabel("texel pitch (dB re 1 cycle/mm)")
    ax_hist.set_ylabel("density (1/dB)")


def _demo_time(ax_time: Any, d: _Demo) -> None:
    """5. played amplitude and finger position over time (lifted = gaps)."""
    ts, down, amp, pos, dx, npos, tr = d.ts, d.down, d.amp, d.pos, d.dx, d.npos, d.tr
    ax_pos = ax_time.twinx()
    handles = []
    if down.any():
        handles.append(ax_time.plot(ts, np.where(down, amp / _U16, np.nan), lw=0.5, marker=".",
                                    ms=3, color="C0", label="played amplitude")[0])
    if (~down).any():
        handles.append(ax_time.plot(ts[~down], amp[~down] / _U16, ls="none", marker="o",
                                    ms=3, mfc="none", color="0.5",
                                    label="played while lifted (idle)")[0])
    if down.any():
        handles.append(ax_pos.plot(ts, np.where(down, pos * dx, np.nan), lw=1.2, color="C1",
                                   label="sensed finger (mm)")[0])
    if tr is not None and len(tr):
        handles.append(ax_pos.plot(d.tr_s, np.where(tr[:, 1] >= 0, tr[:, 1] * dx, np.nan), lw=1,
                                   ls="--", color="k", label="true finger (mm)")[0])
    if not len(d.tel):
        _note(ax_time, "no telemetry")
    elif not down.any():
        ax_time.text(0.5, 0.6, "finger lifted throughout", transform=ax_time.transAxes,
                     ha="center", color="C3")
    ax_time.set_ylim(-0.03, 1.3)
    ax_time.set_yticks([0, 0.25, 0.5, 0.75, 1])
    ax_pos.set_ylim(-0.03 * npos * dx, 1.3 * npos * dx)
    ax_time.set_xlabel("time since the first sample (s)")
    ax_time.set_ylabel("played friction reduction", color="C0")
    ax_pos.set_ylabel("finger position (mm)", color="C1")
    ax_time.set_title("played amplitude and finger over time", fontsize="medium")
    if handles:
        ax_pos.legend(handles=handles, loc="upper left", ncol=len(handles), fontsize="small",
                       framealpha=0.9)


# --- the `texelpad encode` figure ---------------------------------------------------

def encode_figure(path: str | Path, fmap: Any, result: dict, decoded: Any = None,
                  title: str = "") -> None:
    """One PNG (or .pdf/.svg) for an encoder result (texelpad.analysis.encoder.encode):
    the map and its decoding (the texture rendered, as a board plays it) over
    the same stretch, both spectra on a log-frequency axis, the felt
    distributions the encoder compared, and the figures of the report.
    decoded: the rendering (default: encoder.decode(result))."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from .encoder import decode

    x = np.asarray(fmap, dtype=np.float64)
    y = decode(result) if decoded is None else np.asarray(decoded, dtype=np.float64)
    fig = Figure(figsize=(11, 12), layout="constrained")
    FigureCanvasAgg(fig)
    gs = fig.add_gridspec(4, 2, height_ratios=[1, 1, 1.25, 1.1])
    ax_map = fig.add_subplot(gs[0, :])
    ax_dec = fig.add_subplot(gs[1, :], sharex=ax_map)
    ax_spec = fig.add_subplot(gs[2, :])
    ax_felt = fig.add_subplot(gs[3, 0])
    ax_text = fig.add_subplot(gs[3, 1])

    tex = result["texture"]
    src = result.get("source") or "map"
    fig.suptitle("%s%s \u2192 pitch %.2f dB (%.3g c/mm), irregularity %.2f dB (%.3g decade), "
                 "gain %.3g\nfelt distance %.3f dB (method %s), felt spectra %.3f dB apart "
                 "(W2)" % (
                     (title + ": ") if title else "", src, tex["pitch_db"],
                     10 ** (tex["pitch_db"] / 10), tex["irregularity_db"],
                     10 ** (tex["irregularity_db"] / 10), tex["gain"],
                     result["felt_distance_db"], result["method"], result["w2_distance_db"]))

    _encode_maps(ax_map, ax_dec, x, y, tex)
    _encode_spectra(ax_spec, y, tex, result)
    _encode_felt(ax_felt, tex, result)
    _encode_words(ax_text, tex, result)
    fig.savefig(str(path), dpi=100)


def _encode_maps(ax_map: Any, ax_dec: Any, x: np.ndarray, y: np.ndarray, tex: dict) -> None:
    """1-2. the map and its decoding over the same stretch: 6 mm (seed 000's Fig. 4
    shows 6-mm samples), or the whole map when shorter."""
    n = x.size
    dx = texel.DX_MM
    nz = int(min(n, round(6.0 / dx)))
    xs = np.arange(nz) * dx
    ax_map.plot(xs, x[:nz], lw=0.8, color="C0")
    ax_dec.plot(xs, y[:nz], lw=0.8, color="C1")
    L = tex["texel_samples"]
    if nz // max(L, 1) <= 40:
        for k in range(L, nz, L):
            ax_dec.axvline(k * dx, color="0.85", lw=0.6, zorder=0)
    for ax, what in ((ax_map, "the map"), (ax_dec, "encode \u2192 render: the texture as a "
                                                   "board plays it (seed %d%s)"
                                                   % (tex["seed"], ", texel borders in grey"
                                                      if nz // max(L, 1) <= 40 else ""))):
        ax.set_ylim(-0.03, 1.03)
        ax.set_ylabel("friction reduction")
        ax.set_title("%s, first %.3g mm of %.4g mm" % (what, nz * dx, n * dx), fontsize="medium")
    ax_dec.set_xlabel("position (mm)")
    ax_map.set_xlim(0, max(xs[-1], dx))


def _encode_spectra(ax_spec: Any, y: np.ndarray, tex: dict, result: dict) -> None:
    """3. spectra: band power on the log-frequency axis (the encoder's), the decoded
    rendering's own spectrum, and where a finger at the model's speed feels them."""
    from . import perception as P
    sp = result["spectrum"]
    f = np.asarray(sp["f_cpmm"])
    ax_spec.semilogx(f, sp["map_db"], color="C0", lw=1.6, label="the map")
    ax_spec.semilogx(f, sp["rendering_db"], color="C1", lw=1.6,
                     label="the texture (expected over seeds)")
    fd, Pd = P.periodogram(y)
    pat = P.pattern_of_spectrum(Pd, P.segment_length(y.size))
    keep = (P.GRID >= math.log10(max(fd[1], 1e-9))) & (P.GRID <= math.log10(texel.NYQUIST_CPMM))
    ax_spec.semilogx(10 ** P.GRID[keep], 10 * np.log10(np.maximum(pat.band_power[keep], 1e-15)
                                                      / P.FULL_SCALE_POWER),
                     color="C1", lw=0.7, ls=":", label="this rendering (seed %d)" % tex["seed"])
    speed = result["model"]["speed_mm_s"]
    mod = _model_of(result["model"])
    thr = P.force_threshold_db(speed * f, mod) - mod.full_scale_sl_db
    ax_spec.semilogx(f, thr, color="0.4", lw=1, ls="--",
                     label="detection threshold at %g mm/s (model)" % speed)
    ax_spec.axvline(result["skin_band"]["cpmm"][1], color="0.4", ls=":", lw=1,
                    label="the skin's band ends (%.0f Hz)" % result["skin_band"]["hz"][1])
    ax_spec.axvline(texel.NYQUIST_CPMM, color="C3", ls="--", lw=1,
                    label="Nyquist %.1f c/mm" % texel.NYQUIST_CPMM)
    ax_spec.axvline(10 ** (tex["pitch_db"] / 10), color="C2", ls=":", lw=1.2,
                    label="central pitch %.3g c/mm" % 10 ** (tex["pitch_db"] / 10))
    top = max(max(sp["map_db"]), max(sp["rendering_db"]))
    ax_spec.set_ylim(top - 70, top + 8)
    ax_spec.set_xlim(f[0], texel.NYQUIST_CPMM * 1.05)
    ax_spec.set_xlabel("spatial frequency (cycles/mm); felt at \u00d7%g Hz" % speed)
    ax_spec.set_ylabel("band power (dB re full-scale sine)")
    ax_spec.set_title("spectra on a log-frequency axis: power within \u00b11 dB (0.1 decade) "
                      "bands", fontsize="medium")
    ax_spec.legend(loc="lower left", fontsize="small", ncol=2, framealpha=0.9)
    ax_spec.grid(True, which="both", alpha=0.25)


def _encode_felt(ax_felt: Any, tex: dict, result: dict) -> None:
    """4. what the encoder compared: the felt distributions over pitch (dB)."""
    sp = result["spectrum"]
    lf = np.asarray(sp["log10_f"]) * 10.0
    ax_felt.fill_between(lf, sp["map_felt"], step="mid", alpha=0.35, color="C0", label="the map")
    ax_felt.step(lf, sp["rendering_felt"], where="mid", color="C1", lw=1.4, label="the texture")
    ax_felt.axvline(tex["pitch_db"], color="C2", ls=":", lw=1.2)
    ax_felt.set_xlabel("pitch (dB re 1 c/mm)")
    ax_felt.set_ylabel("share of the felt power")
    ax_felt.set_title("felt spectra: pitch %.2f / %.2f dB, noisiness %.2f / %.2f dB "
                      "(map / texture)" % (result["felt"]["map"]["pitch_db"],
                                           result["felt"]["rendering"]["pitch_db"],
                                           result["felt"]["map"]["noisiness_db"],
                                           result["felt"]["rendering"]["noisiness_db"]),
                      fontsize="medium")
    ax_felt.legend(loc="upper left", fontsize="small")


def _encode_words(ax_text: Any, tex: dict, result: dict) -> None:
    """5. the report's figures in words."""
    ax_text.axis("off")
    lines = ["texture: %s" % _short_texture(tex)]
    rg = result.get("ranges")
    if rg:
        lines.append("feels the same (within %.3g dB): pitch %.2f .. %.2f dB, irregularity "
                     "%.2f .. %.2f dB" % (rg["limit_db"], rg["pitch_db"][0],
                                          rg["pitch_db"][1], rg["irregularity_db"][0],
                                          rg["irregularity_db"][1]))
    lines.append("felt distance %.3f dB (under %g: the same); W2 between the felt spectra "
                 "%.3f dB; method %s" % (result["felt_distance_db"], result["model"]["jnd_db"],
                                         result["w2_distance_db"], result["method"]))
    c = result["compression"]
    lines.append("compression: %s bytes of map (uint16) \u2192 %d bytes of texture: %gx"
                 % (format(c["map_bytes"], ","), c["texture_bytes"], c["ratio"]))
    a = result["aliasing"]
    lines.append("aliased texels (above Nyquist): %.1f %% expected, %d of %d drawn"
                 % (100 * a["expected_fraction"], a["drawn_texels"], a["texels"]))
    qz = result.get("quantization")
    if qz:
        lines.append("distance with pitch quantization: " + ", ".join(
            "%s dB: %.2f" % (k, v) for k, v in qz["cost_db"].items()))
    m = result["model"]
    lines.append("model: %g mm/s, full scale %g dB above threshold, masking %s, resolution "
                 "%g decade, fingertip corner %s, lines %s"
                 % (m["speed_mm_s"], m["full_scale_sl_db"],
                    "off" if m["masking_db"] is None else "%g dB" % m["masking_db"],
                    m["resolution_decades"],
                    "off" if m["fingertip_corner_hz"] is None else "%g Hz"
                    % m["fingertip_corner_hz"],
                    "off" if m["line_db"] is None else "%g dB" % m["line_db"]))
    for note in result.get("notes", [])[:3]:
        lines.append("note: " + note)
    import textwrap
    ax_text.text(0.0, 1.0, "\n".join(textwrap.fill(s, 62, subsequent_indent="   ")
                                     for s in lines),
                 transform=ax_text.transAxes, va="top", ha="left", fontsize="small",
                 family="monospace")


def _model_of(d: dict) -> Any:
    """The perception.Model a result's "model" dict describes."""
    from . import perception as P
    return P.Model(**{k: d[k] for k in ("speed_mm_s", "full_scale_sl_db", "masking_db",
                                        "resolution_decades", "slope_above_db_per_octave",
                                        "fingertip_corner_hz", "line_db")})


def _short_texture(tex: dict) -> str:
    return "{" + ", ".join("%r: %s" % (k, ("%g" % v) if isinstance(v, float) else v)
                           for k, v in tex.items()) + "}"
