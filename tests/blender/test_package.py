"""The installable zip: built by scripts/build_addon.py, valid for Blender, installs and
registers as an extension (with its bundled thinburn wheel)."""
from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

bpy = pytest.importorskip("bpy")
pytestmark = pytest.mark.blender

from blender_helpers import ROOT, disable_legacy, enable_legacy  # noqa: E402


def _can_build_offline():
    import importlib.util
    return all(importlib.util.find_spec(m) for m in ("scikit_build_core", "pybind11", "cmeel"))


@pytest.fixture(scope="module")
def addon_zip(tmp_path_factory):
    if not _can_build_offline():
        pytest.skip("building the wheel here needs scikit-build-core, pybind11 and cmeel-eigen "
                    "installed (the build dependencies of pyproject.toml)")
    out = tmp_path_factory.mktemp("dist")
    subprocess.run([sys.executable, str(ROOT / "scripts" / "build_addon.py"), "--out", str(out)],
                   check=True, cwd=ROOT)
    zips = list(out.glob("thinburn-*.zip"))
    assert len(zips) == 1
    return zips[0]


def test_zip_holds_the_addon_the_wheel_and_a_manifest_listing_it(addon_zip):
    import tomllib
    with zipfile.ZipFile(addon_zip) as zf:
        names = set(zf.namelist())
        manifest = tomllib.loads(zf.read("blender_manifest.toml").decode())
    for part in ("__init__.py", "properties.py", "operators.py", "panels.py", "cache.py",
                 "materials.py"):
        assert part in names
    wheels = manifest["wheels"]
    assert len(wheels) == 1 and wheels[0].startswith("./wheels/thinburn-")
    assert wheels[0][2:] in names
    assert "cp311" in wheels[0] or sys.version_info[:2] != (3, 11)
    assert manifest["platforms"] == ["linux-x64"] or not sys.platform.startswith("linux")
    assert not any("__pycache__" in n for n in names)


def test_blender_validates_the_zip(addon_zip):
    cli = Path(bpy.utils.system_resource("SCRIPTS")) / "addons_core" / "bl_pkg" / "cli" / "blender_ext.py"
    run = subprocess.run([sys.executable, str(cli), "validate", str(addon_zip)],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr


def test_zip_installs_and_registers_as_an_extension(addon, addon_zip):
    disable_legacy()  # the same classes cannot be registered twice
    try:
        result = bpy.ops.extensions.package_install_files(
            filepath=str(addon_zip), repo="user_default", enable_on_install=True)
        assert result == {"FINISHED"}
        assert "bl_ext.user_default.thinburn" in bpy.context.preferences.addons
        assert hasattr(bpy.ops.thinburn, "bake")
        site = Path(bpy.utils.user_resource("EXTENSIONS")) / ".local"
        assert list(site.rglob("thinburn/simulation.py")), "the bundled wheel was not installed"
        bpy.ops.extensions.package_uninstall(repo_index=_repo_index("user_default"), pkg_id="thinburn")
        assert "bl_ext.user_default.thinburn" not in bpy.context.preferences.addons
    finally:
        enable_legacy()


def _repo_index(module):
    repos = bpy.context.preferences.extensions.repos
    return next(i for i, r in enumerate(repos) if r.module == module)
