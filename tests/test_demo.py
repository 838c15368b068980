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


# --- curved shells (issue #11): python -m thinburn demo --scene lantern|sphere|letter ----------

import pytest  # noqa: E402

import thinburn  # noqa: E402
from thinburn import _surface_shapes as S  # noqa: E402
from thinburn.demo import SHELL_SCENES, build, default_scene, shell_scene  # noqa: E402


@pytest.mark.parametrize("name", SHELL_SCENES)
def test_a_shell_scene_burns_on_its_surface_and_writes_frames(tmp_path, name):
    summary = run_demo(tmp_path, cells=24, max_time=3.0, frames=3, quiet=True, scene=name)
    assert summary["geometry"] == "surface" and summary["frames_written"] >= 3
    frames = sorted((tmp_path / "frames").glob("frame_*.png"))
    assert len(frames) == summary["frames_written"] and (tmp_path / "burn.gif").is_file()
    with np.load(tmp_path / "frames.npz") as f:
        # Per-cell arrays on a surface: one row of num_cells per frame; lattice (couples, 2, 3).
        assert f["cell_states"].shape == (summary["frames_written"], summary["num_cells"])
        assert f["lattice_positions"].shape[1:] == (summary["lattice_couples"], 2, 3)
        assert np.any(f["cell_states"][-1] == 1)  # lit and burning at the end of 3 s
    from PIL import Image

    img = np.asarray(Image.open(frames[-1]).convert("RGB")).astype(int)
    # Two 3-D views side by side: each half shows the shell (not just background and table),
    # and the lit half shows the glowing edge (orange: red well above blue).
    h, w, _ = img.shape
    for half in (img[:, : w // 2], img[:, w // 2:]):
        paper = np.all(half > 200, axis=2) & (half.max(axis=2) - half.min(axis=2) < 40)
        assert paper.mean() > 0.01
    glow = (img[..., 0] > 180) & (img[..., 0] - img[..., 2] > 120)
    assert glow[:, : w // 2].sum() > 10


def test_the_default_scenes_stay_flat_on_the_grid():
    for material in ("paper", "cloth", "curtain"):
        sim = build(default_scene(material), material, cells=16)
        assert sim.geometry == "plane" and sim.cell_states().shape == (16, 16)


def _lantern_far_side(cells, seed, shell):
    """(ignition time of the vertex opposite the lit point, all vertex ignition times, bound)
    for the demo's lantern burnt with the paper preset's V0 and speed noise."""
    scene = shell_scene("lantern")
    v = scene.vertices
    far = np.argmin(np.linalg.norm(v - np.array([-0.1, 0.0, 0.15]), axis=1))
    sim = thinburn.Simulation(v, scene.faces, cells=cells, seed=seed, floor=scene.floor, shell=shell)
    sim.ignite(scene.ignite_at, time=0.0, radius=scene.ignite_radius)
    sim.run(115.0, dt=0.5)
    t = sim.vertex_ignition_times()
    return t[far], t, np.pi * 0.1 / sim.params.v0


@pytest.mark.parametrize("shell, seeds", [(False, range(4)), (True, [0])])
def test_the_lantern_far_side_catches_last_at_half_its_girth_over_v0(shell, seeds):
    # Issue #11: the vertex diametrically opposite the lit point is pi r = 31.4 cm away over the
    # surface, due at pi r / V0 = 89.8 s at the paper's 3.5 mm/s (it caught at 34-42 s through
    # the old planar projection). With the preset's +-15 % speed noise, at 32 cells (dt 0.5 s),
    # measured: fire alone (shell=False), seeds 0-5: 0.931-1.000 x pi r / V0, later than
    # 91.0-95.7 % of the vertices (only the far top and bottom rims, hypot(pi r, h/2) = 34.8 cm
    # away, come later: max 96-99 s); with the crumpling shell, seeds 0-3: 0.967-1.001 x,
    # later than 92.7-95.6 % (the test allows 10 % and 85 %: the noise moves the far side by up
    # to 7 %). At the demo's 128 cells and 1/24 s steps the lantern stays standing and its far
    # side caught at 0.97 x, later than 95.2 % (README, Shells).
    for seed in seeds:
        t_far, t, due = _lantern_far_side(32, seed, shell)
        assert abs(t_far / due - 1.0) < 0.10
        assert np.isfinite(t).all()
        assert np.mean(t < t_far) > 0.85
