"""Helpers for the Blender tests: enabling the add-on and building small scenes.

Imported by the test modules (a plain module, so its name cannot clash with tests/conftest.py).
bpy is imported inside the functions: the conftest sets Blender's user folders first.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
ADDON_NAME = "thinburn_addon"


def enable_legacy():
    import addon_utils

    def fail(exc):
        raise exc

    addon_utils.enable(ADDON_NAME, default_set=True, handle_error=fail)
    return sys.modules[ADDON_NAME]


def disable_legacy():
    import addon_utils
    addon_utils.disable(ADDON_NAME, default_set=True)



# --- scene builders ---------------------------------------------------------------------------
def make_sheet(name="Sheet", n=9, size=0.2, z=0.5, location=(0.0, 0.0, 0.0)):
    """An n×n-vertex grid of side `size` m in a horizontal plane at height z."""
    import bpy
    xs = np.linspace(-size / 2, size / 2, n)
    verts = [(x, y, z) for y in xs for x in xs]
    faces = [(j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i)
             for j in range(n - 1) for i in range(n - 1)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    return obj


def make_igniter(sheet, location, lit_from=1, radius=0.03, name="Igniter", key_frames=None):
    """An Empty in the sheet's igniter collection, unlit before `lit_from` and lit from it on."""
    import bpy
    coll = sheet.thinburn.igniter_collection
    if coll is None:
        coll = bpy.data.collections.new("Igniters")
        bpy.context.scene.collection.children.link(coll)
        sheet.thinburn.igniter_collection = coll
    empty = bpy.data.objects.new(name, None)
    coll.objects.link(empty)
    empty.location = location
    empty.thinburn_igniter.radius = radius
    if lit_from > bpy.context.scene.frame_start:
        empty.thinburn_igniter.strength = 0.0
        empty.keyframe_insert("thinburn_igniter.strength", frame=lit_from - 1)
    empty.thinburn_igniter.strength = 1.0
    empty.keyframe_insert("thinburn_igniter.strength", frame=lit_from)
    return empty


def make_table(top=0.75):
    """A 1 m cube scaled to a table whose top face is at z = top (its origin at its centre)."""
    import bpy
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.0, 0.0, top - 0.05))
    table = bpy.context.active_object
    table.scale = (1.0, 1.0, 0.1)
    bpy.context.view_layer.update()
    return table


def setup_bake(sheet, frames=24, cells=32, cache_dir=None, floor=True):
    """Bake settings for a test: one core thread (results do not depend on it; the test
    machine is small) and, by default, a floor at the sheet's lowest point so that it lies
    still until it burns (without one it falls away from the igniters)."""
    s = sheet.thinburn
    s.enabled = True
    s.cells = cells
    s.frame_start = 1
    s.frame_end = frames
    s.threads = 1
    if floor:
        s.floor_mode = "HEIGHT"
        s.floor_height = min((sheet.matrix_world @ v.co).z for v in sheet.data.vertices)
    if cache_dir is not None:
        s.cache_dir = str(cache_dir)
    return s


def cache_file(folder, name="Sheet.pc2"):
    """Where a bake into the Cache Folder ``folder`` writes ``name``: a folder per .blend
    ('untitled' while unsaved), so that two files never share a cache."""
    import bpy
    stem = Path(bpy.data.filepath).stem if bpy.data.filepath else "untitled"
    return Path(folder) / stem / name


def evaluated_positions(obj, frame):
    """Local vertex positions of the evaluated mesh at a frame (n, 3)."""
    import bpy
    bpy.context.scene.frame_set(frame)
    dg = bpy.context.evaluated_depsgraph_get()
    mesh = obj.evaluated_get(dg).to_mesh()
    co = np.empty(3 * len(mesh.vertices), dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    obj.evaluated_get(dg).to_mesh_clear()
    return co.reshape(-1, 3)


def evaluated_colours(obj, frame, name="thinburn_char"):
    """The evaluated mesh's colour attribute at a frame (n, 4)."""
    import bpy
    bpy.context.scene.frame_set(frame)
    dg = bpy.context.evaluated_depsgraph_get()
    attr = obj.evaluated_get(dg).data.attributes[name]
    out = np.empty(4 * len(attr.data), dtype=np.float32)
    attr.data.foreach_get("color", out)
    return out.reshape(-1, 4)


def point_attribute(obj, name):
    mesh = obj.data
    attr = mesh.attributes[name]
    values = np.empty(len(attr.data), dtype=np.float32)
    attr.data.foreach_get("value", values)
    return values


# --- the modal operator without a window ------------------------------------------------------
def modal_harness(addon, job, queue=()):
    """The modal bake operator's methods on a stand-in instance (no window in bpy-as-a-module):
    ``send(event type)`` returns what modal() returns; ``queue``: sheets to bake after ``job``."""
    import bpy
    from types import SimpleNamespace
    op_cls = addon.operators.THINBURN_OT_bake
    reports, status = [], []
    op = SimpleNamespace(_job=job, _timer=None, _status_bar=False, _queue=list(queue),
                         _count=1 + len(queue),
                         report=lambda kind, text: reports.append((kind, text)))
    op._end = lambda ctx: op_cls._end(op, ctx)
    ctx = SimpleNamespace(window_manager=bpy.context.window_manager, scene=bpy.context.scene,
                          view_layer=bpy.context.view_layer,
                          workspace=SimpleNamespace(status_text_set=status.append),
                          screen=SimpleNamespace(areas=[]))
    addon.operators._running[ctx.scene.name] = job

    def send(kind):
        return op_cls.modal(op, ctx, SimpleNamespace(type=kind, value="PRESS"))
    return send, reports, status


def worker_busy(job) -> bool:
    """The bake's worker still runs or has results not yet taken."""
    return job.worker.is_alive() or not job.worker.results.empty()


# --- curved shells (issue #11): what an artist burns besides a flat sheet ----------------------
def make_box_table(top=0.0, size=1.0, name="Table"):
    """A box (Blender's cube) whose top face is at z = top, to stand shells on."""
    import bpy
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.0, 0.0, top - 0.025))
    table = bpy.context.active_object
    table.name = name
    table.scale = (size, size, 0.05)
    bpy.context.view_layer.update()
    return table


