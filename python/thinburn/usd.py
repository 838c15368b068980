"""USD out: a baked sheet as a time-sampled ``UsdGeom.Mesh`` and its fire as ``UsdGeom.Points``.

Needs ``usd-core`` (``pip install "thinburn[farm]"``); nothing else in thinburn imports it.

What the stage holds (``/ThinBurn`` is the default prim, z up, 1 unit = 1 m,
``timeCodesPerSecond = framesPerSecond = fps``, time code = ``start + t * fps`` for simulated
time t in seconds):

* ``/ThinBurn/<name>`` (``Mesh``): ``points`` per time sample (float32, the simulation's
  positions), ``faceVertexCounts`` / ``faceVertexIndices`` (triangles, or the polygons given),
  ``extent`` per time sample, subdivisionScheme ``none``; primvars, all ``vertex``
  interpolation, float: ``char`` per time sample (0 unburnt .. 1 fully charred),
  ``ignitionTime`` and ``burnoutTime`` (constant, in time codes of this stage;
  ``NEVER`` = 1e9 for a vertex that never ignites, as the Blender add-on's attributes).
* ``/ThinBurn/<name>_fire`` (``Points``), when particles are given: ``points``, ``widths`` and
  the primvar ``temperature`` (``vertex``, kelvin above ambient, as ``Simulation.particles()``
  gives it) per time sample; the count changes from sample to sample.
"""
from __future__ import annotations

import os

import numpy as np

NEVER = 1.0e9
"""ignitionTime / burnoutTime of a vertex that never ignites (as the add-on's NEVER_FRAME)."""


def _pxr():
    try:
        from pxr import Gf, Sdf, Usd, UsdGeom, Vt
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("USD export needs the 'usd-core' package (pip install usd-core, or "
                          f"pip install 'thinburn[farm]'): {exc}") from exc
    return Gf, Sdf, Usd, UsdGeom, Vt


def _faces(faces):
    """(counts, indices) from an (m, 3) triangle array or a (counts, indices) pair."""
    if isinstance(faces, tuple) and len(faces) == 2:
        counts = np.asarray(faces[0], dtype=np.int32).ravel()
        indices = np.asarray(faces[1], dtype=np.int32).ravel()
        if np.any(counts < 3) or counts.sum() != len(indices):
            raise ValueError("faces: the counts must be >= 3 and add up to the number of indices")
        return counts, indices
    tris = np.asarray(faces)
    if tris.ndim != 2 or tris.shape[1] != 3 or len(tris) == 0:
        raise ValueError(f"faces must be an (m, 3) array of triangles or (counts, indices), got shape {tris.shape}")
    return np.full(len(tris), 3, dtype=np.int32), tris.astype(np.int32).ravel()


