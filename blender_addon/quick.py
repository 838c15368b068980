"""Quick Burn: one click from selected meshes to a baked, playing burn (like Quick Smoke).

``bpy.ops.thinburn.quick_burn()`` on the selected meshes: enables ThinBurn on each, lights it
at the surface point nearest the 3D cursor (in Edit Mode: at its selected vertices), puts a
floor under it when it lies on another object, keeps the cache beside the .blend, bakes, and
goes to the first frame (from the UI it then plays). One undo step takes it all back (the
cache files stay on disk).
"""
from __future__ import annotations

import os
import sys
import tempfile

import bpy
import mathutils
import numpy as np
from mathutils.bvhtree import BVHTree

from . import inputs, operators
from .inputs import BakeError
from .properties import build_material

QUICK_TAG = "thinburn_quick"  # custom property on the igniters Quick Burn made
MAX_POINTS = 32               # igniters from selected vertices, at most (evenly picked)
LIES_ON = 0.01                # m: a sheet this close above an object's top lies on it


def igniter_collection_name(obj) -> str:
    return f"ThinBurn Igniters {obj.name}"


def _world_vertices(obj) -> np.ndarray:
    co = np.empty(3 * len(obj.data.vertices), dtype=np.float64)
    obj.data.vertices.foreach_get("co", co)
    mw = np.array(obj.matrix_world, dtype=np.float64)
    return co.reshape(-1, 3) @ mw[:3, :3].T + mw[:3, 3]


def nearest_surface_point(obj, point) -> np.ndarray:
    """The point of the mesh's surface (its faces, world space) nearest ``point``."""
    world = _world_vertices(obj)
    polygons = [tuple(p.vertices) for p in obj.data.polygons]
    tree = BVHTree.FromPolygons([tuple(v) for v in world], polygons)
    location = tree.find_nearest(mathutils.Vector(point))[0]
    return np.array(location, dtype=np.float64)


def ignition_points(obj, cursor, selected_only: bool) -> list:
    """Where Quick Burn lights the sheet: its selected vertices (Edit Mode, when any are
    selected; at most MAX_POINTS, evenly picked), else the surface point nearest the cursor."""
    if selected_only:
        mask = np.zeros(len(obj.data.vertices), dtype=bool)
        obj.data.vertices.foreach_get("select", mask)
        index = np.flatnonzero(mask)
        if len(index):
            if len(index) > MAX_POINTS:
                index = index[np.linspace(0, len(index) - 1, MAX_POINTS).round().astype(int)]
            return list(_world_vertices(obj)[index])
    return [nearest_surface_point(obj, cursor)]


def support_under(obj, scene, exclude) -> object:
    """The object the sheet lies on, or None: a visible mesh, not one of ``exclude``, whose
    top (its bounding box's highest Z, as Floor = Object reads it) is at most LIES_ON below
    the sheet's lowest point and whose footprint overlaps the sheet's."""
    world = _world_vertices(obj)
    low = float(world[:, 2].min())
    lo_xy, hi_xy = world[:, :2].min(axis=0), world[:, :2].max(axis=0)
    best, best_top = None, -np.inf
    for other in scene.objects:
        if other.type != "MESH" or other.name in exclude or not other.visible_get():
            continue
        if other.name.startswith("ThinBurn "):  # the bake's own fire, embers and ash
            continue
        m = other.matrix_world
        corners = np.array([tuple(m @ mathutils.Vector(c)) for c in other.bound_box])
        if np.any(corners[:, :2].max(axis=0) < lo_xy) or np.any(corners[:, :2].min(axis=0) > hi_xy):
            continue
        top = inputs.object_top(other)
        if -1e-6 <= low - top <= LIES_ON and top > best_top:
            best, best_top = other, top
    return best


def _igniter_radius(obj, settings) -> float:
    """A few cells wide, and at least the igniter's default 2 cm."""
    world, tris, _ = inputs.sheet_geometry(obj)
    return max(0.02, 1.5 * inputs.cell_spacing(world, tris, settings.cells))


