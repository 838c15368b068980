"""Panels: Physics > ThinBurn for a sheet, Object > ThinBurn Igniter for an igniter.

Panels only poll and draw; everything they show is a property or an operator.
"""
from __future__ import annotations

import bpy

from . import inputs, job, materials, stretch
from .operators import running_job
from .properties import DYNAMIC_PARAMS, MATERIAL_FIELDS, MODEL_PARAMS, edited_fields


class ThinBurnPhysicsPanel:
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "physics"

    @classmethod
    def poll(cls, context):
        # Every mesh shows the ThinBurn panel (its header ticks ThinBurn on); its sub-panels
        # appear once it is on (issue #14: panels only where they apply).
        obj = context.object
        if obj is None or obj.type != "MESH":
            return False
        return not getattr(cls, "bl_parent_id", "") or obj.thinburn.enabled


class PHYSICS_PT_thinburn(ThinBurnPhysicsPanel, bpy.types.Panel):
    bl_label = "ThinBurn"

    def draw_header(self, context):
        self.layout.prop(context.object.thinburn, "enabled", text="")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        settings = context.object.thinburn
        layout.active = settings.enabled
        layout.prop(settings, "material")
        own = edited_fields(settings, settings.material)
        if own:
            # Fields kept through a change of preset, or set by hand: say so beside the preset.
            names = ", ".join(MATERIAL_FIELDS[f][0] for f in own)
            layout.label(text=f"Your own: {names} (Advanced > Reset to Preset)", icon="INFO")
        col = layout.column(align=True)
        col.prop(settings, "cells")
        row = col.row()
        row.active = settings.crumple and job.core_supports("lattice")
        row.prop(settings, "lattice")
        row = col.row()
        row.active = settings.crumple
        row.prop(settings, "crease_angle")
        layout.prop(settings, "crumple")
        row = layout.row()
        row.active = settings.crumple
        row.prop(settings, "heat_ignites")
        layout.prop(settings, "burn_duration")
        layout.prop(settings, "igniter_collection")
        layout.prop(settings, "wind_scale")
        layout.operator("thinburn.quick_burn", icon="LIGHT_SUN")
        if settings.enabled:
            for text in sheet_warnings(context, context.object):
                warning(layout, text)
            note = inputs.collision_note(context.view_layer, context.object.name)
            if note and settings.crumple:
                warning(layout, note, icon="INFO")


def sheet_warnings(context, obj) -> list:
    """What the bake will ignore or refuse, as the panel says it (the bake says it too). An
    animated transform is followed, but not with a Floor unless it only slides in X/Y and
    turns about Z; the panel cannot tell that without playing the frames, so it says what the
    bake will check."""
    out = []
    moving = inputs.transform_animation(obj)
    if moving and obj.thinburn.floor_mode != "NONE":
        out.append(f"'{obj.name}' moves in the scene ({moving}) and has a Floor: the bake follows "
                   "the motion only if it slides in X/Y and turns about Z; else set Floor to None")
    return out + inputs.wind_warnings(context.view_layer)


def warning(layout, text: str, width: int = 52, icon: str = "ERROR") -> None:
    """A warning (or with icon INFO, a note) in the panel, wrapped over as many lines as it needs."""
    import textwrap
    col = layout.column(align=True)
    for i, line in enumerate(textwrap.wrap(text, width)):
        col.label(text=line, icon=icon if i == 0 else "BLANK1")


class PHYSICS_PT_thinburn_motion(ThinBurnPhysicsPanel, bpy.types.Panel):
    bl_label = "Motion"
    bl_parent_id = "PHYSICS_PT_thinburn"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        settings = context.object.thinburn
        layout.active = settings.enabled and settings.crumple
        layout.prop(settings, "integrator")
        for key in DYNAMIC_PARAMS:
            layout.prop(settings, key)
        layout.label(text="Gravity: the scene's (Scene > Gravity)", icon="INFO")


class PHYSICS_PT_thinburn_painted(ThinBurnPhysicsPanel, bpy.types.Panel):
    bl_label = "Painted"
    bl_parent_id = "PHYSICS_PT_thinburn"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        obj = context.object
        settings = obj.thinburn
        layout.active = settings.enabled
        for key in ("speed_map", "fuel_map", "ignite_map"):
            col = layout.column(align=True)
            col.prop(settings, key + "_from", text=inputs.MAP_LABELS[key] + " From")
            if getattr(settings, key + "_from") == "GROUP":
                col.prop_search(settings, key, obj, "vertex_groups")
            else:
                col.prop_search(settings, key, obj.data, "attributes")
        row = layout.row()
        row.active = bool(settings.ignite_map)
        row.prop(settings, "ignite_frame")


