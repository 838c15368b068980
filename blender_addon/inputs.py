"""Reading a bake's inputs from the scene. Main thread only (this is where bpy is touched)."""
from __future__ import annotations

import math
import os
from dataclasses import dataclass

import bpy
import mathutils
import numpy as np

from thinburn import force_fields as fields
from thinburn.force_fields import FieldSpec
from .properties import DYNAMIC_PARAMS, MODEL_PARAMS


class BakeError(Exception):
    """A setting that stops the bake; its text is what the artist sees."""


@dataclass
class FrameSample:
    """What the scene says at one frame: each igniter's (world position, strength, radius),
    the force fields, the motion parameters and the sheet's world matrix."""

    frame: int
    igniters: list
    fields: list    # fields.FieldSpec, world space
    wind_scale: float
    dynamics: dict  # the keyframeable motion parameters and the scene's gravity (world)
    matrix: np.ndarray  # the sheet's matrix_world (4, 4)
    surfaces: list = None  # each lit mesh igniter's (world surface points (k, 3), radius)
    flames: list = None    # each lit Flame igniter's (world position (3,), flame width m)

    def wind_at(self, points) -> np.ndarray:
        """(n, 3) wind in m/s at world points: the fields times the sheet's Wind Scale."""
        return fields.wind_at(self.fields, points, self.frame) * self.wind_scale


