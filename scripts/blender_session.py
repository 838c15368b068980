"""The add-on of this checkout in headless Blender (bpy from PyPI), for the scripts that drive it."""
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ADDON_NAME = "thinburn_addon"


def enable_addon(user_dir: Path):
    """Load bpy with throwaway user folders and enable the add-on from this checkout; returns its module."""
    os.environ["BLENDER_USER_RESOURCES"] = str(user_dir)
    addons = user_dir / "scripts" / "addons"
    addons.mkdir(parents=True)
    (addons / ADDON_NAME).symlink_to(ROOT / "blender_addon", target_is_directory=True)
    import bpy  # noqa: F401  (first: it puts Blender's modules on the path)
    import addon_utils

    def fail(exc):
        raise exc

    addon_utils.enable(ADDON_NAME, default_set=True, handle_error=fail)
    return sys.modules[ADDON_NAME]
