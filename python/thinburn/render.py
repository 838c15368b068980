"""Pictures of a burning sheet: the char colour ramp, top views, 3-D views and GIFs.

The ramp follows a cell through its life: unburnt material, scorched (brown, pre-heated
by the nearby fire), a glowing edge while it burns (yellow-white to orange to deep red),
and black char when burnt.
"""
from __future__ import annotations

import numpy as np

# Unburnt colours per preset (sRGB 0..255); anything else gets paper white.
BASE_COLOURS = {
    "paper": (244, 238, 222),
    "hard_paper": (214, 196, 160),
    "cloth": (205, 196, 178),
    "silk": (232, 222, 238),
    "curtain": (150, 42, 46),
}
SCORCH = np.array([139, 90, 43], float)
CHAR = np.array([26, 22, 20], float)
# Glow keys along the burn (char fraction 0..1 while burning).
_GLOW_T = np.array([0.0, 0.12, 0.35, 0.7, 1.0])
_GLOW_RGB = np.array([[255, 236, 160], [255, 170, 40], [230, 80, 10], [110, 22, 6], CHAR], float)
BACKGROUND = (58, 60, 66)


def _blur(a: np.ndarray, passes: int) -> np.ndarray:
    """Cheap separable box blur (edge-clamped) used for the scorch halo."""
    out = a.astype(float)
    for _ in range(passes):
        p = np.pad(out, 1, mode="edge")
        out = (p[:-2, 1:-1] + p[2:, 1:-1] + p[1:-1, :-2] + p[1:-1, 2:] + p[1:-1, 1:-1]) / 5.0
    return out


def char_colours(char, states, material: str = "paper", scorch=None) -> np.ndarray:
    """RGB (uint8) per cell or vertex from char in [0, 1] and states (0/1/2).

    scorch (same shape, 0..1) browns unburnt material near the fire; None means none.
    """
    char = np.asarray(char, float)
    states = np.asarray(states)
    base = np.array(BASE_COLOURS.get(material, BASE_COLOURS["paper"]), float)
    rgb = np.broadcast_to(base, char.shape + (3,)).copy()
    if scorch is not None:
        s = np.clip(np.asarray(scorch, float), 0, 1)[..., None] * 0.75
        rgb = rgb * (1 - s) + SCORCH * s
    burning = states == 1
    if np.any(burning):
        c = np.clip(char[burning], 0, 1)
        rgb[burning] = np.stack([np.interp(c, _GLOW_T, _GLOW_RGB[:, k]) for k in range(3)], axis=1)
    rgb[states == 2] = CHAR
    return np.clip(rgb, 0, 255).astype(np.uint8)


def cell_image(states, char, inside, material="paper", aspect=1.0, width=480) -> np.ndarray:
    """A top view (H, W, 3) uint8 of the cell grid, v up, u to the right.

    aspect is the sheet's height/width, so non-square sheets keep their shape.
    """
    states = np.asarray(states)
    fire = (states > 0).astype(float)
    scorch = np.clip(_blur(fire, 6) * 3.0, 0, 1) * (states == 0)
    rgb = char_colours(char, states, material, scorch)
    rgb[np.asarray(inside) == 0] = BACKGROUND
    img = rgb[::-1]  # rows grow along v, which points up on screen
    n_rows, n_cols = img.shape[:2]
    height = max(1, int(round(width * aspect)))
    ri = np.minimum((np.arange(height) * n_rows) // height, n_rows - 1)
    ci = np.minimum((np.arange(width) * n_cols) // width, n_cols - 1)
    return img[ri][:, ci]


def save_png(img: np.ndarray, path) -> None:
    from PIL import Image

    Image.fromarray(img).save(path)


def save_gif(frames, path, fps: float = 12.0) -> None:
    """An animated GIF from a list of (H, W, 3) uint8 frames."""
    from PIL import Image

    ims = [Image.fromarray(f) for f in frames]
    ims[0].save(path, save_all=True, append_images=ims[1:], duration=int(1000 / fps), loop=0,
                optimize=False)