class PHYSICS_PT_thinburn_hold(ThinBurnPhysicsPanel, bpy.types.Panel):
    bl_label = "Pins and Floor"
    bl_parent_id = "PHYSICS_PT_thinburn"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        obj = context.object
        settings = obj.thinburn
        layout.active = settings.enabled
        row = layout.row()
        row.active = job.core_supports("pinned")
        row.prop_search(settings, "pin_group", obj, "vertex_groups")
        col = layout.column()
        col.active = job.core_supports("floor")
        col.prop(settings, "floor_mode")
        if settings.floor_mode == "HEIGHT":
            col.prop(settings, "floor_height")
        elif settings.floor_mode == "OBJECT":
            col.prop(settings, "floor_object")


class PHYSICS_PT_thinburn_cache(ThinBurnPhysicsPanel, bpy.types.Panel):
    bl_label = "Bake"
    bl_parent_id = "PHYSICS_PT_thinburn"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        obj = context.object
        settings = obj.thinburn
        layout.active = settings.enabled
        col = layout.column(align=True)
        col.prop(settings, "frame_start")
        col.prop(settings, "frame_end")
        layout.prop(settings, "cache_dir")
        layout.prop(settings, "cache_step")
        running = running_job(context.scene)
        if running is not None:
            layout.progress(factor=running.progress, type="BAR",
                            text=f"Frame {running.current_frame} / {running.frames[-1]} (Esc cancels)")
        row = layout.row(align=True)
        row.operator("thinburn.bake", icon="RENDER_ANIMATION")
        row.operator("thinburn.free_bake", text="Free", icon="TRASH")
        layout.operator("thinburn.bake_all", icon="RENDER_ANIMATION")
        if settings.baked_file and obj.modifiers.get(materials.CACHE_MODIFIER):
            layout.label(text=f"Baked: {settings.baked_file}", icon="CHECKMARK")
            if settings.baked_shape:
                warning_free = settings.baked_strain <= stretch.WARN_STRAIN
                text = f"As {settings.baked_shape}"
                if settings.baked_strain > 0.0:
                    text += f"; edge lengths changed up to {100 * settings.baked_strain:.0f} %"
                layout.label(text=text, icon="INFO" if warning_free else "ERROR")


class PHYSICS_PT_thinburn_fire(ThinBurnPhysicsPanel, bpy.types.Panel):
    bl_label = "Fire"
    bl_parent_id = "PHYSICS_PT_thinburn"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        settings = context.object.thinburn
        layout.active = settings.enabled
        if not settings.crumple:
            layout.label(text="Flames and embers need Crumple: the fire particles come with it",
                         icon="INFO")
        layout.prop(settings, "flame_height")
        layout.prop(settings, "flame_intensity")
        layout.prop(settings, "flame_temperature")
        layout.prop(settings, "embers")
        layout.prop(settings, "burnt")
        layout.prop(settings, "flakes")
        layout.operator("thinburn.add_burn_to_material", icon="MATERIAL")
        row = layout.row(align=True)
        row.prop(settings, "mantaflow_resolution")
        row.operator("thinburn.add_mantaflow_fire", text="Add Mantaflow Fire", icon="FORCE_FORCE")
        cycles = getattr(context.scene, "cycles", None)
        if cycles is not None and not getattr(cycles, "volume_biased", True):
            layout.label(text="Flames render far faster with Light Paths > Volumes > Biased",
                         icon="INFO")


class PHYSICS_PT_thinburn_advanced(ThinBurnPhysicsPanel, bpy.types.Panel):
    bl_label = "Advanced"
    bl_parent_id = "PHYSICS_PT_thinburn"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        settings = context.object.thinburn
        layout.active = settings.enabled
        layout.prop(settings, "front")
        layout.prop(settings, "seed")
        layout.prop(settings, "threads")
        box = layout.column(heading="Burns Like")
        for field in MATERIAL_FIELDS:
            box.prop(settings, "mat_" + field)
        layout.operator("thinburn.load_preset", icon="LOOP_BACK")
        col = layout.column(heading="Spread")
        for key in MODEL_PARAMS:
            col.prop(settings, key)


class OBJECT_PT_thinburn_igniter(bpy.types.Panel):
    bl_label = "ThinBurn Igniter"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        obj = context.object
        if obj is None:
            return False
        # Only an igniter of some sheet: an object in a sheet's Igniters collection.
        for sheet in context.scene.objects:
            coll = sheet.thinburn.igniter_collection if sheet.type == "MESH" else None
            if coll is not None and obj.name in coll.all_objects:
                return True
        return False

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        igniter = context.object.thinburn_igniter
        layout.prop(igniter, "kind")
        layout.prop(igniter, "strength")
        layout.prop(igniter, "radius")


CLASSES = (PHYSICS_PT_thinburn, PHYSICS_PT_thinburn_painted, PHYSICS_PT_thinburn_motion,
           PHYSICS_PT_thinburn_hold,
           PHYSICS_PT_thinburn_cache, PHYSICS_PT_thinburn_fire,
           PHYSICS_PT_thinburn_advanced, OBJECT_PT_thinburn_igniter)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