def _igniters(obj, points, frame) -> list:
    """Empties lit from ``frame`` (Strength keyframed to 1) in the sheet's Igniters collection
    (made, and linked to the scene, when it has none). Quick Burn's earlier igniters of this
    sheet go: running it again moves the fire to the new point."""
    settings = obj.thinburn
    coll = settings.igniter_collection
    if coll is None:
        coll = bpy.data.collections.new(igniter_collection_name(obj))
        bpy.context.scene.collection.children.link(coll)
        settings.igniter_collection = coll
    for old in [o for o in coll.objects if o.get(QUICK_TAG)]:
        bpy.data.objects.remove(old)
    radius = _igniter_radius(obj, settings)
    made = []
    for k, point in enumerate(points):
        empty = bpy.data.objects.new(f"ThinBurn Igniter {obj.name}" + (f" {k + 1}" if k else ""),
                                     None)
        empty[QUICK_TAG] = True
        empty.empty_display_type = "SPHERE"
        empty.empty_display_size = radius
        empty.location = tuple(point)
        coll.objects.link(empty)
        empty.thinburn_igniter.radius = radius
        empty.thinburn_igniter.strength = 1.0
        empty.keyframe_insert("thinburn_igniter.strength", frame=frame)
        made.append(empty)
    return made


def _cache_folder(settings) -> str:
    """'//thinburn_cache/' beside a saved .blend (unless the sheet has a folder of its own);
    for an unsaved file, Blender's temporary folder (the report says so)."""
    raw = settings.cache_dir.strip()
    if bpy.data.filepath:
        if not raw:
            settings.cache_dir = "//thinburn_cache/"
        return ""
    if not raw or raw.startswith("//"):
        folder = os.path.join(bpy.app.tempdir or tempfile.gettempdir(), "thinburn_cache")
        settings.cache_dir = folder + os.sep
        return folder
    return ""


def _range_is_default(settings) -> bool:
    props = type(settings).bl_rna.properties
    return (settings.frame_start == props["frame_start"].default and
            settings.frame_end == props["frame_end"].default)


def _take_scene_range(obj, settings, scene):
    """The bake takes the scene's frame range when the sheet has none of its own: it was not
    enabled yet, or its Start and End are still their defaults (an artist who ticked the
    ThinBurn box first, as docs/blender.md's steps say, then set the scene to 1-150, was baked
    1-250 without a word). A range the artist set on the sheet is kept, and the report says so
    where it differs from the scene's."""
    own = (settings.frame_start, settings.frame_end)
    wanted = (scene.frame_start, scene.frame_end)
    if own == wanted:
        return None
    if not settings.enabled or _range_is_default(settings):
        settings.frame_start, settings.frame_end = wanted
        return None
    return (f"'{obj.name}' bakes its own frames {own[0]}–{own[1]}, not the scene's {wanted[0]}–"
            f"{wanted[1]} (Physics > ThinBurn > Start, End)")


def setup(context, obj, points, scene_range: bool, exclude) -> list:
    """Quick Burn's settings on one sheet; returns notes for the report."""
    settings = obj.thinburn
    notes = []
    scene = context.scene
    if scene_range:
        note = _take_scene_range(obj, settings, scene)
        if note:
            notes.append(note)
    settings.enabled = True
    _igniters(obj, points, settings.frame_start)
    if settings.floor_mode == "NONE":
        table = support_under(obj, scene, exclude)
        if table is not None:
            settings.floor_mode, settings.floor_object = "OBJECT", table
            notes.append(f"'{obj.name}' lies on '{table.name}': it is the floor")
    slow = slow_fire_note(obj, settings, scene)
    if slow:
        notes.append(slow)
    temp = _cache_folder(settings)
    if temp:
        notes.append(f"the file is not saved, so '{obj.name}' baked into {temp}: save the file "
                     "and bake again to keep the cache beside it")
    return notes


