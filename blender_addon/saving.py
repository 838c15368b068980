"""Save As gives the new .blend a cache of its own: the bake's files are copied into the new
file's folder (``<Cache Folder>/<new blend name>/``) and its modifiers and record point there,
so the two files never share a cache (Free in one never touches the other's).

A re-bake of a saved file writes beside the cache that file plays (inputs.cache_path), and
``save_post`` deletes what the saved file no longer plays (drop_superseded): until the artist
saves, the file on disk still plays its own bake.

``save_pre`` copies and re-points; Blender then rebases the modifiers' relative paths to the
new file's folder (its *Remap Relative*, on by default), which is why a modifier's path is
written relative to the old file's folder here. ``save_post`` sets the paths as the new
folder sees them (a no-op after a remap) and, when the save was *Save Copy* (the open file
stays the old one), puts the open file's paths back: the copy on disk keeps its own cache.
"""
from __future__ import annotations

import os
import shutil

import bpy

from . import materials

_pending = []  # (saved-to path, [(setter, old value, new value)]) from save_pre to save_post


def _stem(path: str) -> str:
    return bpy.path.clean_name(os.path.splitext(os.path.basename(path))[0])


def _rel(path: str, folder: str) -> str:
    return "//" + os.path.relpath(path, folder).replace(os.sep, "/")


def _sheets():
    for obj in bpy.data.objects:
        settings = getattr(obj, "thinburn", None)
        if settings is not None and len(settings.baked_files):
            yield obj, settings


def _cache_modifiers(obj, settings):
    for o in [obj, *(item.object for item in settings.baked_objects if item.object is not None)]:
        for md in o.modifiers:
            if md.type == "MESH_CACHE":
                yield md


def new_location(path: str, old_blend: str, new_blend: str):
    """Where a recorded file ``path`` (as the modifiers have it) goes for ``new_blend``: the
    same name in the new file's folder beside the old one, ``<…>/<new stem>/<name>``; None when
    the file is not in the old file's folder (a cache folder the artist laid out otherwise)."""
    old_abs = bpy.path.abspath(path, start=os.path.dirname(old_blend))
    folder, name = os.path.split(os.path.normpath(old_abs))
    if os.path.basename(folder) != _stem(old_blend):
        return None
    base = os.path.dirname(folder)
    if path.startswith("//"):  # relative to the .blend: next to the new file, as the old was
        base = os.path.join(os.path.dirname(new_blend),
                            os.path.relpath(base, os.path.dirname(old_blend)))
    return old_abs, os.path.normpath(os.path.join(base, _stem(new_blend), name))


def _copy_bake(obj, settings, old_blend: str, new_blend: str, changes: list) -> None:
    old_dir, new_dir = os.path.dirname(old_blend), os.path.dirname(new_blend)
    modifiers = list(_cache_modifiers(obj, settings))
    places = [new_location(item.path, old_blend, new_blend) for item in settings.baked_files]
    if None in places:  # not this file's own folder (a bake made before the first save, say)
        return
    for item, (old_abs, new_abs) in zip(settings.baked_files, places):
        if os.path.exists(old_abs):
            os.makedirs(os.path.dirname(new_abs), exist_ok=True)
            shutil.copy2(old_abs, new_abs)
        relative = item.path.startswith("//")
        as_new = _rel(new_abs, new_dir) if relative else new_abs
        for md in modifiers:
            if md.filepath == item.path:
                changes.append((md, "filepath", md.filepath, _rel(new_abs, old_dir) if relative else new_abs,
                                as_new))
        if settings.baked_file == item.path:
            changes.append((settings, "baked_file", item.path, as_new, as_new))
        changes.append((item, "path", item.path, as_new, as_new))
    changes.append((settings, "baked_blend", settings.baked_blend, new_blend, new_blend))


@bpy.app.handlers.persistent
def copy_caches_on_save_as(filepath, *_):
    """save_pre: a save to another .blend copies every baked sheet's files for it."""
    _pending.clear()  # a save that failed after its save_pre never reached save_post
    old = bpy.data.filepath
    if not old or not filepath or os.path.realpath(old) == os.path.realpath(filepath):
        return
    changes = []
    for obj, settings in _sheets():
        _copy_bake(obj, settings, old, filepath, changes)
    for target, attr, _, before_save, _ in changes:
        setattr(target, attr, before_save)
    _pending.append((filepath, changes))


def drop_superseded(obj, settings) -> list:
    """The sheet's recorded files that none of its cache modifiers plays any more (a bake the
    re-bake beside it replaced, inputs.cache_path): deleted once the .blend that baked them is
    saved, since the file on disk then plays the new bake. Returns what went."""
    if not materials.owns_cache(settings):
        return []
    played = {bpy.path.abspath(md.filepath) for md in _cache_modifiers(obj, settings) if md.filepath}
    if not played:  # no modifier to go by (an artist's own setup): keep everything
        return []
    stale = [i for i, item in enumerate(settings.baked_files) if bpy.path.abspath(item.path) not in played]
    gone = []
    materials.remove_files({bpy.path.abspath(settings.baked_files[i].path) for i in stale}, gone)
    for index in reversed(stale):  # from the end, so the indices before it stay put
        settings.baked_files.remove(index)
    return gone


@bpy.app.handlers.persistent
def settle_paths_after_save(filepath, *_):
    """save_post: the open file's paths as its folder sees them; after Save Copy, as before.
    A save of the open file itself then deletes the bakes it no longer plays."""
    while _pending:
        saved_to, changes = _pending.pop()
        copy = os.path.realpath(bpy.data.filepath) != os.path.realpath(saved_to)
        for target, attr, old_value, _, as_new in changes:
            try:
                setattr(target, attr, old_value if copy else as_new)
            except ReferenceError:  # removed meanwhile
                pass
    if filepath and bpy.data.filepath and os.path.realpath(filepath) == os.path.realpath(bpy.data.filepath):
        for obj, settings in list(_sheets()):
            drop_superseded(obj, settings)


def register():
    bpy.app.handlers.save_pre.append(copy_caches_on_save_as)
    bpy.app.handlers.save_post.append(settle_paths_after_save)


def unregister():
    for handlers, fn in ((bpy.app.handlers.save_pre, copy_caches_on_save_as),
                         (bpy.app.handlers.save_post, settle_paths_after_save)):
        if fn in handlers:
            handlers.remove(fn)
