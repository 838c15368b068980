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


def _temperature_colours(temps: np.ndarray) -> np.ndarray:
    """RGBA per particle: deep red when cool, through orange, to yellow-white when hot."""
    t = np.clip(np.asarray(temps, float) / 900.0, 0, 1)
    keys = np.array([0.0, 0.3, 0.6, 1.0])
    rgb = np.array([[0.45, 0.05, 0.0], [0.9, 0.25, 0.02], [1.0, 0.6, 0.1], [1.0, 0.95, 0.7]])
    out = np.stack([np.interp(t, keys, rgb[:, k]) for k in range(3)] + [0.15 + 0.6 * t], axis=1)
    return out


class SceneRenderer:
    """Draws the deformed, charred sheet in 3-D beside a top view of its cells.

    The 3-D axes keep fixed limits (from the scene's first frame, padded) so the motion
    reads frame to frame. Burnt-out faces are drawn see-through, so the sheet burns through.
    """

    def __init__(self, faces, first_positions, material="paper", floor=None, width_px=960,
                 height_px=480, elev=32.0, azim=-58.0, pad=0.35):
        import matplotlib

        matplotlib.use("Agg")
        from matplotlib import pyplot as plt

        self.plt = plt
        self.faces = np.asarray(faces)
        self.material = material
        self.floor = floor
        lo, hi = first_positions.min(0), first_positions.max(0)
        span = float(np.max(hi - lo))
        centre = 0.5 * (lo + hi)
        self.limits = [(c - (0.5 + pad) * span, c + (0.5 + pad) * span) for c in centre]
        if floor is not None:
            self.limits[2] = (floor - 0.02 * span, floor + (1.0 + pad) * span)
        self.fig = plt.figure(figsize=(width_px / 100, height_px / 100), dpi=100)
        self.ax3 = self.fig.add_axes([0.0, 0.0, 0.62, 1.0], projection="3d")
        self.ax2 = self.fig.add_axes([0.64, 0.06, 0.34, 0.84])
        self.view = (elev, azim)

    def frame(self, positions, vertex_char, vertex_state, cell_img, particles=None, title=""):
        """One picture (H, W, 3) uint8."""
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        ax = self.ax3
        ax.cla()
        ax.set_axis_off()
        ax.view_init(*self.view)
        ax.set_xlim(*self.limits[0])
        ax.set_ylim(*self.limits[1])
        ax.set_zlim(*self.limits[2])
        ax.set_box_aspect([hi - lo for lo, hi in self.limits])
        if self.floor is not None:
            (x0, x1), (y0, y1) = self.limits[0], self.limits[1]
            table = [[(x0, y0, self.floor), (x1, y0, self.floor), (x1, y1, self.floor), (x0, y1, self.floor)]]
            ax.add_collection3d(Poly3DCollection(table, facecolors=(0.55, 0.42, 0.3, 1.0)))
        rgb = char_colours(vertex_char, vertex_state, self.material).astype(float) / 255.0
        face_rgb = rgb[self.faces].mean(axis=1)
        # Faces whose three vertices are burnt out are ash that fell away: draw them faint.
        gone = np.all(vertex_state[self.faces] == 2, axis=1) & np.all(vertex_char[self.faces] >= 1.0, axis=1)
        alpha = np.where(gone, 0.18, 1.0)
        tris = positions[self.faces]
        coll = Poly3DCollection(tris, facecolors=np.column_stack([face_rgb, alpha]), linewidths=0)
        ax.add_collection3d(coll)
        if particles is not None and len(particles[1]):
            p, t = particles
            ax.scatter(p[:, 0], p[:, 1], p[:, 2], c=_temperature_colours(t), s=4, depthshade=False,
                       linewidths=0)
        self.ax2.cla()
        self.ax2.set_axis_off()
        self.ax2.imshow(cell_img)
        self.ax2.set_title(title, fontsize=9)
        self.fig.canvas.draw()
        buf = np.asarray(self.fig.canvas.buffer_rgba())
        return buf[..., :3].copy()

    def close(self):
        self.plt.close(self.fig)
