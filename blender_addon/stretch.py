"""How far a bake stretched the sheet's edges, and a warning when it went too far. No bpy here.

Paper and cloth hardly stretch: an edge of the mesh that grows to 1.5× its rest length (or
shrinks to half) in a baked frame means the motion misbehaved there (a lattice too coarse for
the shell's shape, or more crumpling than its couples can carry). The bake's worker measures
every edge in every frame (worker.py, ``edge_strains``), and the meter keeps per edge the
largest strain and its frame; edges between burnt-out vertices (holes, ash) do not count. An
edge across a crease of the lattice is a chord, far shorter than the sheet under it: for such
edges the worker measures the length along the surface, and that counts.
"""
from __future__ import annotations

import numpy as np

WARN_STRAIN = 0.5  # |length / rest length - 1| above which the bake's report warns
# Edges whose chords strain past this are measured along the surface as well (worker.py,
# edge_strains), so the report and the Bake panel's "edge lengths changed up to" are the sheet's.
ALONG_FROM = 0.01


def chord_strains(positions: np.ndarray, a: np.ndarray, b: np.ndarray, rest: np.ndarray) -> np.ndarray:
    """l / L - 1 per edge (a[i], b[i]) of rest length rest[i] (< 0: shorter): np.take and
    einsum, a third of fancy indexing and norm's time on a 16k mesh's 48k edges (a probe)."""
    d = np.take(positions, a, axis=0)
    d -= np.take(positions, b, axis=0)
    strain = np.sqrt(np.einsum("ij,ij->i", d, d))
    strain /= rest
    strain -= 1.0
    return strain


class StretchMeter:
    """Per edge of the mesh, the largest |length / rest - 1| over the frames fed to it, and
    whether the edge was longer or shorter then (an artist told "stretched" of a cloth whose
    edges had shrunk to a third looked for the wrong fault)."""

    def __init__(self, rest: np.ndarray, edges: np.ndarray):
        rest = np.asarray(rest, dtype=np.float64)
        edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
        length = np.linalg.norm(rest[edges[:, 0]] - rest[edges[:, 1]], axis=1)
        keep = length > 1e-9  # a zero-length edge (merged vertices) has no strain
        self.edges = edges[keep]
        self.rest = length[keep]
        self.ends = (np.ascontiguousarray(self.edges[:, 0]), np.ascontiguousarray(self.edges[:, 1]))
        self.worst = np.zeros(len(self.edges))
        self.worst_signed = np.zeros(len(self.edges))  # length / rest - 1 at the worst frame
        self.worst_frame = np.zeros(len(self.edges))
        self.creased = 0  # the most edges in a frame measured along the surface, not as chords
        self.turn, self.turn_frame = 0.0, None  # the lattice's largest turn between couples (degrees)

    def add(self, positions: np.ndarray, frame: float) -> None:
        """One frame's positions, every edge measured as a chord."""
        p = np.asarray(positions, dtype=np.float64)
        self.add_strains(chord_strains(p, *self.ends, self.rest), 0, frame)

    def add_strains(self, strain: np.ndarray, creased: int, frame: float) -> None:
        """One frame's l/L - 1 per edge (< 0: shorter), `creased` of them measured along the
        surface (the bake's worker: worker.CoreWorker.edge_strains)."""
        self.creased = max(self.creased, int(creased))
        size = np.abs(strain)
        more = size > self.worst
        self.worst[more] = size[more]
        self.worst_signed[more] = strain[more]
        self.worst_frame[more] = frame

    def add_turn(self, turn: float, frame: float) -> None:
        """One frame's largest turn of the motion lattice between neighbouring couples."""
        if turn > self.turn:
            self.turn, self.turn_frame = float(turn), frame

    def largest(self, burnout_frames=None) -> tuple:
        """(|strain|, frame) of the most strained edge; with ``burnout_frames`` (per vertex), an
        edge counts only while one of its vertices has not burnt out."""
        strain, frame = self.largest_signed(burnout_frames)
        return abs(strain), frame

    def largest_signed(self, burnout_frames=None) -> tuple:
        """(length / rest - 1, frame) of the most strained edge (< 0: it shrank), as largest."""
        worst = self.worst
        if burnout_frames is not None and len(worst):
            b = np.asarray(burnout_frames, dtype=np.float64)
            gone = np.maximum(b[self.edges[:, 0]], b[self.edges[:, 1]])  # both burnt out
            worst = np.where(self.worst_frame < gone, worst, 0.0)
        if not len(worst) or not np.any(worst > 0):
            return 0.0, None
        k = int(np.argmax(worst))
        return float(self.worst_signed[k]), float(self.worst_frame[k])


