"""The burning band for Mantaflow: "ThinBurn Burn" writes ``thinburn_burning`` (1 where a
vertex is lit and not burnt out this frame) into the sheet's vertex group of that name, which
a Fluid flow's Density Vertex Group can use, and Add Mantaflow Fire makes the flow and a
domain that bakes (docs/blender.md, "Mantaflow").

The bake runs in a subprocess (mantaflow_bake.py): Mantaflow in bpy-as-a-module needs the
add-on's mend (blender_addon/mantaflow.py) and, unmended, aborts the process it runs in.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender

from blender_helpers import make_igniter, make_sheet, point_attribute, setup_bake  # noqa: E402


def _weights(obj, frame, group):
    bpy.context.scene.frame_set(frame)
    dg = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(dg)
    mesh = ev.to_mesh()
    index = obj.vertex_groups[group].index
    w = np.zeros(len(mesh.vertices), dtype=np.float32)
    for v in mesh.vertices:
        for g in v.groups:
            if g.group == index:
                w[v.index] = g.weight
    ev.to_mesh_clear()
    return w


def test_burning_band_fills_the_vertex_group_frame_by_frame(addon, tmp_path):
    sheet = make_sheet(n=17, size=0.2, z=0.0)
    settings = setup_bake(sheet, frames=40, cells=32, cache_dir=tmp_path / "cache")
    settings.crumple = False
    settings.mat_V0 = 20.0
    settings.mat_burn_duration = 0.5
    make_igniter(sheet, (-0.1, -0.1, 0.0), lit_from=1, radius=0.06)
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    group = sheet.vertex_groups.new(name="thinburn_burning")
    group.add(range(len(sheet.data.vertices)), 0.0, "REPLACE")  # weights for the nodes to set
    ignite = point_attribute(sheet, "thinburn_ignite_time")
    burnout = point_attribute(sheet, "thinburn_burnout_time")
    bands = []
    for frame in (3, 20, 40):
        band = (ignite <= frame) & (frame < burnout)
        w = _weights(sheet, frame, "thinburn_burning")
        assert band.any(), frame
        np.testing.assert_array_equal(w > 0.5, band)
        bands.append(band)
    assert not np.array_equal(bands[0], bands[2])  # the band moves on


def test_add_mantaflow_fire_bakes_flames_at_the_band_only(addon, tmp_path):
    script = Path(__file__).with_name("mantaflow_bake.py")
    run = subprocess.run([sys.executable, str(script), str(tmp_path / "cache")], cwd=script.parent,
                         capture_output=True, text=True, timeout=300, env=dict(os.environ))
    lines = [line for line in run.stdout.splitlines() if line.startswith("RESULT ")]
    assert run.returncode == 0 and lines, run.stdout[-3000:] + run.stderr[-3000:]
    out = json.loads(lines[-1][len("RESULT "):])
    # the sheet is a planar Fire flow fed by the band's vertex group, after the burn modifier
    assert out["flow"] == ["FIRE", "MESH", True, "thinburn_burning"]
    assert out["stack"] == ["ThinBurn Cache", "ThinBurn Burn", "ThinBurn Flow"]
    # the domain: the 0.2 m sheet's sweep (it lies still at z = 0) + 25 % (5 cm) on each side,
    # 100 % (0.2 m) above; the cache folder beside the ThinBurn cache
    np.testing.assert_allclose(out["domain_low"], [-0.15, -0.15, -0.05], atol=1e-6)
    np.testing.assert_allclose(out["domain_high"], [0.15, 0.15, 0.2], atol=1e-6)
    assert out["cache"] == str(tmp_path / "cache" / "untitled" / "Sheet_mantaflow")
    # bpy from PyPI: manta's grids lack their inherited methods until the operator mends them
    # (Blender itself needs no mend); once is enough
    assert out["whole_before"] is False and out["whole_after"] is True
    assert out["mended_again"] is False
    assert out["files"] == [f"fluid_data_{f:04d}.vdb" for f in range(6, 25)]
    # measured: flame 0.91 / 0.95 and smoke density 0.004 / 0.007 over the band at frames 14
    # and 24; exactly 0 over the sheet 5 cm or more from the fire
    for frame in ("14", "24"):
        at = out[frame]
        assert at["band"] > 0 and at["far"] > 100, at
        assert at["flame_band"] > 0.5 and at["density_band"] > 1e-3, at
        assert at["flame_far"] < 1e-3 and at["density_far"] < 1e-5, at
    # the flames move out with the band: their centre 4.1 -> 6.5 cm from the lit corner while the
    # band's goes 5.7 -> 6.9 cm (measured)
    assert out["24"]["flame_from_corner"] > out["14"]["flame_from_corner"] + 0.01
    for frame in ("14", "24"):
        assert abs(out[frame]["flame_from_corner"] - out[frame]["band_from_corner"]) < 0.025
    # Free took the domain, its cache folder and the flow away
    assert out["after_free"] == {"domain": False, "cache": False, "flow": False}
