"""ThinBurn for Blender: bake a burning sheet (paper, cloth, silk) from keyframed igniters.

A Blender 4.2+ extension (blender_manifest.toml) that also works as a legacy add-on: this
package has ``bl_info``, ``register()`` and ``unregister()``. The simulation is the
``thinburn`` package, bundled as a wheel in the extension (scripts/build_addon.py).
"""

bl_info = {
    "name": "ThinBurn",
    "author": "thinburn contributors",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "Properties > Physics > ThinBurn",
    "description": "Bake burning thin sheets (Liu et al. 2009) to a PC2 cache and attributes",
    "category": "Physics",
}

_MODULES = ("properties", "operators", "saving", "quick", "panels", "usd_export", "scene_export")


def _modules():
    try:
        import thinburn  # noqa: F401  (the core; bundled as a wheel in the extension)
    except ImportError as exc:
        raise ImportError(
            "ThinBurn needs the 'thinburn' Python package. Install the extension zip built by "
            "scripts/build_addon.py, or pip-install the thinburn wheel into Blender's Python "
            f"when using the add-on in legacy mode ({exc})") from exc
    import importlib
    return [importlib.import_module(f"{__package__}.{name}") for name in _MODULES]


def register():
    for module in _modules():
        module.register()


def unregister():
    for module in reversed(_modules()):
        module.unregister()
