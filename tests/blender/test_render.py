"""A Cycles render (CPU, 4 samples, 160×120) shows char where the sheet burnt.

The rendered pictures are kept under pytest's tmp_path (printed on failure) to look at.
"""
from __future__ import annotations

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender

from blender_helpers import make_igniter, make_sheet, point_attribute, setup_bake  # noqa: E402

LIT_FROM = 2
BURN_S = 2.0  # burn duration: long enough that the render frame shows char, not holes


def _render(path, frame):
    scene = bpy.context.scene
    scene.frame_set(frame)
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(str(path))
    w, h = img.size
    px = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    rgb = px.reshape(h, w, 4)[::-1, :, :3]  # Blender stores rows bottom-up
    return rgb @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)


def _camera_and_light(size):
    scene = bpy.context.scene
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.data.type = "ORTHO"
    cam.data.ortho_scale = size
    cam.location = (0.0, 0.0, 2.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 3.0
    scene.collection.objects.link(sun)
    world = bpy.data.worlds.new("World")
    scene.world = world
    world.color = (0.05, 0.05, 0.05)
    if world.node_tree is not None:
        bg = world.node_tree.nodes.get("Background")
        if bg is not None:
            bg.inputs["Color"].default_value = (0.05, 0.05, 0.05, 1.0)
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = 160, 120, 100
    r.image_settings.file_format = "PNG"
    scene.view_settings.view_transform = "Standard"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 4
    scene.cycles.use_denoising = False


def test_cycles_render_shows_char(addon, tmp_path):
    size = 0.2
    sheet = make_sheet(n=17, size=size, z=0.0)
    settings = setup_bake(sheet, frames=40, cells=32, cache_dir=tmp_path / "cache")
    settings.mat_burn_duration = BURN_S
    settings.mat_duration_noise = 0.0
    settings.crumple = False  # this test is about the shading: keep the sheet in the camera
    make_igniter(sheet, (0.0, 0.0, 0.0), lit_from=LIT_FROM, radius=0.05)
    assert bpy.ops.thinburn.bake() == {"FINISHED"}
    _camera_and_light(size)
    fps = bpy.context.scene.render.fps
    ignite = point_attribute(sheet, "thinburn_ignite_time")
    first = float(ignite.min())
    # Half-way through the centre's burn: well charred, before the ember edge and the holes.
    frame = int(round(first + 0.5 * BURN_S * fps))
    assert frame <= 40
    clean = _render(tmp_path / "unburnt.png", LIT_FROM - 1)
    burnt = _render(tmp_path / "burnt.png", frame)
    centre = (slice(50, 70), slice(70, 90))   # inside the lit disc (radius 0.05 m = 40 px)
    corner = (slice(5, 20), slice(5, 25))     # far from it: never lit
    assert clean[centre].mean() > 0.3, "the unburnt sheet should render light"
    assert burnt[centre].mean() < 0.6 * clean[centre].mean(), (tmp_path, burnt[centre].mean())
    assert abs(burnt[corner].mean() - clean[corner].mean()) < 0.1 * clean[corner].mean()
