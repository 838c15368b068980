"""The burning band for Mantaflow: "ThinBurn Burn" writes ``thinburn_burning`` (1 where a
vertex is lit and not burnt out this frame) into the sheet's vertex group of that name, which
a Fluid flow's Density Vertex Group can use (docs/blender.md).

Mantaflow itself is not run here: in bpy-as-a-module its solver fails ("'LevelsetGrid' object
has no attribute 'setConst'", as reported for Blender 4.2+ headless, e.g.
princeton-vl/infinigen#318) and aborts the whole process.
"""
from __future__ import annotations

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
