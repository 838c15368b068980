"""The demo driver (python -m thinburn demo) on a small, short burn."""
from __future__ import annotations

import json
import re

import numpy as np

from thinburn.demo import run_demo


def progress_counts(err: str):
    """(done, total) of every progress line the demo printed."""
    return [(int(a), int(b)) for a, b in re.findall(r"burning paper \[.*?\]\s+[\d.]+%\s+(\d+)/(\d+)", err)]


def test_demo_writes_its_outputs_and_the_bar_ends_full(tmp_path, capsys):
    # max_time far below the burn's length: the run stops at the cap while the sheet still
    # burns, before the estimated end; the bar must still end full (total/total).
    summary = run_demo(tmp_path, material="paper", cells=32, max_time=3.0, frames=4)
    for name in ("burn.gif", "frames.npz", "summary.json"):
        assert (tmp_path / name).is_file()
    assert len(list((tmp_path / "frames").glob("frame_*.png"))) >= 4
    assert json.loads((tmp_path / "summary.json").read_text()) == json.loads(json.dumps(summary))
    with np.load(tmp_path / "frames.npz") as f:
        assert np.all(np.diff(f["time"]) > 0) and f["time"][-1] <= 3.0 + 1 / 24 + 1e-9
    counts = progress_counts(capsys.readouterr().err)
    assert counts and counts[-1][0] == counts[-1][1]
    assert all(done <= total for done, total in counts)


def test_demo_bar_counts_on_to_the_cap_when_the_fire_outlasts_its_estimate(tmp_path, capsys, monkeypatch):
    # The estimate comes from a cheap fire-only probe; make it far too short, as a curled sheet
    # that slows its own fire makes it. The bar must then count on to the time cap, never
    # showing more done than its total, and end full.
    import thinburn.demo as demo
    monkeypatch.setattr(demo, "_expected_duration", lambda scene, material, max_time: 0.5)
    run_demo(tmp_path, material="paper", cells=32, max_time=2.0, frames=4)
    counts = progress_counts(capsys.readouterr().err)
    assert all(done <= total for done, total in counts)
    assert counts[-1] == (48, 48)  # 2 s at 24 frames/s: the cap's step count
    assert counts[0][1] == 12  # the first estimate: 0.5 s
