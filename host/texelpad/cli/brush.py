"""`texelpad brush`: the Tactile Paintbrush (seed 002; docs/brush.md) from the
command line - fit a brush from a friction recording, design one by hand,
paint it to a map or a scene, show it, compare two.

    texelpad brush fit REC.csv [REC2.csv ...] --out brush.json
    texelpad brush fit --reference pink --out pink.json      (a map in amplitude units)
    texelpad brush design --shape pink --level 0.05 --mean 0.5 --out b.json
    texelpad brush paint brush.json --seed 3 --out map.csv   (position_mm,friction)
    texelpad brush paint brush.json --seed 3 --scene s.json  (then: texelpad push --scene s.json)
    texelpad brush show brush.json [--out fig.png] [--original REC.csv]
    texelpad brush compare a.json b.json [--metric braycurtis]

Output files are checked before the work and written atomically. Bad input
(a broken CSV, a brush the board would refuse) is one line naming it, exit 2.
"""
from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

from .errors import EXIT_OK, CliError, to_stderr as _stderr
from .files import check_output, write_atomic, write_output
from .scene_files import scene_json

METRICS = ("euclidean", "canberra", "braycurtis")


def add_brush(p: argparse.ArgumentParser) -> None:
    from texel.gen.brush import NYQ

    from .parsing import Parser as _Parser
    p.description = ("The Tactile Paintbrush (seed 002): a texture as the Weibull distribution "
                     "of its spectral magnitudes per wavenumber - fitted from a recording, "
                     "designed by hand, painted onto a map or a board's region.")
    sub = p.add_subparsers(dest="action", metavar="ACTION", parser_class=_Parser)
    s = sub.add_parser("fit", help="fit a brush to friction recordings (CSV: position_mm, "
                                   "friction) or a reference texture",
                       description="Fit a brush: the space-frequency transform of every "
                                   "recording (resampled to the display's 5.3 um), Weibull by "
                                   "maximum likelihood per wavenumber over all their windows.")
    s.add_argument("recordings", nargs="*", metavar="REC.csv",
                   help="CSV with a header naming the columns: the position in mm "
                        "(position_mm or x_mm, as texelpad render writes it) and friction")
    s.add_argument("--reference", metavar="NAME", help="fit a reference texture's map instead")
    s.add_argument("--kind", choices=("friction", "amplitude"),
                   help="friction (default for recordings: high friction plays as low "
                        "amplitude) or amplitude (default for --reference: 0..1 as played)")
    s.add_argument("--name", default="", help="the brush's name")
    s.add_argument("--out", required=True, metavar="FILE", help="brush.json (or .tpb: binary)")
    s.set_defaults(func=cmd_brush_fit)
    s = sub.add_parser("design", help="a brush by hand from a spectral shape",
                       description="A brush from a spectral shape: the scale at wavenumber n "
                                   "is level * (n/4)^(slope/6.02) (n = 4: a 0.25 mm "
                                   "wavelength), every shape k.")
    s.add_argument("--shape", default="white",
                   help="white, pink, brown, blue, or a slope in dB per octave")
    s.add_argument("--level", type=float, default=0.05, help="scale at n = 4 (amplitude units)")
    s.add_argument("--mean", type=float, default=0.5, help="the mean's scale (amplitude)")
    s.add_argument("--k", type=float, default=2.0, help="shape of every wavenumber (2: Rayleigh)")
    s.add_argument("--band", type=int, nargs=2, default=(1, NYQ), metavar=("LOW", "HIGH"),
                   help="wavenumbers painted (default 1 %d: the Nyquist)" % NYQ)
    s.add_argument("--name", default="")
    s.add_argument("--out", required=True, metavar="FILE")
    s.set_defaults(func=cmd_brush_design)
    s = sub.add_parser("paint", help="paint a brush to a map (CSV) or a scene (JSON)",
                       description="Paint a brush with a seed - the same map a board's brush "
                                   "region paints - to a CSV (position_mm, friction in the "
                                   "brush's units) or a scene file for texelpad push --scene.")
    s.add_argument("brush", metavar="BRUSH")
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--length-mm", type=float, default=101.76, help="default: the full screen")
    s.add_argument("--start-mm", type=float, default=0.0, help="--scene: where the region starts")
    s.add_argument("--out", metavar="FILE.csv", help="the painted map")
    s.add_argument("--scene", metavar="FILE.json", help="a scene with the brush region")
    s.set_defaults(func=cmd_brush_paint)
    s = sub.add_parser("show", help="plot a brush: lam and k against wavenumber, a painting",
                       description="Plot a brush (lam and k against wavelength) and a painted "
                                   "sample, beside an original recording if given; prints its "
                                   "summary and sizes.")
    s.add_argument("brush", metavar="BRUSH")
    s.add_argument("--out", metavar="FILE.png", help="the figure (default: BRUSH.png)")
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--original", metavar="REC.csv", help="the recording it was fitted to")
    s.set_defaults(func=cmd_brush_show)
    s = sub.add_parser("compare", help="distance between two brushes: seed 002's metric and "
                                       "how far apart they feel")
    s.add_argument("a", metavar="A")
    s.add_argument("b", metavar="B")
    s.add_argument("--metric", choices=METRICS, default="braycurtis")
    s.add_argument("--no-felt", action="store_true",
                   help="skip the felt distance (it paints each brush three times)")
    s.set_defaults(func=cmd_brush_compare)
    p.set_defaults(func=_no_action)


