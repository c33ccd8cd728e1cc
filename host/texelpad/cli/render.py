"""`texelpad render`: a texel texture rendered on the host, summarised, saved."""
from __future__ import annotations

import argparse
import math
from typing import Any

import texel

from .errors import EXIT_FAIL, EXIT_OK, CliError
from .files import check_output
from .texel_flags import add_texel_flags, device_error, render_params


OUT_TYPES = (".png", ".csv", ".npy")


def add_render(p: argparse.ArgumentParser) -> None:
    p.description = ("Render a Single-Pitch Texel friction map on the host and print a summary "
                    "(texels, fraction above Nyquist, pitch range). --out writes the map as "
                    ".csv (sample, x_mm, friction) or .npy (float64), or a .png figure of the "
                    "map, its spectrum and the texel pitch histogram against the "
                    "Normal(pitch_db, 10*sigma) pitch distribution.")
    g = p.add_argument_group("texture parameters (ranges: see the texel package)")
    add_texel_flags(g, required=("pitch_db", "irregularity_db"))
    p.add_argument("--engine", metavar="NAME",
                   help="render engine: numpy (default on CPython), int, pure (ulab "
                        "runs on boards with ulab: texelpad bench measures it)")
    p.add_argument("--out", metavar="FILE", help="write FILE.png, FILE.csv or FILE.npy")
    p.set_defaults(func=cmd_render)


def to_numpy(buf: Any) -> Any:
    import numpy as np
    return np.asarray(buf, dtype=np.float64)


def summary(plan: Any, engine: str) -> str:
    """One paragraph: texels, pitch range, fraction above Nyquist."""
    p = plan.params
    f = [float(x) for x in plan.f]
    lo, hi = min(f), max(f)
    srt = sorted(f)
    med = srt[len(srt) // 2] if len(srt) % 2 else 0.5 * (srt[len(srt) // 2 - 1] + srt[len(srt) // 2])
    sigma = 10.0 ** (p["irregularity_db"] / 10.0)
    L = plan.L
    whole, rest = divmod(plan.n, L)
    texels = "%d texel%s of %d sample%s (%.4g mm)" % (
        whole, "" if whole == 1 else "s", L, "" if L == 1 else "s", L * texel.DX_MM)
    if rest and whole:
        texels += " plus one cut to %d" % rest
    elif rest:
        texels = "one texel of %d samples (%.4g mm) cut to the map" % (L, L * texel.DX_MM)
    quant = ("pitches quantized to a %g dB grid" % p["quant_db"]) if p["quant_db"] > 0 \
        else "no quantization"
    if p["band_limit_cpmm"] is not None:
        quant += ", pitches clamped to <= %.4g c/mm" % p["band_limit_cpmm"]
    above = plan.above_nyquist
    return (
        "Rendered %d samples (%.2f mm) with the %s engine: %s. Central pitch %.4g c/mm "
        "(%.2f dB), irregularity %.4g decade (%.2f dB), seed %d, format %d, %s, gain %g. Drawn "
        "texel pitches span %.4g .. %.4g c/mm (%.2f .. %.2f dB, median %.4g c/mm); %d of %d texels "
        "(%.1f %%) lie above Nyquist (%.2f c/mm)%s."
        % (plan.n, plan.n * texel.DX_MM, engine, texels, 10 ** (p["pitch_db"] / 10.0),
           p["pitch_db"], sigma, p["irregularity_db"], p["seed"], p["v"], quant, p["gain"],
           lo, hi, 10 * math.log10(lo), 10 * math.log10(hi), med, above, plan.count,
           100.0 * above / plan.count, texel.NYQUIST_CPMM,
           "" if above == 0 else " and alias, as in the original generator"))


def cmd_render(args: argparse.Namespace) -> int:
    import numpy as np
    params = render_params(args)
    try:
        texel.validate(params)          # the flags first (exit 2), then the file (exit 1)
    except ValueError as e:
        raise device_error(e) from None
    # the output file is checked BEFORE rendering: a typo in its directory
    # costs nothing
    out = check_output("--out", args.out, OUT_TYPES) if args.out else None
    try:
        plan = texel.make_plan(params)
        engine = args.engine or texel.default_engine()
        fmap = to_numpy(texel.render(params, engine=engine))
    except ValueError as e:
        raise device_error(e) from None
    print(summary(plan, engine))
    if out is None:
        return EXIT_OK
    try:
        kind = out.suffix.lower()
        if kind == ".npy":
            # through an open file: np.save(path) appends ".npy" to a name that
            # does not end in it exactly (M.NPY became M.NPY.npy, and "wrote
            # M.NPY" named a file that was not there - the fuzz job found it)
            with open(out, "wb") as f:
                np.save(f, fmap)
        elif kind == ".csv":
            k = np.arange(fmap.size)
            np.savetxt(out, np.column_stack([k, k * texel.DX_MM, fmap]),
                       fmt=("%d", "%.4f", "%.10f"), delimiter=",",
                       header="sample,x_mm,friction", comments="")
        else:
            from ..analysis.figures import render_figure
            render_figure(fmap, plan, out, engine=engine)
    except OSError as e:
        raise CliError("--out", "cannot write %s: %s" % (out, e.strerror or e),
                       EXIT_FAIL) from None
    print("wrote %s" % out)
    return EXIT_OK