def sheet_geometry(obj):
    """(world vertices (n, 3), triangles (m, 3), world matrix (4, 4)) of the original mesh."""
    mesh = obj.data
    n = len(mesh.vertices)
    mesh.calc_loop_triangles()
    m = len(mesh.loop_triangles)
    if n < 3 or m == 0:
        raise BakeError(f"'{obj.name}' has no faces: ThinBurn burns a sheet made of faces "
                        f"({n} vertices, {m} triangles)")
    co = np.empty(3 * n, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    tris = np.empty(3 * m, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    mw = np.array(obj.matrix_world, dtype=np.float64)
    world = co.reshape(n, 3).astype(np.float64) @ mw[:3, :3].T + mw[:3, 3]
    return world, tris.reshape(m, 3), mw


def cell_spacing(world: np.ndarray, tris: np.ndarray, cells: int) -> float:
    """About the distance between the core's fire cells, m, before the core says (it reports
    its own, ``Simulation.cell_spacing``): a curved shell's surface carries about cells² cells,
    so sqrt(area) / cells; a flat sheet's grid spans its bounding box, which is no smaller."""
    a, b, c = (world[tris[:, k]] for k in range(3))
    area = 0.5 * float(np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())
    return math.sqrt(area) / max(int(cells), 1)


def mesh_edges(obj) -> np.ndarray:
    """(e, 2) vertex indices of the mesh's edges."""
    mesh = obj.data
    edges = np.empty(2 * len(mesh.edges), dtype=np.int32)
    mesh.edges.foreach_get("vertices", edges)
    return edges.reshape(-1, 2)


def pin_mask(obj, group_name: str) -> np.ndarray:
    """(n,) bool: the vertices of the pin group with weight above 0.5."""
    group = obj.vertex_groups.get(group_name)
    if group is None:
        raise BakeError(f"pin group '{group_name}' is not a vertex group of '{obj.name}': "
                        "choose one of its vertex groups as Pin Group (Physics > ThinBurn > "
                        "Motion), or clear it")
    mask = np.zeros(len(obj.data.vertices), dtype=bool)
    index = group.index
    for v in obj.data.vertices:
        for g in v.groups:
            if g.group == index and g.weight > 0.5:
                mask[v.index] = True
    return mask


# The floor of a Floor object sits this far above its top face, and a sheet lying on that face
# is lifted by as much: a sheet that coincides with the table top flickers in renders (z-fight).
FLOOR_CLEARANCE = 0.0005  # m


def object_top(obj) -> float:
    """The highest world z of an object's bounding box now (a table's top face)."""
    m = obj.matrix_world
    return max(float((m @ mathutils.Vector(corner)).z) for corner in obj.bound_box)


def floor_height(scene, settings):
    """World height of the floor, or None."""
    if settings.floor_mode == "HEIGHT":
        return float(settings.floor_height)
    if settings.floor_mode == "OBJECT":
        if settings.floor_object is None:
            raise BakeError("Floor is set to Object but no Floor Object is chosen: pick the table "
                            "(or whatever the sheet lies on), or set Floor to Height")
        return object_top(settings.floor_object) + FLOOR_CLEARANCE
    return None


def flame_igniters(igniters: list) -> list:
    """The igniters (names) that are Flames: they burn on their own."""
    return [n for n in igniters if bpy.data.objects[n].thinburn_igniter.kind == "FLAME"]


def igniter_objects(obj, settings) -> list:
    """The igniters of a sheet (names), or a BakeError that says what to do. A sheet lit by
    its Ignite map needs none."""
    coll = settings.igniter_collection
    painted = bool(settings.ignite_map)
    if coll is None:
        if painted:
            return []
        raise BakeError(f"no igniters: set an Igniter collection on '{obj.name}' "
                        "(Physics > ThinBurn) and put an Empty or a mesh in it, or paint where "
                        "it starts (Physics > ThinBurn > Painted > Ignite)")
    names = [o.name for o in coll.all_objects if o.name != obj.name]
    if not names and not painted:
        raise BakeError(f"no igniters: the collection '{coll.name}' is empty; add an Empty "
                        "or a mesh and keyframe its ThinBurn Igniter strength")
    return names


# --- painted maps ---------------------------------------------------------------------------------
MAP_LABELS = {"speed_map": "Speed", "fuel_map": "Fuel", "ignite_map": "Ignite"}


def vertex_map(obj, settings, key: str):
    """(n,) float values of a painted map (a vertex group's weights, unassigned vertices 0, or
    a float attribute on the vertices), or None when the map is not set."""
    name = getattr(settings, key)
    if not name:
        return None
    label = MAP_LABELS[key]
    mesh = obj.data
    n = len(mesh.vertices)
    if getattr(settings, key + "_from") == "GROUP":
        group = obj.vertex_groups.get(name)
        if group is None:
            raise BakeError(f"{label} map: '{name}' is not a vertex group of '{obj.name}': pick one "
                            "in Physics > ThinBurn > Painted, or switch it to Attribute")
        values = np.zeros(n)
        index = group.index
        for v in mesh.vertices:
            for g in v.groups:
                if g.group == index:
                    values[v.index] = g.weight
        return values
    attr = mesh.attributes.get(name)
    if attr is None:
        raise BakeError(f"{label} map: '{obj.name}' has no attribute '{name}': pick one in "
                        "Physics > ThinBurn > Painted, or switch it to Vertex Group")
    if attr.domain != "POINT" or attr.data_type not in {"FLOAT", "INT", "BOOLEAN"}:
        raise BakeError(f"{label} map: attribute '{name}' holds {attr.data_type.lower()} values on "
                        f"the {attr.domain.lower()} domain; paint a Float attribute on vertices (Point)")
    field = "value"
    raw = np.zeros(n, dtype=np.float64 if attr.data_type == "FLOAT" else
                   (np.int32 if attr.data_type == "INT" else bool))
    attr.data.foreach_get(field, raw)
    values = raw.astype(np.float64)
    if not np.all(np.isfinite(values)) or (values < 0).any():
        bad = values[~np.isfinite(values) | (values < 0)][0]
        raise BakeError(f"{label} map: attribute '{name}' holds {bad:g}; paint values of 0 "
                        "(never burns) or more (1: the material's own)")
    return values


def surface_points(obj, spacing: float, limit: int = 200_000) -> np.ndarray:
    """(k, 3) world points on a mesh igniter's faces, at most about ``spacing`` apart (its
    vertices and points spread over each triangle), so that the cells within an igniter's
    radius of its surface are those within that radius of a point, to within spacing."""
    mesh = obj.data
    n = len(mesh.vertices)
    co = np.empty(3 * n)
    mesh.vertices.foreach_get("co", co)
    mw = np.array(obj.matrix_world, dtype=np.float64)
    world = co.reshape(n, 3) @ mw[:3, :3].T + mw[:3, 3]
    mesh.calc_loop_triangles()
    tris = np.empty(3 * len(mesh.loop_triangles), dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    tris = tris.reshape(-1, 3)
    out = [world]
    if len(tris) and spacing > 0:
        a, b, c = (world[tris[:, k]] for k in range(3))
        longest = np.max([np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1),
                          np.linalg.norm(a - c, axis=1)], axis=0)
        splits = np.ceil(longest / spacing).astype(int)
        total = len(world)
        for m in np.unique(splits[splits > 1]):
            sel = splits == m
            i, j = np.meshgrid(np.arange(m + 1), np.arange(m + 1), indexing="ij")
            keep = (i + j) <= m
            wb, wc = i[keep] / m, j[keep] / m
            wa = 1.0 - wb - wc
            pts = (wa[None, :, None] * a[sel][:, None] + wb[None, :, None] * b[sel][:, None]
                   + wc[None, :, None] * c[sel][:, None]).reshape(-1, 3)
            total += len(pts)
            if total > limit:
                raise BakeError(f"igniter '{obj.name}' is too large for its fire cells ({total} "
                                "points to test): use a smaller igniter mesh or lower Fire Detail")
            out.append(pts)
    return np.concatenate(out)


FIELD_KINDS = ("WIND", "TURBULENCE")  # the force fields that blow on a sheet
FIELD_SHAPES = ("POINT", "LINE", "PLANE")


def wind_objects(view_layer) -> list:
    """Names of the Wind and Turbulence force fields in the view layer."""
    return [o.name for o in view_layer.objects
            if o.field is not None and o.field.type in FIELD_KINDS]


def field_spec(ob) -> FieldSpec:
    """A force field's settings now, in world space (thinburn.force_fields evaluates them)."""
    f = ob.field
    m = ob.matrix_world
    axis = np.array(m.to_3x3().col[2], dtype=np.float64)
    length = float(np.linalg.norm(axis))
    axis = axis / length if length > 0 else np.array([0.0, 0.0, 1.0])
    return FieldSpec(
        kind=f.type, origin=tuple(float(c) for c in m.translation), axis=tuple(float(c) for c in axis),
        shape=f.shape if f.shape in FIELD_SHAPES else "POINT", strength=float(f.strength),
        noise=float(f.noise), seed=int(f.seed), z_direction=f.z_direction, falloff=f.falloff_type,
        power=float(f.falloff_power), use_min=bool(f.use_min_distance),
        min_distance=float(f.distance_min), use_max=bool(f.use_max_distance),
        max_distance=float(f.distance_max), radial_power=float(f.radial_falloff),
        use_radial_min=bool(f.use_radial_min), radial_min=float(f.radial_min),
        use_radial_max=bool(f.use_radial_max), radial_max=float(f.radial_max),
        size=float(f.size), global_coords=bool(f.use_global_coords))


# --- what the bake ignores, said so ---------------------------------------------------------------
TRANSFORM_PATHS = {"location", "rotation_euler", "rotation_quaternion", "rotation_axis_angle",
                   "scale", "delta_location", "delta_rotation_euler", "delta_rotation_quaternion",
                   "delta_scale"}


def _fcurves(anim) -> list:
    """The F-curves of an object's action (Blender 5's slotted actions, or 4.x's flat ones)."""
    action = anim.action
    if action is None:
        return []
    if hasattr(action, "fcurves"):
        return list(action.fcurves)
    from bpy_extras import anim_utils
    bag = anim_utils.action_get_channelbag_for_slot(action, anim.action_slot)
    return [] if bag is None else list(bag.fcurves)


def transform_animation(obj):
    """What animates the object's transform, in the UI's words, or None: keyframes or drivers
    on its location, rotation or scale, constraints, or the same on a parent."""
    ob = obj
    while ob is not None:
        whose = "its" if ob is obj else f"its parent '{ob.name}''s"
        anim = ob.animation_data
        if anim is not None:
            curves = _fcurves(anim) + list(anim.drivers)
            paths = sorted({fc.data_path for fc in curves if fc.data_path in TRANSFORM_PATHS
                            and not fc.mute})
            if paths:
                return f"{whose} {', '.join(p.replace('_', ' ') for p in paths)} (animated)"
        live = [c.name for c in ob.constraints if c.enabled]
        if live:
            return f"{whose} constraint{'s' if len(live) > 1 else ''} {', '.join(live)}"
        ob = ob.parent
    return None


def floor_motion_error(name: str, what: str, frame) -> str:
    return (f"'{name}' tilts or moves up or down in the scene ({what}; at frame {frame}), and "
            "its Floor cannot follow that: set Floor to None (Physics > ThinBurn > Floor), or "
            "animate only the sheet's X/Y location and Z rotation")


def tilt_warning(name: str, degrees: float) -> str:
    return (f"'{name}' tilts up to {degrees:.0f}° during the bake: ThinBurn follows it, but keeps "
            "the sheet's buoyancy, the fire's climb and the flames' rise along its up direction "
            "at Start, not the world's up")


def wind_warnings(view_layer) -> list:
    """What the bake ignores of the force fields: Wind and Turbulence fields blow on the sheet
    with their shape (Point, Line, Plane), strength, falloff, distances and noise, read every
    frame; a Surface or Every Point shape, and every other kind of field, are not used."""
    out = []
    for ob in view_layer.objects:
        field = ob.field
        if field is None or field.type == "NONE":
            continue
        kind = field.type.replace("_", " ").title()
        if field.type not in FIELD_KINDS:
            out.append(f"'{ob.name}' (a {kind} field) does not act on ThinBurn sheets: only Wind "
                       "and Turbulence fields blow on them")
        elif field.shape not in FIELD_SHAPES:
            out.append(f"{kind} '{ob.name}': its Shape ({field.shape.title()}) is not used: "
                       "ThinBurn measures its falloff from the field's centre (Shape Point); "
                       "set Shape to Point, Line or Plane")
    return out


def sample_frame(scene, frame: int, sheet_name: str, igniters: list, winds: list,
                 spacing: float = 0.0) -> FrameSample:
    """Move the scene to ``frame`` and read the igniters, the force fields and the sheet's
    transform. Empties (any object but a mesh) light around their origin; mesh igniters around
    their surface, sampled ``spacing`` apart; Flames burn on their own at their origin.

    frame_set evaluates the scene and writes animated values and world matrices back to the
    original objects (those of the active depsgraph), which is what is read here.
    """
    scene.frame_set(frame)
    objects = bpy.data.objects
    for name in (sheet_name, *igniters, *winds):
        if objects.get(name) is None:
            raise BakeError(f"'{name}' was deleted or renamed during the bake")
    samples, surfaces, flames = [], [], []
    for name in igniters:
        ob = objects[name]
        ig = ob.thinburn_igniter
        if ig.kind == "FLAME":  # burns on its own: fire particles from its origin while lit
            if ig.strength > 0.0:
                flames.append((np.array(ob.matrix_world.translation, dtype=np.float64), 2.0 * float(ig.radius)))
            continue
        if ob.type == "MESH":  # its surface lights the cells within its radius while lit
            if ig.strength > 0.0:
                surfaces.append((surface_points(ob, spacing), float(ig.radius)))
            continue
        samples.append((np.array(ob.matrix_world.translation, dtype=np.float64),
                        float(ig.strength), float(ig.radius)))
    sheet = objects[sheet_name]
    settings = sheet.thinburn
    return FrameSample(frame, samples, [field_spec(objects[name]) for name in winds],
                       float(settings.wind_scale), dynamics(scene, settings),
                       np.array(sheet.matrix_world, dtype=np.float64), surfaces, flames)


def dynamics(scene, settings) -> dict:
    """The motion parameters now: the sheet's keyframeable ones and the scene's gravity."""
    values = {key: float(getattr(settings, key)) for key in DYNAMIC_PARAMS}
    gravity = tuple(float(g) for g in scene.gravity) if scene.use_gravity else (0.0, 0.0, 0.0)
    values["gravity"] = gravity
    return values


def blend_stem() -> str:
    """The open .blend's name without '.blend' ('untitled' while it is not saved): each file's
    bakes go into a folder of their own, so a Save As never shares (or frees) another's."""
    if not bpy.data.filepath:
        return "untitled"
    return bpy.path.clean_name(os.path.splitext(os.path.basename(bpy.data.filepath))[0])


def saved_file_plays(path: str) -> bool:
    """Whether the .blend saved on disk may play the cache file ``path``: the file exists and
    was written before the .blend's last save (a bake since then is the open file's alone).
    A copy Save As made keeps its bake's time, so it counts as the saved file's."""
    blend = bpy.data.filepath
    if not blend or not os.path.exists(blend) or not os.path.exists(path):
        return False
    return os.path.getmtime(path) <= os.path.getmtime(blend)


def _cache_names(stem: str):
    """``<stem>.pc2``, then ``<stem>.2.pc2``, ``<stem>.3.pc2``, …: the names a sheet's bake may
    take (clean object names have no '.', so no sheet's name is another's version)."""
    yield stem + ".pc2"
    for k in range(2, 10000):
        yield f"{stem}.{k}.pc2"


def cache_path(obj, settings, keep_saved: bool = True) -> tuple:
    """(path for the modifier as the artist wrote it, absolute path) of the sheet's PC2 file:
    ``<Cache Folder>/<blend name>/<object name>.pc2``. A re-bake never writes over the cache
    the saved .blend plays (a file written before its last save): it takes the next free
    ``<object name>.<k>.pc2``, and saving the file deletes the one it no longer plays
    (saving.drop_superseded). Re-baking an unsaved change writes over the last bake, and so
    does every bake with ``keep_saved`` False (a headless bake that saves the .blend at once)."""
    raw = settings.cache_dir.strip()
    if not raw:
        raise BakeError("the Cache Folder is empty: choose a folder for the bake "
                        "(Physics > ThinBurn > Cache; '//thinburn_cache/' keeps it beside the .blend)")
    if raw.startswith("//") and not bpy.data.filepath:
        raise BakeError(f"the cache folder '{raw}' is relative to the .blend file, which is not "
                        "saved yet: save the file or choose an absolute folder")
    stem = blend_stem()
    folder = os.path.join(bpy.path.abspath(raw), stem)
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as exc:
        raise BakeError(f"cannot create the cache folder '{folder}': {exc.strerror or exc}. "
                        "Choose another Cache Folder (Physics > ThinBurn > Cache)") from None
    if not os.access(folder, os.W_OK):
        raise BakeError(f"the cache folder '{folder}' is not writable: choose another Cache "
                        "Folder (Physics > ThinBurn > Cache)")
    name = next(n for n in _cache_names(bpy.path.clean_name(obj.name))
                if not (keep_saved and saved_file_plays(os.path.join(folder, n))))
    shown = raw if raw.endswith(("/", "\\")) else raw + "/"
    return f"{shown}{stem}/{name}", os.path.join(folder, name)


# --- sheets that heat each other bake together -----------------------------------------------------
# Heat Ignites lights a cell from the fire particles' heat (eq. 2), and the particles rise about
# a Flame Height above the burning edge before they cool (docs/heat.md). Two sheets whose world
# bounding boxes come closer than HEAT_REACH + the larger Flame Height can heat each other, so
# they bake as one simulation; further apart they bake alone, as before.
HEAT_REACH = 0.05  # m, beyond the flames: the hot particles' sideways spread and the mesh's curl


def heat_reach(settings) -> float:
    """How close (m) another sheet must come to this one to bake with it."""
    return HEAT_REACH + float(settings.flame_height)


def world_box(obj) -> tuple:
    """(min (3,), max (3,)) of the object's bounding box in the world now."""
    m = np.array(obj.matrix_world, dtype=np.float64)
    corners = np.array([tuple(c) for c in obj.bound_box], dtype=np.float64)
    world = corners @ m[:3, :3].T + m[:3, 3]
    return world.min(axis=0), world.max(axis=0)


def box_gap(a, b) -> float:
    """The distance between two axis-aligned boxes (0 when they overlap)."""
    d = np.maximum(0.0, np.maximum(a[0] - b[1], b[0] - a[1]))
    return float(np.linalg.norm(d))


def heats_others(obj) -> bool:
    s = obj.thinburn
    return obj.type == "MESH" and s.enabled and s.heat_ignites and s.crumple


def heat_group(scene, obj) -> list:
    """The names of the sheets that bake with ``obj`` (``obj`` first, then the scene's order):
    the enabled meshes with Heat Ignites (and Crumple) linked to it by chains of sheets whose
    bounding boxes come within heat_reach of each other. Just ``obj`` when its Heat Ignites is
    off."""
    if not heats_others(obj):
        return [obj.name]
    sheets = [o for o in scene.objects if o is not obj and heats_others(o)]
    boxes = {o.name: world_box(o) for o in [obj, *sheets]}
    group, todo = [obj], [obj]
    while todo:
        here = todo.pop()
        for o in sheets:
            if o in group:
                continue
            reach = max(heat_reach(here.thinburn), heat_reach(o.thinburn))
            if box_gap(boxes[here.name], boxes[o.name]) <= reach:
                group.append(o)
                todo.append(o)
    order = {o.name: i for i, o in enumerate(scene.objects)}
    rest = sorted((o.name for o in group[1:]), key=order.get)
    return [obj.name, *rest]


def group_geometry(objs) -> tuple:
    """(world vertices, triangles, [(name, first vertex, vertex count, world matrix)]) of the
    sheets' meshes concatenated in this order (each triangle's indices shifted by its offset)."""
    worlds, tris, parts, offset = [], [], [], 0
    for obj in objs:
        world, t, mw = sheet_geometry(obj)
        worlds.append(world)
        tris.append(t + offset)
        parts.append((obj.name, offset, len(world), mw))
        offset += len(world)
    return np.concatenate(worlds), np.concatenate(tris).astype(np.int32), parts


def group_edges(objs) -> np.ndarray:
    """(e, 2) edges of the concatenated meshes."""
    out, offset = [], 0
    for obj in objs:
        out.append(mesh_edges(obj) + offset)
        offset += len(obj.data.vertices)
    return np.concatenate(out)


# Painted maps of a group: a sheet without its own map takes the value that changes nothing.
MAP_NEUTRAL = {"speed_map": 1.0, "fuel_map": 1.0, "ignite_map": 0.0}


def group_vertex_map(objs, key: str):
    """(n,) the sheets' painted maps concatenated, or None when none of them has one."""
    maps = [vertex_map(obj, obj.thinburn, key) for obj in objs]
    if all(m is None for m in maps):
        return None
    return np.concatenate([np.full(len(obj.data.vertices), MAP_NEUTRAL[key]) if m is None else m
                           for obj, m in zip(objs, maps)])


def group_pin_mask(objs):
    """(n,) bool: each sheet's Pin Group concatenated, or None when none has one."""
    if not any(obj.thinburn.pin_group for obj in objs):
        return None
    return np.concatenate([pin_mask(obj, obj.thinburn.pin_group) if obj.thinburn.pin_group
                           else np.zeros(len(obj.data.vertices), dtype=bool) for obj in objs])


def group_igniters(objs) -> list:
    """Every igniter of the group's sheets (names, each once, none of the sheets themselves):
    a sheet of a group needs no igniter of its own, as long as one of them has some."""
    members = {obj.name for obj in objs}
    names, errors = [], []
    for obj in objs:
        try:
            found = igniter_objects(obj, obj.thinburn)
        except BakeError as exc:
            errors.append(exc)
            continue
        names += [n for n in found if n not in members and n not in names]
    if not names and not any(obj.thinburn.ignite_map for obj in objs):
        raise errors[0] if errors else BakeError(
            f"no igniters: none of {', '.join(repr(o.name) for o in objs)} (they bake together) "
            "has an Igniter collection with an Empty or a mesh in it")
    return names


# The settings a group bakes with come from the sheet it was baked from; these, when another
# sheet of the group has them otherwise, are not used for it (the report says so).
GROUP_SHARED = ("material", "cells", "crumple", "frame_start", "frame_end", "lattice", "crease_angle",
                "integrator", "seed", "front", "burn_duration", "floor_mode", "floor_height",
                "floor_object", "wind_scale", "threads")


def group_setting_warnings(lead, others) -> list:
    """One line per sheet whose shared settings differ from ``lead``'s, naming them."""
    props = lead.thinburn.bl_rna.properties
    keys = list(GROUP_SHARED) + [p.identifier for p in props if p.identifier.startswith("mat_")]
    keys += [k for k in (*MODEL_PARAMS, *DYNAMIC_PARAMS) if k not in keys]
    out = []
    for obj in others:
        differ = [props[k].name for k in keys
                  if props.get(k) is not None and getattr(obj.thinburn, k) != getattr(lead.thinburn, k)]
        if differ:
            out.append(f"'{obj.name}' burns together with '{lead.name}' as one simulation, with "
                       f"'{lead.name}''s settings: its own {', '.join(differ)} "
                       f"{'is' if len(differ) == 1 else 'are'} not used. Set them alike, or bake "
                       f"from '{obj.name}' to use its settings for the group")
    return out


# --- collision objects ----------------------------------------------------------------------------
# Blender's cloth collision takes cloth_friction * 0.01 times the normal speed change off the
# tangential speed (collision.cc, cloth_collision_response_static): a Coulomb coefficient of
# cloth_friction / 100, which is what the core's colliders take.
CLOTH_FRICTION_SCALE = 0.01


def _collision_modifier(ob):
    return next((m for m in ob.modifiers if m.type == "COLLISION" and m.show_viewport), None)


def collision_objects(view_layer, sheet_name: str) -> list:
    """Names of the meshes in the view layer with Blender's Collision physics (a Collision
    modifier), the sheet itself excepted."""
    return [o.name for o in view_layer.objects
            if o.name != sheet_name and o.type == "MESH" and _collision_modifier(o) is not None]


def closed_mesh(tris: np.ndarray) -> bool:
    """Every edge in exactly two triangles (what a collider mesh must be)."""
    e = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    return bool(len(counts)) and bool(np.all(counts == 2))


def collider_sample(ob, depsgraph) -> dict:
    """A collision object now: its evaluated mesh in its own (scaled) frame, its pose in the
    world (rotation, translation: world = rotation @ vertices + translation) and its settings.
    A mirrored or sheared transform is baked into the vertices (pose: identity)."""
    ob_eval = ob.evaluated_get(depsgraph)
    me = ob_eval.to_mesh()
    try:
        me.calc_loop_triangles()
        co = np.empty(3 * len(me.vertices), dtype=np.float64)
        me.vertices.foreach_get("co", co)
        tris = np.empty(3 * len(me.loop_triangles), dtype=np.int32)
        me.loop_triangles.foreach_get("vertices", tris)
    finally:
        ob_eval.to_mesh_clear()
    co, tris = co.reshape(-1, 3), tris.reshape(-1, 3)
    m = np.array(ob.matrix_world, dtype=np.float64)
    A, t = m[:3, :3], m[:3, 3]
    scale = np.linalg.norm(A, axis=0)
    R = A / np.where(scale > 0, scale, 1.0)
    if np.all(scale > 0) and np.abs(R.T @ R - np.eye(3)).max() < 1e-6 and np.linalg.det(R) > 0:
        local = co * scale
    else:
        local, R = co @ A.T, np.eye(3)
    c = ob.collision
    return dict(name=ob.name, vertices=local, faces=tris, rotation=R, translation=t,
                friction=CLOTH_FRICTION_SCALE * float(c.cloth_friction), thickness=float(c.thickness_outer))


def collision_warnings(view_layer, sheet_name: str, shell: bool) -> list:
    """What the bake ignores of Blender's Collision settings, in the panel's words."""
    out = []
    for ob in view_layer.objects:
        mod = _collision_modifier(ob)
        if mod is None:
            continue
        if ob.name == sheet_name:
            out.append(f"'{ob.name}' has Collision physics itself: ThinBurn ignores it on the sheet")
            continue
        if ob.type != "MESH":
            out.append(f"'{ob.name}' has Collision physics but is not a mesh: only meshes collide with ThinBurn sheets")
            continue
        if not shell:
            out.append(f"'{ob.name}' (Collision) does not hold the sheet: collisions need Crumple on "
                       "(Physics > ThinBurn)")
            continue
        ignored = changed_collision_settings(ob.collision)
        if ignored:
            out.append(f"Collision '{ob.name}': {', '.join(ignored)} not used by ThinBurn: it uses "
                       "Friction and Outer thickness only, and collides with both sides")
    return out


# m: a collider's Outer thickness above this is named in the bake's report, since the sheet rests
# that far off it (Blender's default is 0.02 m; docs/blender.md, "Collision objects").
OUTER_NOTICE = 0.005

# What a ThinBurn sheet reads of Blender's Collision physics (docs/blender.md, "Collision
# objects"); the panel says it, so that the report need not warn about settings left alone.
COLLISION_NOTE = ("Collision objects: ThinBurn uses their Friction and Outer thickness; it "
                  "ignores Damping, Single Sided (it collides with both sides), Override Normals, "
                  "Inner thickness and the particle settings")

# Blender's defaults of the Collision settings ThinBurn ignores (a new Collision modifier in
# bpy 4.2-5.0: Damping 0.1, Single Sided on, Override Normals off). Every new Collision has
# them, so warning about them warned on every bake; the report names only those changed.
IGNORED_COLLISION_DEFAULTS = (("Damping", "damping", 0.1), ("Override Normals", "use_normal", False))


def changed_collision_settings(c) -> list:
    """Labels of the ignored Collision settings that differ from Blender's defaults. Single
    Sided is not among them: on (the default) or off, a ThinBurn sheet meets both sides."""
    return [label for label, attr, default in IGNORED_COLLISION_DEFAULTS
            if abs(float(getattr(c, attr)) - float(default)) > 1e-6]


def collision_note(view_layer, sheet_name: str):
    """The panel's line on Collision objects, when the view layer has one besides the sheet."""
    return COLLISION_NOTE if collision_objects(view_layer, sheet_name) else None
