"""examples/post_tensioned_pier.py: the rocking pier free-standing and post-tensioned, its table and its plot.

The verdicts asserted are far from their decision boundaries (the uplift thresholds 0.200 / 0.302 / 0.506 g
against pulses of 0.45 and 0.9 g; peaks of 0.05-0.08 rad against a bound of 0.15 rad, 8 times alpha's
distance to overturning), and they hold with the record's scale moved by a few ulps (round-off).
"""
from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("_post_tensioned_pier", ROOT / "examples" / "post_tensioned_pier.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("scale", [2.0, float(np.nextafter(np.nextafter(2.0, 3.0), 3.0))], ids=["nominal", "ulps"])
def test_the_tendon_keeps_the_pier_standing_and_recentres_it(example, scale, tmp_path, capsys):
    """The free-standing pier overturns under the long 1 Hz pulse and the record x 2; both post-tensioned piers
    stand, rock less than 0.15 rad and end at rest upright; the 300 kN pier does not even uplift under the
    0.45 g pulse (its threshold is 0.506 g); the tendon force never drops below P0 (no slide, no slack), and the
    printed table and the plot come from the same runs."""
    out = tmp_path / "pier.png"
    res = example.run(30.0, out, scale=scale)
    table = res["table"]
    assert table[("free-standing", "pulse 0.45 g, 1 Hz")]["overturned"]
    assert table[("free-standing", "record")]["overturned"]
    for pier in ("P0 = 100 kN", "P0 = 300 kN"):
        P0 = example.PIERS[pier]["P0"]
        for motion in ("record", "pulse 0.45 g, 1 Hz", "pulse 0.9 g, 2.5 Hz"):
            s = table[(pier, motion)]
            assert not s["overturned"] and s["peak_phi"] < 0.15, (pier, motion, s)
            assert s["max_tendon_force"] >= P0
        rec = res["record"][pier]
        assert rec.phi[-1] == 0.0 and np.all(rec.tendon_force >= P0 * (1 - 1e-12))
    quiet = table[("P0 = 300 kN", "pulse 0.45 g, 1 Hz")]
    assert quiet["peak_phi"] == 0.0 and quiet["impacts"] == 0 and quiet["max_tendon_force"] == 300e3
    assert out.stat().st_size > 10_000
    printed = capsys.readouterr().out
    for (pier, motion), s in table.items():
        line = next(ln for ln in printed.splitlines() if ln.startswith(f"{pier:15s} {motion:22s}"))
        assert f"{s['peak_phi']:9.4f}" in line and f"{s['impacts']:8d}" in line
    m = example.PostTensionedBlock(**example.PIER)
    assert f"{math.tan(m.alpha) * (1 + 300e3 / (20e3 * m.g)):10.3f}".strip() == "0.506"


def test_the_docs_table_is_the_example_s(example):
    """The models page's table of the example (docs/guide/models.md: uplift thresholds, peak rotations to two significant digits,
    overturning) is what the example computes."""
    res = example.run(30.0, None)["table"]
    text = (ROOT / "docs" / "guide" / "models.md").read_text(encoding="utf-8")
    rows = [ln for ln in text.split("| pier | uplift threshold |", 1)[1].splitlines()[2:5]]
    m = example.PostTensionedBlock(**example.PIER)

    def cell(s):
        if s["overturned"]:
            return "overturns"
        if s["peak_phi"] == 0.0:
            return "0 (no uplift)"
        peak = float(f"{s['peak_phi']:.2g}")
        return f"{peak:g} rad"

    for row, pier in zip(rows, example.PIERS):
        uplift = math.tan(m.alpha) * (1.0 + example.PIERS[pier]["P0"] / (example.PIER["m"] * m.g))
        expected = (f"| {pier} | {uplift:.3f} g | {cell(res[(pier, 'record')])} | "
                    f"{cell(res[(pier, 'pulse 0.45 g, 1 Hz')])} |")
        assert row == expected
