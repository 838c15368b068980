#!/usr/bin/env python3
"""Build the installable ThinBurn extension: dist/thinburn-<version>.zip.

    python scripts/build_addon.py                    # build the wheel here, zip the add-on
    python scripts/build_addon.py --wheel W1 --wheel W2   # bundle wheels built elsewhere

Steps: ``pip wheel . --no-deps`` builds the thinburn wheel with the interpreter given by
``--python`` (default: this one); the wheel goes to blender_addon/wheels/; a copy of
blender_manifest.toml listing the wheels and their platforms goes into the zip with the
add-on's files.

Other platforms and Python versions: the wheel must match Blender's Python (3.11 for Blender
4.2 to 5.0) and the platform. Either run this script on that platform with a CPython 3.11
(``--python /path/to/python3.11``), or build wheels elsewhere (e.g. cibuildwheel with
CIBW_BUILD=cp311-*) and pass each with ``--wheel``; one zip can carry several platforms.
"""
from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ADDON = ROOT / "blender_addon"
SKIP_DIRS = {"__pycache__", "wheels"}

# Wheel platform tag (its tail) -> Blender extension platform.
PLATFORMS = (
    (re.compile(r"(manylinux|musllinux|linux).*_x86_64$"), "linux-x64"),
    (re.compile(r"(manylinux|musllinux|linux).*_aarch64$"), "linux-arm64"),
    (re.compile(r"macosx_.*_(arm64|universal2)$"), "macos-arm64"),
    (re.compile(r"macosx_.*_x86_64$"), "macos-x64"),
    (re.compile(r"win_amd64$"), "windows-x64"),
    (re.compile(r"win_arm64$"), "windows-arm64"),
)


def project_version() -> str:
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    match = re.search(r'^\[project\][^\[]*?^version\s*=\s*"([^"]+)"', text, re.M | re.S)
    if not match:
        sys.exit("build_addon: no version in pyproject.toml [project]")
    return match.group(1)


def wheel_platform(wheel: Path) -> str:
    """The Blender platform of a wheel, from the platform tag in its file name."""
    tag = wheel.name[:-len(".whl")].split("-")[-1]
    if tag == "any":
        return ""
    for pattern, platform in PLATFORMS:
        if any(pattern.search(t) for t in tag.split(".")):
            return platform
    sys.exit(f"build_addon: no Blender platform for the wheel tag {tag!r} ({wheel.name})")


BUILD_REQUIRES = ("scikit_build_core", "pybind11", "cmeel")


def has_build_requires(python: str) -> bool:
    """Whether `python` can build the wheel without an isolated build environment."""
    probe = "import " + ", ".join(BUILD_REQUIRES)
    return subprocess.run([python, "-c", probe], capture_output=True).returncode == 0


def build_wheel(python: str, out: Path, isolation: bool) -> Path:
    cmd = [python, "-m", "pip", "wheel", str(ROOT), "--no-deps", "-w", str(out)]
    if not isolation and has_build_requires(python):
        cmd.append("--no-build-isolation")  # reuses build/{wheel_tag}: incremental
    print("+", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    wheels = sorted(out.glob("thinburn-*.whl"))
    if len(wheels) != 1:
        sys.exit(f"build_addon: expected one thinburn wheel in {out}, found {wheels}")
    return wheels[0]


def manifest_text(version: str, wheels: list, platforms: list) -> str:
    """blender_manifest.toml with version, wheels and platforms filled in (top-level keys)."""
    text = (ADDON / "blender_manifest.toml").read_text(encoding="utf-8")
    text = re.sub(r'^version\s*=\s*"[^"]*"', f'version = "{version}"', text, count=1, flags=re.M)
    extra = "wheels = [\n" + "".join(f'  "./wheels/{w}",\n' for w in wheels) + "]\n"
    if platforms:
        extra += "platforms = [" + ", ".join(f'"{p}"' for p in platforms) + "]\n"
    first_table = re.search(r"^\[", text, re.M)
    cut = first_table.start() if first_table else len(text)
    return text[:cut] + extra + "\n" + text[cut:]


def write_zip(target: Path, manifest: str, wheels: list) -> None:
    target.parent.mkdir(parents=True, exist_ok=True)
    partial = target.with_suffix(".zip.partial")
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as zf:
        for path in sorted(ADDON.rglob("*")):
            rel = path.relative_to(ADDON)
            if path.is_dir() or SKIP_DIRS & set(rel.parts) or path.suffix in {".pyc", ".zip"}:
                continue
            if rel.as_posix() == "blender_manifest.toml":
                continue
            zf.write(path, rel.as_posix())
        zf.writestr("blender_manifest.toml", manifest)
        for wheel in wheels:
            zf.write(ADDON / "wheels" / wheel, f"wheels/{wheel}")
    os.replace(partial, target)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--wheel", action="append", type=Path, default=[],
                    help="bundle this thinburn wheel instead of building one (repeat for platforms)")
    ap.add_argument("--python", default=sys.executable,
                    help="interpreter that builds the wheel; must be the Python of the target "
                         "Blender (3.11 for 4.2 to 5.0)")
    ap.add_argument("--build-isolation", action="store_true",
                    help="let pip build in an isolated environment (default: use the installed "
                         "scikit-build-core, pybind11, cmeel-eigen when they are there)")
    ap.add_argument("--out", type=Path, default=ROOT / "dist", help="folder of the zip")
    args = ap.parse_args(argv)

    version = project_version()
    wheel_dir = ADDON / "wheels"
    wheel_dir.mkdir(exist_ok=True)
    for old in wheel_dir.glob("*.whl"):
        old.unlink()
    sources = list(args.wheel)
    with tempfile.TemporaryDirectory(prefix="thinburn-wheel-") as tmp:
        if not sources:
            sources = [build_wheel(args.python, Path(tmp), args.build_isolation)]
        names = []
        for wheel in sources:
            if not wheel.name.startswith(f"thinburn-{version}-"):
                sys.exit(f"build_addon: {wheel.name} is not thinburn {version}")
            shutil.copy2(wheel, wheel_dir / wheel.name)
            names.append(wheel.name)
    platforms = sorted({p for p in (wheel_platform(wheel_dir / n) for n in names) if p})
    target = args.out / f"thinburn-{version}.zip"
    write_zip(target, manifest_text(version, names, platforms), names)
    print(f"wrote {target} (wheels: {', '.join(names)}; platforms: {', '.join(platforms) or 'any'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