def times_to_codes(times, fps: float, start: float = 0.0) -> np.ndarray:
    """Simulated seconds -> float time codes; inf (never) -> NEVER. Codes within 1e-6 of a
    whole frame are snapped to it (a sum of 1/fps steps is a frame up to rounding)."""
    t = np.asarray(times, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        codes = start + t * fps
        near = np.abs(codes - np.round(codes)) < 1e-6
    codes = np.where(near, np.round(codes), codes)
    return np.where(np.isfinite(codes), codes, NEVER)


def write_usd(path, faces, time_codes, positions, fps: float, *, char=None, ignition=None,
              burnout=None, particles=None, name: str = "Sheet", transform=None,
              particle_width: float = 0.004) -> str:
    """Write a bake to a USD file (.usda text, .usdc / .usd binary). Returns the path.

    faces: (m, 3) triangles or (counts, indices). time_codes: (F,) increasing time codes.
    positions: (F, n, 3). char: None or (F, n). ignition, burnout: None or (n,) in time codes
    (NEVER or anything above 1e8 for never; use ``times_to_codes`` from seconds).
    particles: None or F pairs (positions (k, 3), temperatures (k,)), k may change.
    transform: None, the sheet's 4×4 matrix (column vectors, as Blender's matrix_world), or
    (F, 4, 4), one per time code (a sheet whose transform is animated); the points are then
    in the sheet's object space.
    """
    Gf, Sdf, Usd, UsdGeom, Vt = _pxr()
    fps = float(fps)
    if not np.isfinite(fps) or fps <= 0:
        raise ValueError(f"fps must be positive, got {fps!r}")
    codes = np.asarray(time_codes, dtype=np.float64).ravel()
    pos = np.asarray(positions, dtype=np.float32)
    if pos.ndim != 3 or pos.shape[2] != 3 or pos.shape[0] != len(codes) or len(codes) == 0:
        raise ValueError(f"positions must be (frames, n, 3) with one frame per time code "
                         f"({len(codes)}), got shape {pos.shape}")
    if np.any(np.diff(codes) <= 0) or not np.all(np.isfinite(codes)):
        raise ValueError("time_codes must be finite and increasing")
    n = pos.shape[1]
    counts, indices = _faces(faces)
    if indices.size and (indices.min() < 0 or indices.max() >= n):
        raise ValueError(f"faces: vertex indices must be in [0, {n})")
    if char is not None:
        char = np.asarray(char, dtype=np.float32)
        if char.shape != pos.shape[:2]:
            raise ValueError(f"char must be (frames, n) = {pos.shape[:2]}, got {char.shape}")
    if particles is not None and len(particles) != len(codes):
        raise ValueError(f"particles: one (positions, temperatures) pair per time code "
                         f"({len(codes)}), got {len(particles)}")
    if transform is not None:  # checked before an existing file at path is replaced
        transform = _transforms(transform, len(codes))

    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    if os.path.exists(path):
        os.remove(path)  # CreateNew refuses an existing layer
    stage = Usd.Stage.CreateNew(path)
    stage.SetMetadata("comment", "thinburn bake (Liu et al. 2009 burning thin shells)")
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetTimeCodesPerSecond(fps)
    stage.SetFramesPerSecond(fps)
    stage.SetStartTimeCode(float(codes[0]))
    stage.SetEndTimeCode(float(codes[-1]))
    root = UsdGeom.Xform.Define(stage, "/ThinBurn")
    stage.SetDefaultPrim(root.GetPrim())

    mesh = UsdGeom.Mesh.Define(stage, f"/ThinBurn/{_prim_name(name)}")
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(indices))
    if transform is not None:
        _set_transform(mesh.AddTransformOp(), transform, codes, Gf, Usd)
    points = mesh.CreatePointsAttr()
    extent = mesh.CreateExtentAttr()
    api = UsdGeom.PrimvarsAPI(mesh)
    char_pv = None
    if char is not None:
        char_pv = api.CreatePrimvar("char", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex)
    for k, code in enumerate(codes):
        tc = Usd.TimeCode(float(code))
        points.Set(Vt.Vec3fArray.FromNumpy(pos[k]), tc)
        extent.Set(Vt.Vec3fArray.FromNumpy(np.stack([pos[k].min(0), pos[k].max(0)])), tc)
        if char_pv is not None:
            char_pv.Set(Vt.FloatArray.FromNumpy(char[k]), tc)
    for key, values in (("ignitionTime", ignition), ("burnoutTime", burnout)):
        if values is None:
            continue
        v = np.asarray(values, dtype=np.float64).ravel()
        if v.shape != (n,):
            raise ValueError(f"{key}: one value per vertex ({n}), got shape {v.shape}")
        v = np.where(np.isfinite(v), v, NEVER).astype(np.float32)
        api.CreatePrimvar(key, Sdf.ValueTypeNames.FloatArray,
                          UsdGeom.Tokens.vertex).Set(Vt.FloatArray.FromNumpy(v))

    if particles is not None:
        fire = UsdGeom.Points.Define(stage, f"/ThinBurn/{_prim_name(name)}_fire")
        fpoints, fwidths, fextent = fire.CreatePointsAttr(), fire.CreateWidthsAttr(), fire.CreateExtentAttr()
        fire.SetWidthsInterpolation(UsdGeom.Tokens.vertex)
        temp = UsdGeom.PrimvarsAPI(fire).CreatePrimvar("temperature", Sdf.ValueTypeNames.FloatArray,
                                                      UsdGeom.Tokens.vertex)
        for k, code in enumerate(codes):
            p, t = particles[k]
            p = np.asarray(p, dtype=np.float32).reshape(-1, 3)
            t = np.asarray(t, dtype=np.float32).ravel()
            if len(p) != len(t):
                raise ValueError(f"particles[{k}]: {len(p)} positions but {len(t)} temperatures")
            tc = Usd.TimeCode(float(code))
            fpoints.Set(Vt.Vec3fArray.FromNumpy(p), tc)
            fwidths.Set(Vt.FloatArray.FromNumpy(np.full(len(p), particle_width, np.float32)), tc)
            temp.Set(Vt.FloatArray.FromNumpy(t), tc)
            box = np.stack([p.min(0), p.max(0)]) if len(p) else np.zeros((2, 3), np.float32)
            fextent.Set(Vt.Vec3fArray.FromNumpy(box), tc)
    stage.GetRootLayer().Save()
    return path


