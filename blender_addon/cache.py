"""What a bake leaves on disk and on the mesh.

The PC2 writer and reader import neither bpy nor the rest of the add-on, so they can be
tested on their own (tests/test_pc2.py). The attribute helpers take a mesh (duck-typed
``bpy.types.Mesh``) and never import bpy either.

PC2 layout (little endian), as Blender's Mesh Cache modifier reads it::

    char[12]  "POINTCACHE2\\0"
    int32     file version (1)
    int32     number of points
    float32   start frame
    float32   sample rate (frames per sample)
    int32     number of samples
    float32   x, y, z for every point of every sample, sample after sample
"""
from __future__ import annotations

import os
import struct

import numpy as np

PC2_MAGIC = b"POINTCACHE2\0"
PC2_VERSION = 1
_HEADER = struct.Struct("<12siiffi")
_SAMPLES_OFFSET = 28  # where the int32 sample count sits in the header

NEVER_FRAME = 1.0e9
"""Stored in the time attributes of a vertex that never ignites during the bake.

Blender frames stop at 1,048,574, so any value above 1e8 means "never". 1e9 is exact in
float32.
"""


class PC2Writer:
    """Streams samples to ``<path>.partial`` and renames it onto ``path`` when committed.

    Until ``commit()`` the file at ``path`` (a previous bake, if any) is untouched; ``abort()``
    deletes the partial file. Use as a context manager to commit on success and abort on an
    exception.
    """

    def __init__(self, path, n_points: int, start_frame: float = 1.0, sample_rate: float = 1.0):
        if isinstance(n_points, bool) or not isinstance(n_points, (int, np.integer)) or n_points < 1:
            raise ValueError(f"n_points must be a positive int, got {n_points!r}")
        if not (np.isfinite(start_frame) and np.isfinite(sample_rate) and sample_rate > 0):
            raise ValueError(f"start_frame must be finite and sample_rate > 0, got "
                             f"{start_frame!r}, {sample_rate!r}")
        self.path = os.fspath(path)
        self.partial_path = self.path + ".partial"
        self.n_points = int(n_points)
        self.samples = 0
        self._fh = open(self.partial_path, "wb")
        self._fh.write(_HEADER.pack(PC2_MAGIC, PC2_VERSION, self.n_points, float(start_frame),
                                    float(sample_rate), 0))

    def append(self, positions) -> None:
        """Append one sample: an (n_points, 3) array of finite positions."""
        if self._fh is None:
            raise ValueError("PC2Writer: append after commit or abort")
        a = np.asarray(positions)
        if a.shape != (self.n_points, 3):
            raise ValueError(f"positions has invalid shape: expected ({self.n_points}, 3) but got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError("positions contains NaN or inf")
        self._fh.write(np.ascontiguousarray(a, dtype="<f4").tobytes())
        self.samples += 1

    def commit(self) -> str:
        """Write the sample count, close, and atomically replace ``path``. Returns ``path``."""
        if self._fh is None:
            raise ValueError("PC2Writer: commit after commit or abort")
        fh, self._fh = self._fh, None
        try:
            fh.seek(_SAMPLES_OFFSET)
            fh.write(struct.pack("<i", self.samples))
            fh.flush()
            os.fsync(fh.fileno())
        finally:
            fh.close()
        os.replace(self.partial_path, self.path)
        return self.path

    def abort(self) -> None:
        """Drop the partial file; ``path`` stays as it was. Safe to call twice."""
        if self._fh is not None:
            self._fh.close()
            self._fh = None
        if os.path.exists(self.partial_path):
            os.remove(self.partial_path)

    def __enter__(self) -> "PC2Writer":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None and self._fh is not None:
            self.commit()
        else:
            self.abort()


class ThinnedSamples:
    """Every ``step``-th frame of a bake into a PC2Writer (the compact cache, *Keep Every*).

    Frames 0, k, 2k, … are written as they come. When the last frame n is not one of them,
    one more sample at the next multiple of k is written, chosen so that blending linearly
    from the last whole sample reaches frame n's positions exactly at frame n (a readers'
    frames past n are not played)."""

    def __init__(self, writer: PC2Writer, step: int):
        if int(step) < 1:
            raise ValueError(f"Keep Every must be at least 1, got {step!r}")
        self.writer, self.step = writer, int(step)
        self._kept = None  # (index, positions) of the last sample written
        self._latest = None

    def add(self, index: int, positions) -> None:
        positions = np.asarray(positions, dtype=np.float64)
        if index % self.step == 0:
            self.writer.append(positions)
            self._kept = (index, positions)
        self._latest = (index, positions)

    def finish(self, last_index: int) -> None:
        """After the last frame: the closing sample, if the last frame was not a kept one."""
        if self._latest is None or self._kept is None or self._kept[0] == last_index:
            return
        k0, p0 = self._kept
        r = (last_index - k0) / self.step  # in (0, 1): where frame n falls between samples
        self.writer.append(p0 + (self._latest[1] - p0) / r)


def read_pc2_header(path) -> dict:
    """The header of a PC2 file: version, points, start_frame, sample_rate, samples."""
    with open(path, "rb") as fh:
        raw = fh.read(_HEADER.size)
    if len(raw) < _HEADER.size:
        raise ValueError(f"{path}: too short for a PC2 header ({len(raw)} bytes)")
    magic, version, points, start, rate, samples = _HEADER.unpack(raw)
    if magic != PC2_MAGIC:
        raise ValueError(f"{path}: not a PC2 file (magic {magic!r})")
    return dict(version=version, points=points, start_frame=start, sample_rate=rate, samples=samples)


def read_pc2(path):
    """(header, positions (samples, points, 3) float32); the file size must match the header."""
    head = read_pc2_header(path)
    want = _HEADER.size + 12 * head["points"] * head["samples"]
    size = os.path.getsize(path)
    if size != want:
        raise ValueError(f"{path}: {size} bytes, the header promises {want}")
    data = np.fromfile(path, dtype="<f4", offset=_HEADER.size)
    return head, data.reshape(head["samples"], head["points"], 3)


# --- attributes on the mesh (no bpy import: the mesh is passed in) ---------------------------

def seconds_to_frames(times, frame_start: float, fps: float) -> np.ndarray:
    """Simulation seconds -> scene frames as float32; inf (never) -> NEVER_FRAME."""
    t = np.asarray(times, dtype=np.float64)
    frames = frame_start + t * fps
    return np.where(np.isfinite(frames), frames, NEVER_FRAME).astype(np.float32)


def write_point_attribute(mesh, name: str, values, data_type: str = "FLOAT") -> None:
    """Create or replace a point attribute and fill it (FLOAT: (n,), FLOAT_COLOR: (n, 4))."""
    old = mesh.attributes.get(name)
    if old is not None and (old.data_type != data_type or old.domain != "POINT"):
        mesh.attributes.remove(old)
        old = None
    if old is None:
        if data_type == "FLOAT_COLOR":
            mesh.color_attributes.new(name, data_type, "POINT")
        else:
            mesh.attributes.new(name, data_type, "POINT")
    attr = mesh.attributes[name]
    key = "color" if data_type == "FLOAT_COLOR" else "value"
    attr.data.foreach_set(key, np.ascontiguousarray(values, dtype=np.float32).ravel())


def remove_attributes(mesh, names) -> int:
    """Remove the named attributes that exist; returns how many went."""
    gone = 0
    for name in names:
        attr = mesh.attributes.get(name)
        if attr is not None:
            mesh.attributes.remove(attr)
            gone += 1
    return gone