def slow_fire_note(obj, settings, scene):
    """A note when the fire, at the material's own speed, reaches less than a quarter of the
    sheet's size from Start to End (no Burn Duration): in the artists' trial, paper at its 3.5 mm/s
    lit 71 of an A4 sheet's 3721 vertices in a 5 s shot, and nothing said why."""
    if settings.burn_duration > 0:
        return None
    seconds = (settings.frame_end - settings.frame_start) * scene.render.fps_base / scene.render.fps
    speed = build_material(settings).V0  # mm/s
    reach = 1e-3 * speed * seconds
    # Its longest side (an artist's 50 cm cloth was "71 cm across" by its box's diagonal).
    size = float(np.max(np.ptp(_world_vertices(obj), axis=0)))
    if not (reach < 0.25 * size):
        return None
    return (f"'{obj.name}': at its Spread Speed ({speed:g} mm/s) the fire spreads about "
            f"{100 * reach:.1f} cm in the {seconds:.1f} s from Start to End, on a sheet "
            f"{100 * size:.0f} cm across: set Burn Duration (Physics > ThinBurn) to burn it "
            "within the shot, or raise Spread Speed (Physics > ThinBurn > Advanced)")


class THINBURN_OT_quick_burn(bpy.types.Operator):
    """Set the selected meshes on fire: enable ThinBurn, light each at the point nearest the 3D
    cursor (or at the selected vertices in Edit Mode), floor them on what they lie on, bake"""

    bl_idname = "thinburn.quick_burn"
    bl_label = "Quick Burn"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return (operators.running_job(context.scene) is None
                and any(o.type == "MESH" for o in _selection(context)))

    def execute(self, context):
        sheets = [o for o in _selection(context) if o.type == "MESH"]
        edit = context.mode == "EDIT_MESH"
        if edit:
            bpy.ops.object.mode_set(mode="OBJECT")  # writes the edit mesh back, selection too
        cursor = tuple(context.scene.cursor.location)
        names = {o.name for o in sheets}
        baked = 0
        for obj in sheets:
            if len(obj.data.polygons) == 0:
                self.report({"WARNING"}, f"ThinBurn: skipped '{obj.name}': it has no faces")
                continue
            points = ignition_points(obj, cursor, selected_only=edit)
            for note in setup(context, obj, points, scene_range=True, exclude=names):
                self.report({"INFO"}, f"ThinBurn: {note}")
            wm = context.window_manager
            wm.progress_begin(0, 1000)  # the mouse cursor counts while the window waits
            try:
                job = operators.bake_now(context, obj,
                                         stream=sys.stderr if bpy.app.background else None,
                                         on_frame=lambda j: wm.progress_update(int(1000 * j.progress)))
            except BakeError as exc:
                self.report({"ERROR"}, f"ThinBurn: {exc}")
                continue
            finally:
                wm.progress_end()
            operators.report_bake(self, job)
            baked += 1
        if not baked:
            return {"FINISHED"}  # the setup stays, and one undo takes it back
        scene = context.scene
        scene.frame_set(min(o.thinburn.frame_start for o in sheets if o.thinburn.enabled))
        screen = getattr(context, "screen", None)
        if not bpy.app.background and screen is not None and not screen.is_animation_playing:
            bpy.ops.screen.animation_play()
        return {"FINISHED"}


def _selection(context):
    objects = getattr(context, "selected_objects", None)
    if objects is None:
        objects = [o for o in context.scene.objects if o.select_get()]
    return objects


def _menu(self, context):
    self.layout.operator(THINBURN_OT_quick_burn.bl_idname, icon="LIGHT_SUN")


CLASSES = (THINBURN_OT_quick_burn,)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.VIEW3D_MT_object_quick_effects.append(_menu)


def unregister():
    bpy.types.VIEW3D_MT_object_quick_effects.remove(_menu)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