def _transforms(transform, frames: int) -> np.ndarray:
    """transform as (4, 4) (also from 16 numbers) or (frames, 4, 4), else a ValueError."""
    m = np.asarray(transform, dtype=np.float64)
    if m.size == 16:
        m = m.reshape(4, 4)
    if m.shape not in ((4, 4), (frames, 4, 4)) or not np.all(np.isfinite(m)):
        raise ValueError(f"transform has invalid shape: expected (4, 4) or ({frames}, 4, 4) "
                         f"(finite) but got {m.shape}")
    return m


def _set_transform(op, m: np.ndarray, codes: np.ndarray, Gf, Usd) -> None:
    """One matrix, or one time sample per time code (USD takes row vectors: transposed)."""
    if m.shape == (4, 4):
        op.Set(Gf.Matrix4d(m.T.tolist()))
        return
    for mk, code in zip(m, codes):
        op.Set(Gf.Matrix4d(mk.T.tolist()), Usd.TimeCode(float(code)))


def _prim_name(name: str) -> str:
    """A valid USD prim name from any object name."""
    out = "".join(c if c.isalnum() or c == "_" else "_" for c in str(name)) or "Sheet"
    return "_" + out if out[0].isdigit() else out


def export_frames(frames_npz, path, fps: float | None = None, name: str = "Sheet") -> str:
    """A demo's or a wedge's ``frames.npz`` (with its ``summary.json`` beside it for the fps)
    to USD. Time code = t * fps for each recorded frame's simulated time t."""
    frames_npz = os.fspath(frames_npz)
    if fps is None:
        import json
        summary = os.path.join(os.path.dirname(os.path.abspath(frames_npz)), "summary.json")
        if not os.path.exists(summary):
            raise ValueError(f"fps: not given and no summary.json beside {frames_npz}")
        with open(summary) as f:
            fps = float(json.load(f)["fps"])
    with np.load(frames_npz) as data:
        d = {k: data[k] for k in data.files}
    for key in ("time", "vertex_positions", "faces"):
        if key not in d:
            raise ValueError(f"{frames_npz}: no '{key}' array (not a thinburn frames.npz)")
    codes = times_to_codes(d["time"], fps)
    particles = None
    if "particles_0000" in d:
        particles = []
        for k in range(len(codes)):
            a = d[f"particles_{k:04d}"]
            particles.append((a[:, :3], a[:, 3]))
    ign = d.get("vertex_ignition_times")
    out = d.get("vertex_burnout_times")
    return write_usd(path, d["faces"], codes, d["vertex_positions"], fps, char=d.get("vertex_char"),
                     ignition=None if ign is None else times_to_codes(ign, fps),
                     burnout=None if out is None else times_to_codes(out, fps),
                     particles=particles, name=name)
