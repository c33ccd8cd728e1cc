"""The report on what painting makes (bench.brush_painting; issue 21
items 4-5), run small: two sources, three short swipes each. Its structure,
that every number is finite and in range, the autocorrelation and the
silhouettes against independent computations, the figure and the JSON.
Whether a painting meets issue 21's |r| <= 0.1 is the painter's test
(tests/brush/test_paint.py), not this one: here the report only says it."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from texel.gen import brush as B
from texel.gen.params import DX_MM
from bench import brush_painting as BP, jsonable
from texelpad.brush import compare as C
from texelpad.brush import swipes as S

NAMES = ("pink", "texel-p15-i-5")
SWIPES = 3
SEEDS = (0, 1)
SAMPLES = 4800                  # a quarter screen: the report paints and swipes that


@pytest.fixture(scope="module")
def res():
    return BP.run(names=NAMES, swipes=SWIPES, paint_seeds=SEEDS,
                  model=S.SwipeModel(length_samples=1200), samples=SAMPLES)


def _finite(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def test_the_report_has_every_part_and_finite_numbers(res):
    cfg = res["config"]
    assert cfg["sources"] == list(NAMES) and cfg["swipes"] == SWIPES
    assert cfg["samples"] == SAMPLES and cfg["paint_seeds"] == list(SEEDS)
    assert (cfg["window"], cfg["hop"], cfg["wavenumbers"]) == (B.WINDOW, B.HOP, B.K)
    assert cfg["lags"]["1W"] == B.WINDOW and cfg["lags"]["2W"] == 2 * B.WINDOW
    assert cfg["lags"]["2mm"] == round(2 / DX_MM) and cfg["lags"]["10mm"] == round(10 / DX_MM)
    for name in NAMES:
        p = res["sources"][name]
        assert len(p["source_swipes"]) == SWIPES and len(p["painted_swipes"]) == SWIPES
        assert [s["painting_seed"] for s in p["painted_swipes"]] == [0, 1, 0]
        for s in p["source_swipes"] + p["painted_swipes"]:
            assert s["vector"].shape == (2 * B.K,) and np.all(np.isfinite(s["vector"]))
            assert 0.0 <= s["weibull_ks_mean"] <= 1.0
        assert p["_map"].shape == p["_paintings"][0].shape == (SAMPLES,)
        assert 0.0 <= p["_paintings"][0].min() and p["_paintings"][0].max() <= 1.0
        a = p["acf"]
        assert len(a["paintings"]) == len(SEEDS)
        for r in [a["source"], a["painting_mean"]] + a["paintings"]:
            assert set(r) == set(cfg["lags"])
            assert all(_finite(v) and -1.0 - 1e-9 <= v <= 1.0 + 1e-9 for v in r.values())
        assert isinstance(a["criterion_met"], bool)
        q = res["perception"][name]
        for key in ("source_painting", "source_painting2", "painting_painting2",
                    "to_nearest_other", "to_others_median", "level_source_db",
                    "level_painting_db", "w2_source_painting"):
            assert _finite(q[key]), key
        assert q["source_painting"] >= 0 and q["nearest_other"] in NAMES and \
            q["nearest_other"] != name
    for me in C.METRICS:
        c = res["compare"][me]
        for key in ("silhouette_sources", "silhouette_with_paintings",
                    "silhouette_source_swipes_mean", "silhouette_painted_swipes_mean"):
            assert _finite(c[key]) and -1.0 <= c[key] <= 1.0, (me, key)
        assert 0.0 <= c["accuracy_source"] <= 1.0 and 0.0 <= c["accuracy_painted"] <= 1.0
        for name in NAMES:
            r = c["sources"][name]
            for key in ("within_source", "source_to_painting", "within_painting",
                        "to_nearest_other", "to_others_median", "ratio"):
                assert _finite(r[key]) and r[key] >= 0, (me, name, key)
            assert -1.0 <= r["silhouette_source"] <= 1.0
            assert -1.0 <= r["silhouette_painted"] <= 1.0
            assert 0 <= r["correct_painted"] <= SWIPES
            assert set(r["classified_painted"]) <= set(NAMES)


def test_the_source_swipes_silhouette_is_sklearns(res):
    """Per source, the mean silhouette of its swipes is sklearn's
    silhouette_samples over the sources' swipes (Euclidean: no variances
    from the set), and the overall one compare.silhouette's."""
    from sklearn.metrics import silhouette_samples
    X = np.stack([s["vector"] for n in NAMES for s in res["sources"][n]["source_swipes"]])
    labels = [n for n in NAMES for _ in range(SWIPES)]
    D = C.distance_matrix(X, "euclidean")
    sil = silhouette_samples(D, labels, metric="precomputed")
    c = res["compare"]["euclidean"]
    for i, n in enumerate(NAMES):
        assert c["sources"][n]["silhouette_source"] == pytest.approx(
            sil[i * SWIPES:(i + 1) * SWIPES].mean(), abs=1e-9)
    assert c["silhouette_sources"] == pytest.approx(C.silhouette(D, labels), abs=1e-12)


def test_the_autocorrelation():
    n = np.arange(5000)
    lag = 200
    x = 0.5 + 0.4 * np.sin(2 * np.pi * n / 100.0)
    r = BP.autocorrelation(x, lag)
    assert r[0] == pytest.approx(1.0)
    assert r[100] == pytest.approx(1.0, abs=1e-9) and r[50] == pytest.approx(-1.0, abs=1e-9)
    assert r[25] == pytest.approx(0.0, abs=0.01)     # a partial period at the end
    rng = np.random.default_rng(1)
    y = rng.standard_normal(3000)
    r = BP.autocorrelation(y, 40)
    yc = y - y.mean()
    assert r[37] == pytest.approx(np.dot(yc[:-37], yc[37:]) / (3000 - 37) / np.mean(yc * yc))
    assert np.all(BP.autocorrelation(np.full(300, 0.3), 10)[1:] == 0.0)


def test_tables_json_and_figure(res, tmp_path):
    text = BP.format_tables(res)
    for word in ("Bray-Curtis", "standardized Euclidean", "How it feels",
                 "Autocorrelation", "|r|<=0.1", "pink", "texel-p15-i-5"):
        assert word in text
    doc = json.loads(json.dumps(jsonable(res), allow_nan=False))
    assert "_map" not in doc["sources"]["pink"] and "_paintings" not in doc["sources"]["pink"]
    assert len(doc["sources"]["pink"]["painted_swipes"][0]["vector"]) == 2 * B.K
    out = tmp_path / "painting.png"
    BP.figure(res, str(out))
    assert out.stat().st_size > 20000


def test_the_command_refuses_before_working(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        BP.main(["--swipes", "1"])
    assert e.value.code == 2
    with pytest.raises(SystemExit):
        BP.main(["--sources", "pink,velvet"])
    assert "velvet" in capsys.readouterr().err
    assert BP.main(["--quick", "--json", str(tmp_path / "no" / "r.json")]) == 1
    assert "no such directory" in capsys.readouterr().err
