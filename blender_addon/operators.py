"""Bake, Bake All and Free Bake.

``bpy.ops.thinburn.bake()`` (the active mesh) and ``bpy.ops.thinburn.bake_all()`` (every
enabled sheet of the scene) called from a script (or in background mode) bake to the end
before they return. Invoked from the UI they are modal: a timer drives the bake, the status
bar shows the sheet, the frame and a progress bar, Esc cancels and leaves the previous bake
untouched. ``bake_now`` is the bake-to-the-end that Quick Burn and headless bakes share.
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
        batch = getattr(job, "batch", None)
        which = f"'{job.obj_name}' ({batch[0]} of {batch[1]}) " if batch and batch[1] > 1 else ""
        self.layout.progress(factor=job.progress, type="BAR",
                             text=f"ThinBurn {which}frame {job.current_frame} / {job.frames[-1]}, "
                                  f"ETA {job.eta_text()}  (Esc cancels)")


def bake_now(context, obj, stream=None, interval: float = 1.0, on_frame=None,
             keep_saved: bool = True) -> BakeJob:
    """Bake ``obj`` to the end before returning (scripts, background mode, Quick Burn, Bake
    All, headless). With ``stream``, a progress line about every ``interval`` seconds (and one
    at the end); ``on_frame(job)`` after each frame. Raises BakeError with the artist's text;
    a failed or interrupted bake leaves the previous one as it was. ``keep_saved`` False
    writes over the cache the saved .blend plays (inputs.cache_path)."""
    scene = context.scene
    if running_job(scene) is not None:
        raise BakeError("another ThinBurn bake is running in this scene: wait for it to finish, "
                        "or press Esc to cancel it")
    job = BakeJob(context, obj, keep_saved)
    lines = ProgressLines(job.obj_name, stream, interval) if stream is not None else None

    def progress(j):
        if lines is not None:
            lines(j)
        if on_frame is not None:
            on_frame(j)
    _running[scene.name] = job
    if lines is not None:
        lines.building()
    try:
        job.run(progress=progress, built=lines.built if lines is not None else None)
    except BakeError:
        raise
    except BaseException:
        job.cancel()  # stop the worker, keep the previous bake, then let the error show
        raise
    finally:
        _running.pop(scene.name, None)
    if lines is not None:
        lines(job, force=True)
    return job


def report_bake(op, job) -> None:
    """The bake's message, and a warning for each thing it had to ignore."""
    op.report({"INFO"}, job.message)
    for text in getattr(job, "warnings", ()):
        op.report({"WARNING"}, f"ThinBurn: {text}")


def enabled_sheets(scene) -> list:
    """The scene's meshes with ThinBurn enabled, by name."""
    return [o.name for o in scene.objects if o.type == "MESH" and o.thinburn.enabled]


class BakeSheets:
    """Bake one sheet after another. From a script or in background mode the operator bakes to
    the end before it returns (progress lines on stderr in background mode). Invoked from the
    UI it is modal: a timer drives the bake, the status bar shows the sheet, the frame and a
    progress bar, Esc cancels the bake in progress and leaves its previous bake untouched."""

    bl_options = {"REGISTER"}

    _timer = None
    _job = None
    _status_bar = False
    _queue = ()
    _count = 0

    def _targets(self, context) -> list:
        raise NotImplementedError

    def _fail(self, name, exc) -> None:
        self.report({"ERROR"}, f"ThinBurn: {exc}")

    def execute(self, context):
        names = self._targets(context)
        stream = sys.stderr if bpy.app.background else None
        baked, together = 0, set()
        for name in names:
            if name in together:
                continue  # baked already, with a sheet it heats (inputs.heat_group)
            try:
                job = bake_now(context, bpy.data.objects[name], stream=stream)
            except BakeError as exc:
                self._fail(name, exc)
                continue
            baked += 1
            together.update(job.members)
            report_bake(self, job)
        return {"FINISHED"} if baked else {"CANCELLED"}

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        self._queue = list(self._targets(context))
        self._count = len(self._queue)
        if not _start_next(self, context):
            return {"CANCELLED"}
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.05, window=context.window)
        wm.progress_begin(0, 1000)
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
            _fail(self, job.obj_name, exc)
            done = None
        except BaseException:
            job.cancel()
            self._end(context)
            raise
        context.window_manager.progress_update(int(1000 * job.progress))
        context.workspace.status_text_set(job.status_text())
        for area in context.screen.areas:
            if area.type in {"PROPERTIES", "STATUSBAR"}:
                area.tag_redraw()
        if done is False:
            return {"RUNNING_MODAL"}
        if done:
            report_bake(self, job)
        if _start_next(self, context):
            return {"RUNNING_MODAL"}
        self._end(context)
        return {"FINISHED"} if done else {"CANCELLED"}

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


def _fail(op, name, exc) -> None:
    fail = getattr(op, "_fail", None)
    if fail is not None:
        fail(name, exc)
    else:
        op.report({"ERROR"}, f"ThinBurn: {exc}")


def _start_next(op, context) -> bool:
    """Start the modal operator's next sheet (skipping those that cannot start). False when
    none is left."""
    queue = getattr(op, "_queue", None) or []
    _running.pop(context.scene.name, None)
    done = getattr(getattr(op, "_job", None), "members", ())
    queue[:] = [n for n in queue if n not in done]  # baked already, with a sheet it heats
    while queue:
        name = queue.pop(0)
        try:
            job = BakeJob(context, bpy.data.objects[name])
        except BakeError as exc:
            _fail(op, name, exc)
            continue
        job.batch = (op._count - len(queue), op._count)
        op._job = job
        _running[context.scene.name] = job
        return True
    return False


