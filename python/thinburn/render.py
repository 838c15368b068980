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

    second_view=(elev, azim) draws a second 3-D view instead of the top view (for shells on
    their own surface, which have no N x N grid: a lantern from its lit and its far side); it
    also shades the faces by their normals (a curved shell reads as curved) and draws the fire
    particles behind the shell's centre before the shell, so the shell hides them.
    """

    def __init__(self, faces, first_positions, material="paper", floor=None, width_px=960,
                 height_px=480, elev=32.0, azim=-58.0, pad=0.35, second_view=None,
                 labels=("", "")):
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
        self.centre = centre
        self.limits = [(c - (0.5 + pad) * span, c + (0.5 + pad) * span) for c in centre]
        if floor is not None:
            self.limits[2] = (floor - 0.02 * span, floor + (1.0 + pad) * span)
        self.fig = plt.figure(figsize=(width_px / 100, height_px / 100), dpi=100)
        self.view = (elev, azim)
        self.second_view = None if second_view is None else tuple(second_view)
        self.labels = labels
        if self.second_view is None:
            self.ax3 = self.fig.add_axes([0.0, 0.0, 0.62, 1.0], projection="3d")
            self.ax2 = self.fig.add_axes([0.64, 0.06, 0.34, 0.84])
        else:
            self.ax3 = self.fig.add_axes([0.0, 0.0, 0.5, 0.94], projection="3d")
            self.ax2 = self.fig.add_axes([0.5, 0.0, 0.5, 0.94], projection="3d")
            self.ax2.computed_zorder = False
        # Draw in the order added (table, sheet, flames): mplot3d's per-collection depth sort
        # puts a large table polygon in front of the sheet lying on it.
        self.ax3.computed_zorder = False

    def frame(self, positions, vertex_char, vertex_state, cell_img=None, particles=None, title=""):
        """One picture (H, W, 3) uint8. cell_img: the top view of the cells (ignored, and
        may be None, with a second 3-D view)."""
        shells = self.second_view is not None
        self._draw3d(self.ax3, self.view, positions, vertex_char, vertex_state, particles, shells)
        if shells:
            self._draw3d(self.ax2, self.second_view, positions, vertex_char, vertex_state,
                         particles, shells)
            for t in list(self.fig.texts):
                t.remove()
            self.fig.text(0.5, 0.965, title, ha="center", va="center", fontsize=10)
            for x, label in zip((0.25, 0.75), self.labels):
                if label:
                    self.fig.text(x, 0.92, label, ha="center", va="center", fontsize=8,
                                  color=(0.35, 0.35, 0.35))
        else:
            self.ax2.cla()
            self.ax2.set_axis_off()
            self.ax2.imshow(cell_img)
            self.ax2.set_title(title, fontsize=9)
        self.fig.canvas.draw()
        buf = np.asarray(self.fig.canvas.buffer_rgba())
        return buf[..., :3].copy()

    def _draw3d(self, ax, view, positions, vertex_char, vertex_state, particles, shells):
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        ax.cla()
        ax.set_axis_off()
        ax.view_init(*view)
        ax.set_xlim(*self.limits[0])
        ax.set_ylim(*self.limits[1])
        ax.set_zlim(*self.limits[2])
        ax.set_box_aspect([hi - lo for lo, hi in self.limits])
        if self.floor is not None:
            (x0, x1), (y0, y1) = self.limits[0], self.limits[1]
            table = [[(x0, y0, self.floor), (x1, y0, self.floor), (x1, y1, self.floor), (x0, y1, self.floor)]]
            ax.add_collection3d(Poly3DCollection(table, facecolors=(0.55, 0.42, 0.3, 1.0), zorder=0))
        rgb = char_colours(vertex_char, vertex_state, self.material).astype(float) / 255.0
        face_rgb = rgb[self.faces].mean(axis=1)
        tris = positions[self.faces]
        if shells:
            face_rgb = face_rgb * self._shade(tris, view, vertex_state)[:, None]
        # Faces whose three vertices are burnt out are ash that fell away: draw them faint.
        gone = np.all(vertex_state[self.faces] == 2, axis=1) & np.all(vertex_char[self.faces] >= 1.0, axis=1)
        alpha = np.where(gone, 0.18, 1.0)
        order = np.argsort(-self._depth(tris.mean(axis=1), view))  # painter's order within the sheet
        colours = np.column_stack([face_rgb, alpha])[order]
        if shells:
            # Edges in the face colour close the anti-aliasing seams that let the far wall of a
            # closed shell show through its near wall as a grid of dots; ash faces get none
            # (their overlapping faint edges would draw a wireframe).
            edges = colours.copy()
            edges[gone[order], 3] = 0.0
            coll = Poly3DCollection(tris[order], facecolors=colours, edgecolors=edges,
                                    linewidths=0.4, zorder=1)
        else:
            coll = Poly3DCollection(tris[order], facecolors=colours, linewidths=0, zorder=1)
        ax.add_collection3d(coll)
        if particles is not None and len(particles[1]):
            p, t = particles
            colours = _temperature_colours(t)
            if shells:
                # Behind the shell's centre: drawn first, so the shell in front hides them.
                behind = self._depth(p, view) > self._depth(self.centre[None], view)[0]
                groups = ((behind, 0.5), (~behind, 2))
            else:
                groups = ((np.ones(len(t), bool), 2),)
            for mask, z in groups:
                if np.any(mask):
                    ax.scatter(p[mask, 0], p[mask, 1], p[mask, 2], c=colours[mask], s=4,
                               depthshade=False, linewidths=0, zorder=z)

    @staticmethod
    def _eye(view):
        elev, azim = np.radians(view[0]), np.radians(view[1])
        return np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])

    def _shade(self, tris, view, vertex_state):
        """Per-face brightness: two-sided diffuse light from above the camera, so each view is
        lit; glowing (burning) faces are not darkened."""
        n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
        light = self._eye(view) + np.array([0.0, 0.0, 0.8])
        light /= np.linalg.norm(light)
        shade = 0.45 + 0.55 * np.abs(n @ light)
        glowing = np.any(vertex_state[self.faces] == 1, axis=1)
        return np.where(glowing, 1.0, shade)

    def _depth(self, pts, view=None):
        """Distance along the viewing direction (larger = farther from the camera)."""
        return -pts @ self._eye(self.view if view is None else view)

    def close(self):
        self.plt.close(self.fig)