def _motion_detail(lattice: int) -> str:
    """Motion Detail as the panel shows it."""
    return "0: the core's choice" if lattice == 0 else f"{lattice}"


def stretch_warning(name: str, strain: float, frame, lattice: int, crumple=None, fit=None,
                    couples=None) -> str | None:
    """The report's words for a bake that stretched or squashed an edge by more than WARN_STRAIN
    (strain: length / rest - 1 of the worst edge, < 0 where it shrank). crumple:
    the Crumple Amount baked (None: unknown); fit: the core's lattice fit (how far, in half
    layer thicknesses, the mesh lies off its curved shell's lattice; None or 0 on a flat one);
    couples: how many the lattice had (for a Motion Detail to suggest)."""
    if frame is None or abs(strain) <= WARN_STRAIN:
        return None
    motion = _motion_detail(lattice)
    if strain > 0.0:
        text = (f"'{name}' stretched: an edge reached {1.0 + strain:.1f}× its rest length at frame "
                f"{frame:.0f} (a sheet hardly stretches), so the motion misbehaved there. ")
    else:
        text = (f"'{name}' squashed: an edge shrank to {1.0 + strain:.2f}× its rest length at frame "
                f"{frame:.0f} (a sheet hardly shrinks), so the motion misbehaved there. ")
    finer = finer_detail(lattice, couples)
    if fit is not None and fit > 1.0:
        text += (f"Its mesh has detail finer than the motion lattice (pleats, waves, folds up to "
                 f"{fit:.1f} half layer-thicknesses off it): set Motion Detail (now {motion}) higher{finer}")
    else:
        text += (f"A lattice too coarse for the shape it takes (an edge of a collider, a tight fold) "
                 f"is the usual cause: set Motion Detail (now {motion}) higher{finer}")
    if crumple is None or crumple > 0.3:
        text += ", lower Crumple Amount (ThinBurn > Motion; e.g. 0.3)"
    return text + ", or switch Crumple off to burn the sheet in its rest shape"


# From this turn between neighbouring couples on the mesh follows the couples wholly
# (FoldBlend::kTo in cpp/fold_blend.hpp, not bound: keep the two equal; docs/lattice.md): its
# folds are creases on the lattice's lines.
CREASE_TURN = 40.0


def finer_detail(lattice: int, couples) -> str:
    """", e.g. N": twice the couples per side the bake had (at least 9), or "" when unknown.
    Motion Detail counts couples along the square root of the area: twice as many per side as
    the core chose (or as set) halves their spacing. A fixed suggestion ("such as 9") named the
    lattice the core had already chosen for a 48-cell sheet, which changed nothing."""
    per_side = lattice if lattice > 0 else (couples or 0) ** 0.5
    return f", e.g. {max(9, int(round(2 * per_side)))}" if per_side > 0 else ""


def crease_note(name: str, turn: float, frame, lattice: int, couples=None) -> str | None:
    """The report's note for a bake whose motion lattice folded sharply where the sheet had not
    burnt: its folds show as creases on the lattice's lines (an artist's cloth on a 10 cm ball
    at the default lattice folded through 128 degrees into a four-sided tent). None below
    CREASE_TURN."""
    if frame is None or turn < CREASE_TURN:
        return None
    motion = _motion_detail(lattice)
    return (f"'{name}' folded sharply on its motion lattice (up to {turn:.0f}° between neighbouring "
            f"couples, frame {frame:.0f}), so its folds show as creases along the lattice's lines: "
            f"for finer, rounder folds set Motion Detail (now {motion}) higher{finer_detail(lattice, couples)} "
            "(the bake takes longer)")
