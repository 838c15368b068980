"""Bake and Free Bake.

``bpy.ops.thinburn.bake()`` called from a script (or in background mode) bakes to the end
before it returns. Invoked from the UI it is modal: a timer drives the bake, the status bar
shows the frame and a progress bar, Esc cancels and leaves the previous bake untouched.
"""
from __future__ import annotations

import sys

import bpy

from . import materials
from .inputs import BakeError
from .properties import load_preset
from .job import BakeJob, ProgressLines

_running = {}  # scene name -> the BakeJob in progress (the panel shows it)


def running_job(scene):
    return _running.get(scene.name)


def _sheet(context):
    obj = context.active_object
    if obj is None or obj.type != "MESH":
        return None
    return obj


def _draw_status(self, context):
    job = running_job(context.scene)
    if job is not None:
        self.layout.progress(factor=job.progress, type="BAR",
                             text=f"ThinBurn frame {job.current_frame} / {job.frames[-1]}  (Esc cancels)")


class THINBURN_OT_bake(bpy.types.Operator):
    """Bake the burning of the active mesh to a PC2 cache and point attributes"""

    bl_idname = "thinburn.bake"
    bl_label = "Bake ThinBurn"
    bl_options = {"REGISTER"}

    _timer = None
    _job = None
    _status_bar = False

    @classmethod
    def poll(cls, context):
        return _sheet(context) is not None and running_job(context.scene) is None

    def _start(self, context):
        obj = _sheet(context)
        try:
            job = BakeJob(context, obj)
        except BakeError as exc:
            self.report({"ERROR"}, f"ThinBurn: {exc}")
            return None
        return job

    def execute(self, context):
        job = self._start(context)
        if job is None:
            return {"CANCELLED"}
        _running[context.scene.name] = job
        # From a script in background mode (blender -b) nothing else shows the bake going on.
        progress = ProgressLines(job.obj_name, sys.stderr, 1.0) if bpy.app.background else None
        try:
            job.run(progress=progress)
        except BakeError as exc:
            self.report({"ERROR"}, f"ThinBurn: {exc}")
            return {"CANCELLED"}
        except BaseException:
            job.cancel()  # stop the worker, keep the previous bake, then let the error show
            raise
        finally:
            _running.pop(context.scene.name, None)
        self.report({"INFO"}, job.message)
        return {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        job = self._start(context)
        if job is None:
            return {"CANCELLED"}
        self._job = job
        _running[context.scene.name] = job
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.05, window=context.window)
        wm.progress_begin(0, len(job.frames))
        bpy.types.STATUSBAR_HT_header.append(_draw_status)
        self._status_bar = True
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        job = self._job
        if event.type == "ESC" and event.value == "PRESS":
            job.cancel()
            self._end(context)
            self.report({"WARNING"}, "ThinBurn: bake cancelled; the previous bake is unchanged")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        try:
            done = job.tick(budget_s=0.04)
        except BakeError as exc:
            self._end(context)
            self.report({"ERROR"}, f"ThinBurn: {exc}")
            return {"CANCELLED"}
        except BaseException:
            job.cancel()
            self._end(context)
            raise
        context.window_manager.progress_update(job.frames_done)
        context.workspace.status_text_set(
            f"ThinBurn: baking frame {job.current_frame} of {job.frames[0]}–{job.frames[-1]}  (Esc to cancel)")
        for area in context.screen.areas:
            if area.type in {"PROPERTIES", "STATUSBAR"}:
                area.tag_redraw()
        if not done:
            return {"RUNNING_MODAL"}
        self._end(context)
        self.report({"INFO"}, job.message)
        return {"FINISHED"}

    def _end(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        context.workspace.status_text_set(None)
        if self._status_bar:
            bpy.types.STATUSBAR_HT_header.remove(_draw_status)
            self._status_bar = False
        _running.pop(context.scene.name, None)
        for area in context.screen.areas:
            area.tag_redraw()


class THINBURN_OT_free_bake(bpy.types.Operator):
    """Remove the active mesh's ThinBurn bake: cache file, modifiers, attributes, material"""

    bl_idname = "thinburn.free_bake"
    bl_label = "Free ThinBurn Bake"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _sheet(context) is not None and running_job(context.scene) is None

    def execute(self, context):
        obj = _sheet(context)
        gone = materials.free_bake(obj)
        if not gone:
            self.report({"INFO"}, f"ThinBurn: '{obj.name}' has no bake to free")
        else:
            self.report({"INFO"}, "ThinBurn: removed " + ", ".join(gone))
        return {"FINISHED"}


class THINBURN_OT_load_preset(bpy.types.Operator):
    """Reload the material preset's values into the Material fields"""

    bl_idname = "thinburn.load_preset"
    bl_label = "Reset to Preset"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _sheet(context) is not None

    def execute(self, context):
        settings = _sheet(context).thinburn
        load_preset(settings, settings.material)
        return {"FINISHED"}


CLASSES = (THINBURN_OT_bake, THINBURN_OT_free_bake, THINBURN_OT_load_preset)


class THINBURN_OT_add_burn_to_material(bpy.types.Operator):
    """Insert ThinBurn's char, ember glow and burn-through into each of the active mesh's
    materials, around their own shader (the bake does this for slots that have a material)"""

    bl_idname = "thinburn.add_burn_to_material"
    bl_label = "Add Burn to Material"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _sheet(context) is not None

    def execute(self, context):
        obj = _sheet(context)
        if not obj.material_slots:
            self.report({"ERROR"}, f"ThinBurn: '{obj.name}' has no material slots: add a material "
                                   "first, or bake, which makes a ThinBurn material")
            return {"CANCELLED"}
        results = materials.burn_materials(obj)
        added = sum(1 for _, r in results if r == "added")
        problems = [r for _, r in results if r not in ("added", "already")]
        for text in problems:
            self.report({"WARNING"}, f"ThinBurn: skipped {text}")
        self.report({"INFO"}, f"ThinBurn: added the burn to {added} material(s)")
        return {"FINISHED"}


CLASSES = CLASSES + (THINBURN_OT_add_burn_to_material,)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for job in list(_running.values()):
        job.cancel()
    _running.clear()
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