def _no_action(args: argparse.Namespace) -> int:
    raise CliError("", "say what to do: texelpad brush fit|design|paint|show|compare "
                   "(see: texelpad brush --help)")


def _load(flag: str, path: str) -> dict:
    from ..brush.document import load
    try:
        return load(path)
    except OSError as e:
        raise CliError(flag, "cannot read %s: %s" % (path, e.strerror or e)) from None
    except ValueError as e:
        raise CliError(flag, str(e)) from None


def _save(flag: str, doc: dict, path: str) -> None:
    from ..brush.document import save
    write_output(flag, path, lambda: save(doc, path))


def cmd_brush_fit(args: argparse.Namespace) -> int:
    import numpy as np

    from ..brush.document import fit
    from ..brush.transform import read_recording, resample
    check_output("--out", args.out, (".json", ".tpb"))
    if bool(args.recordings) == bool(args.reference):
        raise CliError("REC.csv", "give recordings or --reference NAME (one of them)")
    maps, source = [], []
    if args.reference:
        from ..analysis.encoder import EncodeError, reference_map
        try:
            maps.append(np.asarray(reference_map(args.reference), float))
        except EncodeError as e:
            raise CliError("--reference", str(e)) from None
        kind = args.kind or "amplitude"
        source.append("reference %s" % args.reference)
    else:
        for rec in args.recordings:
            try:
                pos, fr = read_recording(rec)
                maps.append(resample(pos, fr))
            except OSError as e:
                raise CliError("REC.csv", "cannot read %s: %s" % (rec, e.strerror or e)) from None
            except ValueError as e:
                raise CliError("REC.csv", str(e)) from None
            source.append(Path(rec).name)
        kind = args.kind or "friction"
    t0 = time.perf_counter()
    try:
        doc = fit(maps, kind, name=args.name or Path(args.out).stem, source=", ".join(source))
    except ValueError as e:
        raise CliError("REC.csv", str(e)) from None
    dt = time.perf_counter() - t0
    _save("--out", doc, args.out)
    ks = doc["fit"]["ks"]
    print("fitted %d windows (%.1f mm) in %.2f s: K-S of the Weibull fits median %.3f, worst "
          "%.3f (wavenumber %d); range %s -> amplitude 0..1; wrote %s"
          % (doc["fit"]["windows"], sum(len(m) for m in maps) * 0.0053, dt,
             float(np.median(ks)), max(ks), ks.index(max(ks)),
             [round(x, 4) for x in doc["range"]], args.out))
    return EXIT_OK


def cmd_brush_design(args: argparse.Namespace) -> int:
    from ..brush.document import design
    check_output("--out", args.out, (".json", ".tpb"))
    try:
        shape = args.shape if args.shape in ("white", "pink", "brown", "blue") \
            else float(args.shape)
    except ValueError:
        raise CliError("--shape", "expected white, pink, brown, blue or dB per octave, got %r"
                       % args.shape) from None
    if not math.isfinite(shape if isinstance(shape, float) else 0.0):
        raise CliError("--shape", "a slope must be a finite number of dB per octave, got %s"
                       % args.shape)
    for flag, v in (("--level", args.level), ("--mean", args.mean), ("--k", args.k)):
        if not math.isfinite(v):
            raise CliError(flag, "must be a finite number, got %s" % v)
    try:
        doc = design(shape, args.level, args.mean, args.k, band=tuple(args.band),
                     name=args.name)
    except ValueError as e:
        raise CliError(_design_flag(str(e), args), str(e)) from None
    _save("--out", doc, args.out)
    print("wrote %s (%s)" % (args.out, doc["source"]))
    return EXIT_OK


def _design_flag(message: str, args: argparse.Namespace) -> str:
    """The flag a refused design came from, by the key path the brush's own
    validation names: brush.k[n] is --k, brush.lam[0] the mean's scale
    (--mean), brush.lam[n] the scale at wavenumber n: --level, unless the
    level is within range and a slope in dB per octave took it out (--shape)."""
    path = message.partition(": ")[0]
    if path.startswith("band"):
        return "--band"
    if path.startswith("brush.k["):
        return "--k"
    if path == "brush.lam[0]":
        return "--mean"
    if path.startswith("brush.lam["):
        from texel.gen.brush import LAM_MAX
        level_ok = 0 <= args.level <= LAM_MAX
        sloped = args.shape not in ("white", "pink", "brown", "blue")
        return "--shape" if level_ok and sloped else "--level"
    return "--shape"