def _loop_cut_vertical(obj, cuts):
    """Loop cuts (Ctrl+R) across a cylinder's side: every vertical edge cut ``cuts`` times."""
    import bmesh
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    edges = [e for e in bm.edges
             if abs(e.verts[0].co.z - e.verts[1].co.z) > 0.5 * (e.verts[0].co - e.verts[1].co).length]
    bmesh.ops.subdivide_edges(bm, edges=edges, cuts=cuts, use_grid_fill=True)
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()


def make_lantern(name="Lantern", radius=0.1, depth=0.3, segments=96, cuts=31, bottom=0.0):
    """A paper lantern: Blender's cylinder without caps (Cap Fill Type: Nothing), standing on
    z = bottom, its side cut into ``cuts + 1`` rings of quads (segments × (cuts + 2) vertices)."""
    import bpy
    bpy.ops.mesh.primitive_cylinder_add(vertices=segments, radius=radius, depth=depth,
                                        end_fill_type="NOTHING",
                                        location=(0.0, 0.0, bottom + depth / 2))
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    _loop_cut_vertical(obj, cuts)
    return obj


def make_uv_sphere(name="Sphere", radius=0.1, segments=64, rings=32, centre=(0.0, 0.0, 0.2)):
    import bpy
    bpy.ops.mesh.primitive_uv_sphere_add(segments=segments, ring_count=rings, radius=radius,
                                         location=centre)
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    return obj


def link_mesh(name, verts, faces):
    """A mesh object from vertices and faces, linked to the scene and made active."""
    import bpy
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    return obj


def make_rect(name="Sheet", width=0.21, height=0.297, nx=43, ny=61, z=0.0):
    """A width × height sheet of nx × ny vertices at height z, centred on the origin (A4)."""
    xs, ys = np.linspace(-width / 2, width / 2, nx), np.linspace(-height / 2, height / 2, ny)
    verts = [(x, y, z) for y in ys for x in xs]
    faces = [(j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i)
             for j in range(ny - 1) for i in range(nx - 1)]
    return link_mesh(name, verts, faces)


def make_folded(name="Letter", width=0.21, depth=0.15, fold_deg=30.0, n=41, z=0.0):
    """A sheet folded along y = 0 (a letter): the half y < 0 lies flat at height z, the half
    y > 0 rises at ``fold_deg`` degrees; n × n vertices, the fold on a row of vertices."""
    a = np.radians(fold_deg)
    xs = np.linspace(-width / 2, width / 2, n)
    ys = np.linspace(-depth, depth, n)
    verts = []
    for y in ys:
        for x in xs:
            verts.append((x, y, z) if y <= 0 else (x, y * np.cos(a), z + y * np.sin(a)))
    faces = [(j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i)
             for j in range(n - 1) for i in range(n - 1)]
    return link_mesh(name, verts, faces)


def make_stack(name="Stack", size=0.2, gap=0.004, sheets=3, n=33, z=0.0, shift=0.01):
    """Several flat square sheets a few mm apart in one object (disconnected pieces), each
    shifted by ``shift`` in x and y from the one below."""
    xs = np.linspace(-size / 2, size / 2, n)
    verts, faces = [], []
    for k in range(sheets):
        base = len(verts)
        verts += [(x + k * shift, y + k * shift, z + k * gap) for y in xs for x in xs]
        faces += [(base + j * n + i, base + j * n + i + 1, base + (j + 1) * n + i + 1,
                   base + (j + 1) * n + i) for j in range(n - 1) for i in range(n - 1)]
    return link_mesh(name, verts, faces)


def mesh_edges(obj):
    """(e, 2) vertex indices of the mesh's edges."""
    e = np.empty(2 * len(obj.data.edges), dtype=np.int32)
    obj.data.edges.foreach_get("vertices", e)
    return e.reshape(-1, 2)


def world_vertices(obj):
    n = len(obj.data.vertices)
    co = np.empty(3 * n, dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    mw = np.array(obj.matrix_world, dtype=np.float64)
    return co.reshape(n, 3).astype(np.float64) @ mw[:3, :3].T + mw[:3, 3]


def edge_strain(rest, frames, edges):
    """max |length / rest length - 1| over the edges, per frame of ``frames`` (k, n, 3)."""
    l0 = np.linalg.norm(rest[edges[:, 0]] - rest[edges[:, 1]], axis=1)
    out = []
    for pos in frames:
        l1 = np.linalg.norm(pos[edges[:, 0]] - pos[edges[:, 1]], axis=1)
        out.append(float(np.max(np.abs(l1 / l0 - 1.0))))
    return np.array(out)
