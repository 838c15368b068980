"""Regenerate the README's pictures from the demo: `python scripts/readme_images.py`.

Runs `python -m thinburn demo` for the given materials into a scratch folder and tiles four
of its frames (a quarter, half, three quarters and the end of the burn) into
docs/images/demo_<material>.png. Names of shell scenes (`lantern`, `sphere`, `letter`: `demo
--scene NAME`, paper) tile the frames nearest fixed times instead (SHELL_TIMES; the shells
crumple and burn on slowly long after the far side has caught) into docs/images/demo_<scene>.png
and print when the vertex opposite the lit point ignited. With no names: the three materials;
`python scripts/readme_images.py lantern sphere` makes the shells' pictures only.
"""
from __future__ import annotations

import argparse
import os
import tempfile

import numpy as np
from PIL import Image

from thinburn.demo import SHELL_SCENES, run_demo, shell_scene

# Simulated times (s) of the four tiles per shell scene: the far side of the lantern and of the
# sphere (pi r = 31 cm away) is due at about pi r / V0 = 90 s at the paper's 3.5 mm/s.
SHELL_TIMES = {"lantern": (20.0, 45.0, 70.0, 95.0), "sphere": (20.0, 45.0, 70.0, 87.0),
               "letter": (15.0, 35.0, 60.0, 90.0)}


def tile(frame_dir: str, out: str, times=None) -> None:
    names = sorted(f for f in os.listdir(frame_dir) if f.endswith(".png"))
    if times is None:
        picks = [names[int(round(q * (len(names) - 1)))] for q in (0.15, 0.4, 0.65, 0.9)]
    else:  # the frames nearest the given simulated times (frames.npz beside the frames)
        with np.load(os.path.join(os.path.dirname(frame_dir), "frames.npz")) as f:
            frame_times = f["time"]
        picks = [names[int(np.argmin(np.abs(frame_times - t)))] for t in times]
    ims = [np.asarray(Image.open(os.path.join(frame_dir, n)).convert("RGB")) for n in picks]
    h, w, _ = ims[0].shape
    grid = np.full((2 * h, 2 * w, 3), 255, np.uint8)
    for k, im in enumerate(ims):
        grid[(k // 2) * h:(k // 2 + 1) * h, (k % 2) * w:(k % 2 + 1) * w] = im
    img = Image.fromarray(grid)
    img.thumbnail((1400, 1400))
    img.save(out, optimize=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("materials", nargs="*", default=["paper", "cloth", "curtain"])
    args = ap.parse_args()
    for material in args.materials:
        if material in SHELL_SCENES:
            shell(material)
            continue
        with tempfile.TemporaryDirectory() as tmp:
            run_demo(tmp, material=material, frames=40, quiet=True)
            out = os.path.join("docs", "images", f"demo_{material}.png")
            tile(os.path.join(tmp, "frames"), out)
            print("wrote", out)


def shell(name: str) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        summary = run_demo(tmp, material="paper", frames=60, quiet=True, scene=name)
        out = os.path.join("docs", "images", f"demo_{name}.png")
        tile(os.path.join(tmp, "frames"), out, SHELL_TIMES[name])
        with np.load(os.path.join(tmp, "frames.npz")) as f:
            t = f["vertex_ignition_times"]
        scene = shell_scene(name)
        src = np.asarray(scene.ignite_at)
        v = scene.vertices
        if name in ("lantern", "sphere"):
            axis_point = np.array([0.0, 0.0, src[2]])  # opposite = mirrored through the axis
            far = int(np.argmin(np.linalg.norm(v - (2 * axis_point - src), axis=1)))
            done = np.isfinite(t)
            print(f"{name}: opposite vertex ignited at {t[far]:.1f} s (pi r / V0 = "
                  f"{np.pi * 0.1 / 0.0035:.1f} s); later than {100 * np.mean(t[done] < t[far]):.1f} % "
                  f"of the ignited vertices; {100 * np.mean(done):.1f} % ignited, "
                  f"{100 * summary['burnt_fraction']:.1f} % of cells burnt at "
                  f"{summary['simulated_seconds']:.0f} s")
        print("wrote", out)


if __name__ == "__main__":
    main()
