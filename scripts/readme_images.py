"""Regenerate the README's pictures from the demo: `python scripts/readme_images.py`.

Runs `python -m thinburn demo` for the given materials into a scratch folder and tiles four
of its frames (a quarter, half, three quarters and the end of the burn) into
docs/images/demo_<material>.png.
"""
from __future__ import annotations

import argparse
import os
import tempfile

import numpy as np
from PIL import Image

from thinburn.demo import run_demo


def tile(frame_dir: str, out: str) -> None:
    names = sorted(f for f in os.listdir(frame_dir) if f.endswith(".png"))
    picks = [names[int(round(q * (len(names) - 1)))] for q in (0.15, 0.4, 0.65, 0.9)]
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
        with tempfile.TemporaryDirectory() as tmp:
            run_demo(tmp, material=material, frames=40, quiet=True)
            out = os.path.join("docs", "images", f"demo_{material}.png")
            tile(os.path.join(tmp, "frames"), out)
            print("wrote", out)


if __name__ == "__main__":
    main()
