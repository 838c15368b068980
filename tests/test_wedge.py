"""Wedges (thinburn.wedge) on Dask and in a plain loop, and the scene file format."""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

from thinburn import scenefile, wedge
from thinburn.__main__ import main

TINY = ["--scene", "paper", "--vertices", "120", "--cells", "12", "--frames", "5",
        "--render-frames", "0,4"]


def test_params_parse_and_combine():
    assert wedge.parse_param("crumple_gain=0.1,0.3,1") == ("crumple_gain", [0.1, 0.3, 1.0])
    assert wedge.parse_param("cells=16,32") == ("cells", [16, 32])
    with pytest.raises(ValueError, match="'crumple_gian'.*unknown"):
        wedge.parse_param("crumple_gian=1")
    with pytest.raises(ValueError, match="v0: 'fast' is not a number"):
        wedge.parse_param("v0=0.003,fast")
    with pytest.raises(ValueError, match="cells: '16.5' is not an integer"):
        wedge.parse_param("cells=16.5")
    with pytest.raises(ValueError, match="NAME=VALUE"):
        wedge.parse_param("v0")
    combos = wedge.combinations([("a", [1, 2]), ("b", [3, 4, 5])])
    assert len(combos) == 6 and combos[0] == {"a": 1, "b": 3} and combos[-1] == {"a": 2, "b": 5}
    with pytest.raises(ValueError, match="twice"):
        wedge.combinations([("a", [1]), ("a", [2])])
    assert wedge.wedge_name({"v0": 0.01, "crumple_gain": 0.3}) == wedge.wedge_name({"crumple_gain": 0.3, "v0": 0.01})


def test_v0_and_material_fields_reach_the_simulation():
    spec = scenefile.demo_scene("paper", cells=8, frames=2, vertices=30)
    sim, mat, fps, frames = wedge.simulation_for(spec, {"v0": 0.01, "Cp": 0.5, "frames": 3,
                                                        "crumple_gain": 0.25})
    assert mat.V0 == pytest.approx(10.0) and mat.Cp == 0.5 and frames == 3 and fps == 24.0
    assert sim.params.dynamics["crumple_gain"] == pytest.approx(0.25)
    assert sim.threads == 1


