"""Fixtures for the tests that run the add-on in real Blender (bpy from PyPI).

Every test module here starts with ``pytest.importorskip("bpy")``, so the suite skips where
bpy is absent. Blender's user folders (preferences, add-ons, extensions) go to a throwaway
folder, set before bpy loads; the add-on is enabled as a legacy add-on from there (a link
to blender_addon/), and the scene is reset around each test.
"""
from __future__ import annotations

import os
import shutil
import sys
import tempfile
from pathlib import Path

import pytest

from blender_helpers import ADDON_NAME, ROOT, disable_legacy, enable_legacy

_USER = Path(tempfile.mkdtemp(prefix="thinburn-blender-user-"))
os.environ["BLENDER_USER_RESOURCES"] = str(_USER)
(_USER / "scripts" / "addons").mkdir(parents=True)
(_USER / "scripts" / "addons" / ADDON_NAME).symlink_to(ROOT / "blender_addon", target_is_directory=True)


def pytest_sessionfinish(session, exitstatus):
    shutil.rmtree(_USER, ignore_errors=True)


@pytest.fixture(scope="session")
def addon():
    """The add-on package, enabled (legacy mode)."""
    pytest.importorskip("bpy")
    module = enable_legacy()
    yield module
    disable_legacy()


@pytest.fixture(autouse=True)
def clean_scene(request):
    """An empty scene before and after each test."""
    if "bpy" not in sys.modules:
        yield
        return
    import bpy
    bpy.ops.wm.read_homefile(use_empty=True)
    yield
    bpy.ops.wm.read_homefile(use_empty=True)