def cmd_brush_paint(args: argparse.Namespace) -> int:
    import numpy as np

    from ..brush.document import paint, region, to_values
    from ..link.board import host_check
    if not args.out and not args.scene:
        raise CliError("--out", "give --out FILE.csv (the map) and/or --scene FILE.json")
    if args.out:
        check_output("--out", args.out, (".csv",))
    if args.scene:
        check_output("--scene", args.scene, (".json",))
    if not 0 <= args.seed <= 0xFFFFFFFF:
        raise CliError("--seed", "expected 0 .. 4294967295, got %d" % args.seed)
    for flag, v in (("--length-mm", args.length_mm), ("--start-mm", args.start_mm)):
        if not math.isfinite(v):
            raise CliError(flag, "must be a finite number of mm, got %s" % v)
    n = int(round(args.length_mm / 0.0053))
    if not 1 <= n <= 19200 * 8:
        raise CliError("--length-mm", "expected 0.0053 .. %g mm, got %g"
                       % (19200 * 8 * 0.0053, args.length_mm))
    doc = _load("BRUSH", args.brush)
    if args.scene:
        end = round(args.start_mm + args.length_mm, 4)
        scene = {"name": "brush %s seed %d" % (doc.get("name") or Path(args.brush).stem,
                                               args.seed),
                 "regions": [region(doc, args.seed, args.start_mm, end)]}
        try:
            host_check(scene)                   # the board's own validation
        except ValueError as e:
            raise CliError("--scene", str(e)) from None
        write_output("--scene", args.scene, lambda: write_atomic(args.scene, scene_json(scene)))
        print("wrote %s: a %.2f mm brush region (%d bytes of scene for %d bytes of map); play "
              "it with texelpad push --scene %s" % (args.scene, args.length_mm,
                                                    len(json.dumps(scene)), 2 * n, args.scene))
    if args.out:
        t0 = time.perf_counter()
        u16 = paint(doc, args.seed, n)
        dt = time.perf_counter() - t0
        vals = to_values(doc, u16)
        pos = np.arange(n) * 0.0053

        def write() -> None:
            lines = ["position_mm,friction"] + ["%.4f,%.6g" % (p, v) for p, v in zip(pos, vals)]
            write_atomic(args.out, "\n".join(lines) + "\n")
        write_output("--out", args.out, write)
        print("painted %d samples (%.2f mm) in %.2f s; wrote %s" % (n, n * 0.0053, dt, args.out))
    return EXIT_OK


def cmd_brush_show(args: argparse.Namespace) -> int:
    from ..brush.document import to_bytes
    out = args.out or str(Path(args.brush).with_suffix(".png"))
    check_output("--out", out, (".png", ".svg", ".pdf"))
    doc = _load("BRUSH", args.brush)
    original = None
    if args.original:
        from ..brush.transform import read_recording, resample
        try:
            original = resample(*read_recording(args.original))
        except (OSError, ValueError) as e:
            raise CliError("--original", str(e)) from None
    from ..brush.figures import brush_figure
    write_output("--out", out, lambda: brush_figure(doc, out, seed=args.seed, original=original))
    print("brush %s: range %s; mean scale %.4g (k %.3g); wavenumbers 1..%d: scale %.3g .. %.3g, "
          "shape %.3g .. %.3g; %d bytes as JSON, %d binary, a full screen map 38,400; wrote %s"
          % (doc.get("name") or args.brush, [round(x, 4) for x in doc["range"]],
             doc["lam"][0], doc["k"][0], len(doc["k"]) - 1, min(doc["lam"][1:]),
             max(doc["lam"][1:]), min(doc["k"][1:]), max(doc["k"][1:]), len(json.dumps(doc)),
             len(to_bytes(doc)), out))
    return EXIT_OK


def cmd_brush_compare(args: argparse.Namespace) -> int:
    from ..brush.document import distance
    a = _load("A", args.a)
    b = _load("B", args.b)
    d = distance(a, b, args.metric)
    print("%s distance %s .. %s: %.4f" % (args.metric, args.a, args.b, d))
    if not args.no_felt:
        from ..analysis.perception import JND_DB
        from ..brush.document import FELT_SEEDS, felt_distance
        fd, fa, fb = felt_distance(a, b)
        print("felt distance %s .. %s: %.2f dB (%s: under %g dB they feel the same)"
              % (args.a, args.b, fd, "the same" if fd < JND_DB else "different", JND_DB))
        for label, path, fp in (("A", args.a, fa), ("B", args.b, fb)):
            print("  %s felt pitch %.2f dB, noisiness %.2f dB (full screen, seeds %s)"
                  % (label, fp.pitch_db, fp.noisiness_db, ", ".join(map(str, FELT_SEEDS))))
    if a["range"] != b["range"]:
        _stderr("note: their ranges differ (%s, %s): the scales are in their own units"
                % (a["range"], b["range"]))
    return EXIT_OK