@pytest.mark.parametrize("ext", ["json", "npz"])
def test_scene_file_round_trip(tmp_path, ext):
    spec = scenefile.demo_scene("cloth", cells=16, frames=7, vertices=50)
    spec.material = {"preset": "cloth", "V0": 5.0}
    spec.wind = [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    path = scenefile.save_scene(spec, tmp_path / f"scene.{ext}")
    back = scenefile.load_scene(path)
    np.testing.assert_array_equal(back.vertices, spec.vertices)
    np.testing.assert_array_equal(back.faces, spec.faces)
    assert back.to_dict() == spec.to_dict()
    assert back.resolved_material().V0 == 5.0 and back.resolved_material().name == "cloth"
    assert back.wind_at(0) == (0.0, 0.0, 0.0) and back.wind_at(9) == (0.0, 1.0, 0.0)


def test_scene_file_errors_name_the_field(tmp_path):
    good = scenefile.demo_scene("paper", vertices=30).to_dict()
    with pytest.raises(ValueError, match="not a thinburn scene"):
        scenefile.from_dict({"vertices": []})
    for change, match in (({"settings": {"cels": 3}}, "unknown settings.*cels"),
                          ({"material": {"preset": "paper", "v00": 1}}, "material: unknown fields"),
                          ({"igniters": [{"time": 1}]}, r"igniters\[0\]"),
                          ({"faces": [[0, 1, 99999]]}, "faces")):
        with pytest.raises(ValueError, match=match):
            scenefile.from_dict({**good, **change})
    with pytest.raises(ValueError, match=r"\.json or \.npz"):
        scenefile.load_scene(tmp_path / "scene.txt")


def test_scene_file_igniter_times_follow_the_frames(tmp_path, capsys):
    """An igniter at t = 0.1 s lights nothing before frame 3 (24 fps) and the sheet after it."""
    spec = scenefile.demo_scene("paper", cells=12, frames=6, vertices=60)
    spec.igniters = [{"point": spec.igniters[0]["point"], "time": 0.1, "radius": 0.02}]
    spec.shell = False
    path = scenefile.save_scene(spec, tmp_path / "scene.json")
    out = tmp_path / "w"
    rc = main(["wedge", "--scene", str(path), "--workers", "0", "--out", str(out),
               "--param", "seed=0", "--render-frames", "5"])
    assert rc == 0
    with np.load(out / "seed-0" / "frames.npz") as d:
        char = d["vertex_char"]
        ign = d["vertex_ignition_times"]
    assert np.all(char[:3] == 0) and np.any(char[5] > 0)
    assert 0.1 - 1e-9 <= ign[np.isfinite(ign)].min() < 0.2


def test_wedge_usd_and_the_usd_command(tmp_path, capsys):
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom
    out = tmp_path / "w"
    assert main(["wedge", *TINY, "--out", str(out), "--param", "seed=3", "--workers", "0", "--usd"]) == 0
    folder = out / "seed-3"
    assert (folder / "bake.usda").exists()
    assert main(["usd", str(folder), "--out", str(tmp_path / "again.usdc")]) == 0
    stage = Usd.Stage.Open(str(tmp_path / "again.usdc"))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/ThinBurn/Sheet"))
    with np.load(folder / "frames.npz") as d:
        np.testing.assert_array_equal(np.array(mesh.GetPointsAttr().Get(Usd.TimeCode(4))),
                                      d["vertex_positions"][4])
    assert main(["usd", str(tmp_path / "nothing")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_wedges_on_a_local_cluster_failures_reruns_and_a_scheduler(tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    out = tmp_path / "wedges"
    args = ["wedge", *TINY, "--out", str(out), "--param", "v_floor=0.05,2", "--param",
            "crumple_gain=0.5"]
    # One wedge has a bad value: it fails, the other finishes (2 worker processes).
    assert main(args + ["--workers", "2"]) == 1
    err = capsys.readouterr().err
    assert "FAILED" in err and "v_floor must be <= 1.0" in err
    good, bad = out / "crumple_gain-0.5__v_floor-0.05", out / "crumple_gain-0.5__v_floor-2"
    for name in ("frames.npz", "summary.json", "frames.png", "DONE"):
        assert (good / name).exists(), name
    assert not (bad / "DONE").exists() and "v_floor" in (bad / "error.txt").read_text()
    summary = json.loads((good / "summary.json").read_text())
    assert summary["frames"] == 5 and summary["values"] == {"v_floor": 0.05, "crumple_gain": 0.5}
    index = json.loads((out / "wedges.json").read_text())
    assert [w["status"] for w in index["wedges"]] == ["done", "failed"]
    from PIL import Image
    with Image.open(out / "contact_sheet.png") as sheet, Image.open(good / "frames.png") as strip:
        assert sheet.height >= 2 * strip.height and sheet.width > strip.width
    with np.load(good / "frames.npz") as d:
        dask_positions = d["vertex_positions"].copy()
    assert dask_positions.shape[0] == 5

    # Re-run on an existing scheduler, adding a value: the done wedge is skipped, the new one
    # runs, the bad one fails again.
    done_mtime = os.path.getmtime(good / "DONE")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        rc = main(["wedge", *TINY, "--out", str(out), "--param", "v_floor=0.05,2,0.1", "--param",
                   "crumple_gain=0.5", "--scheduler", cluster.scheduler_address])
    assert rc == 1
    err = capsys.readouterr().err
    assert f"skip {good.name}" in err and "1 baked, 1 skipped" in err
    assert os.path.getmtime(good / "DONE") == done_mtime
    assert (out / "crumple_gain-0.5__v_floor-0.1" / "DONE").exists()

    # The same wedge in a plain loop gives the same frames, bit for bit.
    loop = tmp_path / "loop"
    assert main(["wedge", *TINY, "--out", str(loop), "--param", "v_floor=0.05", "--param",
                 "crumple_gain=0.5", "--workers", "0"]) == 0
    with np.load(loop / good.name / "frames.npz") as d:
        np.testing.assert_array_equal(d["vertex_positions"], dask_positions)


def test_wedge_cli_errors(capsys):
    assert main(["wedge", "--scene", "no_such_scene"]) == 2
    assert "--scene 'no_such_scene'" in capsys.readouterr().err
    assert main(["wedge", "--param", "nope=1"]) == 2
    assert "'nope': unknown parameter" in capsys.readouterr().err
    assert main(["wedge", "--render-frames", "a,b"]) == 2
    assert "--render-frames" in capsys.readouterr().err