class THINBURN_OT_bake(BakeSheets, bpy.types.Operator):
    """Bake the burning of the active mesh to a PC2 cache and point attributes"""

    bl_idname = "thinburn.bake"
    bl_label = "Bake ThinBurn"

    @classmethod
    def poll(cls, context):
        return _sheet(context) is not None and running_job(context.scene) is None

    def _targets(self, context) -> list:
        return [_sheet(context).name]


class THINBURN_OT_bake_all(BakeSheets, bpy.types.Operator):
    """Bake every sheet of the scene that has ThinBurn enabled, one after another"""

    bl_idname = "thinburn.bake_all"
    bl_label = "Bake All ThinBurn"

    @classmethod
    def poll(cls, context):
        return running_job(context.scene) is None

    def _targets(self, context) -> list:
        names = enabled_sheets(context.scene)
        if not names:
            self.report({"ERROR"}, f"ThinBurn: no sheet to bake: no mesh in the scene "
                                   f"'{context.scene.name}' has ThinBurn enabled (tick the "
                                   "checkbox in Properties > Physics > ThinBurn)")
        return names

    def _fail(self, name, exc) -> None:
        self.report({"ERROR"}, f"ThinBurn: '{name}': {exc}")


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
        kept = [g for g in gone if g.startswith("kept ")]
        gone = [g for g in gone if not g.startswith("kept ")]
        if not gone:
            self.report({"INFO"}, f"ThinBurn: '{obj.name}' has no bake to free")
        else:
            self.report({"INFO"}, "ThinBurn: removed " + ", ".join(gone))
        for text in kept:
            self.report({"INFO"}, f"ThinBurn: {text}")
        return {"FINISHED"}


class THINBURN_OT_load_preset(bpy.types.Operator):
    """Reload the preset's values into Advanced > Burns Like"""

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


CLASSES = (THINBURN_OT_bake, THINBURN_OT_bake_all, THINBURN_OT_free_bake,
           THINBURN_OT_load_preset)


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


class THINBURN_OT_add_mantaflow_fire(bpy.types.Operator):
    """Make the baked sheet a Mantaflow fire source that emits from its burning edge, inside a
    smoke domain sized to the burn (Free Bake removes both)"""

    bl_idname = "thinburn.add_mantaflow_fire"
    bl_label = "Add Mantaflow Fire"
    bl_options = {"REGISTER", "UNDO"}

    bake: bpy.props.BoolProperty(
        name="Bake Now", default=False,
        description="Bake the smoke domain right away (else bake it from its Physics > Cache panel)")
    hide_flames: bpy.props.BoolProperty(
        name="Hide ThinBurn Flames", default=True,
        description="Hide the add-on's own flame volume, which Mantaflow's flames replace (its "
                    "light and the embers stay)")

    @classmethod
    def poll(cls, context):
        return _sheet(context) is not None and running_job(context.scene) is None

    def execute(self, context):
        from . import mantaflow
        obj = _sheet(context)
        if not obj.thinburn.baked_file:
            self.report({"ERROR"}, f"ThinBurn: bake '{obj.name}' first (Physics > ThinBurn > "
                                   "Bake): the fire source follows the baked burning edge")
            return {"CANCELLED"}
        try:
            mantaflow.prepare_solver(context.scene)  # before the domain's solver exists (bpy module)
            usable = True
        except mantaflow.MantaflowError as exc:
            self.report({"WARNING"}, f"ThinBurn: {exc}")
            usable = False
        mantaflow.add_flow(obj)
        domain = mantaflow.add_domain(obj, context.scene, obj.thinburn.mantaflow_resolution)
        mantaflow.hide_thinburn_flames(obj, self.hide_flames)
        if self.bake and usable:
            try:
                mantaflow.bake(domain, context.scene)
            except mantaflow.MantaflowError as exc:
                self.report({"ERROR"}, f"ThinBurn: {exc}")
                usable = False
        self.report({"INFO"}, f"ThinBurn: '{obj.name}' emits fire into '{domain.name}'"
                              + (" (baked)" if self.bake and usable
                                 else "; bake it in its Physics > Cache panel"))
        return {"FINISHED"}


CLASSES = CLASSES + (THINBURN_OT_add_mantaflow_fire,)


def _quick_effects_menu(self, context):
    self.layout.operator(THINBURN_OT_add_mantaflow_fire.bl_idname, icon="FORCE_FORCE")


@bpy.app.handlers.persistent
def _claim_unsaved_bakes(filepath, *_):
    """A bake made before the file was first saved belongs to the file it is saved as (so that
    Free there deletes its cache, and Free in a later Save As copy does not)."""
    for obj in bpy.data.objects:
        settings = getattr(obj, "thinburn", None)
        if settings is not None and len(settings.baked_files) and not settings.baked_blend:
            settings.baked_blend = filepath


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.app.handlers.save_pre.append(_claim_unsaved_bakes)
    bpy.types.VIEW3D_MT_object_quick_effects.append(_quick_effects_menu)


def unregister():
    bpy.types.VIEW3D_MT_object_quick_effects.remove(_quick_effects_menu)
    if _claim_unsaved_bakes in bpy.app.handlers.save_pre:
        bpy.app.handlers.save_pre.remove(_claim_unsaved_bakes)
    for job in list(_running.values()):
        job.cancel()
    _running.clear()
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
