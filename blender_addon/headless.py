"""Bakes without the UI: for render farms, scripts and ``python -m thinburn bake``.

Inside Blender::

    blender -b shot.blend --python-expr "import thinburn_addon.headless as h; h.main()" -- --object Sheet

(``bl_ext.user_default.thinburn.headless`` when installed as an extension), or with bpy as a
Python module: ``python -m thinburn bake shot.blend --object Sheet``. Each sheet is baked by
the add-on's own ``BakeJob`` (the same job and worker thread as the Bake button), with a
progress line about once a second (frame, %, elapsed, ETA) on stderr. After the bakes the
.blend is saved (its modifiers and attributes point at the new cache). A sheet that fails
prints ``ThinBurn: error: ...`` and keeps its previous bake (file, modifier, attributes); the
exit status is then 1.
"""
from __future__ import annotations

import argparse
import os
import sys

import bpy

from . import operators
from .inputs import BakeError


enabled_sheets = operators.enabled_sheets  # the scene's meshes with ThinBurn enabled, by name


def bake_object(obj, stream=sys.stderr, interval: float = 1.0, keep_saved: bool = True) -> str:
    """Bake one sheet as the Bake operator does from a script; returns the bake's message
    (and a line for each thing the bake ignored).

    Raises BakeError with the text the operator would report; the previous bake stays.
    ``keep_saved`` False writes over the cache the saved .blend plays (inputs.cache_path).
    """
    job = operators.bake_now(bpy.context, obj, stream=stream, interval=interval, keep_saved=keep_saved)
    return "\n".join([job.message, *(f"ThinBurn: warning: {w}" for w in job.warnings)])


def bake_file(filepath=None, objects=None, save: bool = True, usd=None, stream=sys.stderr,
              interval: float = 1.0) -> int:
    """Open ``filepath`` (None: the file already open), bake ``objects`` (names; None: every
    enabled sheet of the scene), save the .blend, optionally export each to ``usd``/<name>.usda.
    Returns the exit status: 0 if every bake succeeded, 1 otherwise."""
    if filepath is not None:
        bpy.ops.wm.open_mainfile(filepath=os.fspath(filepath))
    scene = bpy.context.scene
    names = list(objects) if objects else enabled_sheets(scene)
    if not names:
        stream.write(f"ThinBurn: error: no sheet to bake: no mesh in scene '{scene.name}' has "
                     "ThinBurn enabled (or pass --object NAME)\n")
        return 1
    failed, baked = [], []
    for name in names:
        obj = bpy.data.objects.get(name)
        try:
            if obj is None:
                raise BakeError(f"there is no object '{name}' in {bpy.data.filepath or 'this file'}")
            if scene.objects.get(name) is None:
                raise BakeError(f"'{name}' is not in the scene '{scene.name}'")
            stream.write(f"ThinBurn: baking '{name}' frames {obj.thinburn.frame_start}–"
                         f"{obj.thinburn.frame_end}\n")
            # A bake that saves the .blend at once writes over its cache: a farm's file
            # names stay as they are, and the saved file never plays a bake it did not make.
            stream.write(bake_object(obj, stream, interval, keep_saved=not save) + "\n")
            baked.append(name)
        except BakeError as exc:
            stream.write(f"ThinBurn: error: '{name}': {exc}\n")
            failed.append(name)
        stream.flush()
    if baked and save:
        if not bpy.data.filepath:
            stream.write("ThinBurn: error: the file has never been saved; nothing to save to\n")
            return 1
        bpy.ops.wm.save_mainfile()
        stream.write(f"ThinBurn: saved {bpy.data.filepath}\n")
    if usd and baked:
        from .usd_export import export_object
        for name in baked:
            path = os.path.join(bpy.path.abspath(usd), bpy.path.clean_name(name) + ".usda")
            export_object(bpy.data.objects[name], path)
            stream.write(f"ThinBurn: wrote {path}\n")
    if failed:
        stream.write(f"ThinBurn: {len(failed)} of {len(names)} bake(s) failed: {', '.join(failed)}\n")
    stream.flush()
    return 1 if failed else 0


def main(argv=None) -> None:
    """Command line inside Blender: the arguments after ``--``. Exits with bake_file's status."""
    if argv is None:
        argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="thinburn headless bake",
                                description="Bake the open .blend's ThinBurn sheets and save it.")
    p.add_argument("--object", action="append", default=None, metavar="NAME",
                   help="bake this sheet (repeat for more; default: every enabled sheet)")
    p.add_argument("--no-save", action="store_true", help="do not save the .blend")
    p.add_argument("--usd", default=None, metavar="FOLDER", help="also export FOLDER/<name>.usda")
    args = p.parse_args(argv)
    sys.exit(bake_file(None, objects=args.object, save=not args.no_save, usd=args.usd))
