"""Blender's Wind and Turbulence force fields as wind on a sheet.

The Blender add-on (blender_addon/inputs.py, ``field_spec``) reads each field into a
``FieldSpec`` (plain numbers), and a scene file holds them per frame (thinburn.scenefile);
``wind_at`` gives the wind they make at world points, ``blow`` sets it on a Simulation before
a step, as the add-on's bake and thinburn.scene_run both do. The formulas follow Blender's effector code
(source/blender/blenkernel/intern/effect.cc: get_effector_data, effector_falloff,
falloff_func, do_physical_effector, wind_func); docs/blender.md writes them out. Blender's
cloth takes a field's force as the wind's velocity, and so does ThinBurn (times Wind Scale).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import bake_frame


@dataclass(frozen=True)
class FieldSpec:
    """One force field at one frame, in world space."""

    kind: str                 # "WIND" or "TURBULENCE"
    origin: tuple             # the field object's world location
    axis: tuple               # its world Z axis, unit
    shape: str                # "POINT", "LINE" or "PLANE"
    strength: float
    noise: float              # Blender's Noise Amount: random strength per point and frame
    seed: int
    z_direction: str          # "BOTH", "POSITIVE", "NEGATIVE"
    falloff: str              # "SPHERE", "TUBE", "CONE"
    power: float
    use_min: bool
    min_distance: float
    use_max: bool
    max_distance: float
    radial_power: float = 0.0
    use_radial_min: bool = False
    radial_min: float = 0.0
    use_radial_max: bool = False
    radial_max: float = 0.0
    size: float = 1.0         # Turbulence: the noise's size
    global_coords: bool = False  # Turbulence: noise in world coordinates, not the field's


def falloff_curve(x, power, use_min, lo, use_max, hi) -> np.ndarray:
    """Blender's falloff_func: 0 beyond Max Distance, 1 inside Min Distance, else
    (1 + x - Min)^-Power (Min taken as 0 when it is off)."""
    x = np.asarray(x, dtype=np.float64)
    base = lo if use_min else 0.0
    out = np.power(np.maximum(1.0 + x - base, 1e-300), -float(power))
    if use_min:
        out = np.where(x < lo, 1.0, out)
    if use_max:
        out = np.where(x > hi, 0.0, out)
    return out


def falloff(spec: FieldSpec, points: np.ndarray) -> np.ndarray:
    """(n,) Blender's effector_falloff at world points: the shape sets where distance is
    measured from (the origin, the Z line or the XY plane), the Z direction cuts a side off,
    the falloff type measures the distance (Sphere) or, from the field's centre, splits it
    along Z and across it (Tube: the distance from the Z axis; Cone: the angle to it, degrees),
    the radial part with the Radial settings."""
    o = np.asarray(spec.origin, dtype=np.float64)
    nor = np.asarray(spec.axis, dtype=np.float64)
    rel = points - o                   # vec_to_point2: from the object's centre
    along = rel @ nor                  # fac
    if spec.shape == "PLANE":          # the closest point on the field's XY plane
        vec = np.outer(along, nor)
    elif spec.shape == "LINE":         # the closest point on the field's Z axis
        vec = rel - np.outer(along, nor)
    else:
        vec = rel
    distance = np.linalg.norm(vec, axis=1)
    curve = (spec.power, spec.use_min, spec.min_distance, spec.use_max, spec.max_distance)
    radial = (spec.radial_power, spec.use_radial_min, spec.radial_min, spec.use_radial_max,
              spec.radial_max)
    if spec.falloff == "TUBE":
        across = np.linalg.norm(rel - np.outer(along, nor), axis=1)
        out = falloff_curve(np.abs(along), *curve) * falloff_curve(across, *radial)
    elif spec.falloff == "CONE":
        cosine = np.clip(along / np.maximum(np.linalg.norm(rel, axis=1), 1e-300), -1.0, 1.0)
        out = falloff_curve(np.abs(along), *curve) * falloff_curve(np.degrees(np.arccos(cosine)), *radial)
    else:
        out = falloff_curve(distance, *curve)
    if spec.z_direction == "POSITIVE":
        out = np.where(along < 0.0, 0.0, out)
    elif spec.z_direction == "NEGATIVE":
        out = np.where(along > 0.0, 0.0, out)
    return out


def strength_noise(noise: float, count: int, rng: np.random.Generator) -> np.ndarray:
    """Blender's wind_func, drawn per point: a whole number r in [0, 128) and f in [1, 2);
    ±r / f × Noise / 128, the sign + when r > 64. (The same law, not Blender's own random
    sequence: Blender seeds its generator with Seed + frame too, but draws in its own order.)"""
    r = rng.integers(0, 128, size=count).astype(np.float64)
    f = rng.random(count) + 1.0
    return np.where(r > 64.0, 1.0, -1.0) * r / f * noise / 128.0


def wind_at(specs, points, frame: int) -> np.ndarray:
    """(n, 3) wind at world points from every field in ``specs`` at ``frame``, in units of
    field strength (multiply by Wind Scale for m/s)."""
    points = np.atleast_2d(np.asarray(points, dtype=np.float64))
    out = np.zeros_like(points)
    for spec in specs:
        fall = falloff(spec, points)
        strength = np.full(len(points), float(spec.strength))
        if spec.noise > 0.0:
            rng = np.random.default_rng([int(spec.seed) & 0x7FFFFFFF, abs(int(frame))])
            strength = strength + strength_noise(spec.noise, len(points), rng)
        if spec.kind == "TURBULENCE":
            out += turbulence_direction(spec, points) * (strength * fall)[:, None]
        else:
            out += np.outer(strength * fall, spec.axis)
    return out


# --- Turbulence ---------------------------------------------------------------------------------
def turbulence_direction(spec: FieldSpec, points: np.ndarray) -> np.ndarray:
    """(n, 3) per component -1 + 2 × turbulence(size, point) with the point's coordinates
    rotated per component (x, y, z), (y, z, x), (z, x, y), as do_physical_effector does; the
    point is taken from the field's centre plus its Z axis unless Global Coordinates is on."""
    o = np.asarray(spec.origin, dtype=np.float64)
    nor = np.asarray(spec.axis, dtype=np.float64)
    p = points if spec.global_coords else points - o + nor
    perm = _permutation(spec.seed)
    cols = []
    for order in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        cols.append(-1.0 + 2.0 * turbulence(spec.size, p[:, order], perm))
    return np.stack(cols, axis=1)


def turbulence(size: float, p: np.ndarray, perm: np.ndarray, octaves: int = 2) -> np.ndarray:
    """Blender's BLI_noise_generic_turbulence(size, x, y, z, 2, soft, Improved Perlin): octaves
    0..2 of noise in [0, 1] at doubling frequency and halving amplitude, scaled by
    2^oct / (2^(oct+1) - 1) so that the sum stays in [0, 1]."""
    if size != 0.0:
        p = p / size
    total = np.zeros(len(p))
    amp, scale = 1.0, 1.0
    for _ in range(octaves + 1):
        total += amp * (0.5 + 0.5 * improved_perlin(scale * p, perm))
        amp *= 0.5
        scale *= 2.0
    return total * ((1 << octaves) / ((1 << (octaves + 1)) - 1))


def _permutation(seed: int) -> np.ndarray:
    perm = np.random.default_rng(int(seed) & 0x7FFFFFFF).permutation(256)
    return np.concatenate([perm, perm])


_GRAD = np.array([[1, 1, 0], [-1, 1, 0], [1, -1, 0], [-1, -1, 0], [1, 0, 1], [-1, 0, 1],
                  [1, 0, -1], [-1, 0, -1], [0, 1, 1], [0, -1, 1], [0, 1, -1], [0, -1, -1],
                  [1, 1, 0], [0, -1, 1], [-1, 1, 0], [0, -1, -1]], dtype=np.float64)


def improved_perlin(p: np.ndarray, perm: np.ndarray) -> np.ndarray:
    """Ken Perlin's improved noise (2002) at points (n, 3), in about [-1, 1]: gradients from
    the 16 edge directions at the lattice corners, blended with 6t^5 - 15t^4 + 10t^3."""
    cell = np.floor(p)
    f = p - cell
    i = cell.astype(np.int64) & 255
    fade = f * f * f * (f * (f * 6.0 - 15.0) + 10.0)
    corners = {}
    for dx in (0, 1):
        for dy in (0, 1):
            for dz in (0, 1):
                h = perm[perm[perm[i[:, 0] + dx] + i[:, 1] + dy] + i[:, 2] + dz] & 15
                d = f - np.array([dx, dy, dz], dtype=np.float64)
                corners[dx, dy, dz] = np.einsum("ij,ij->i", _GRAD[h], d)
    u, v, w = fade[:, 0], fade[:, 1], fade[:, 2]
    x00 = corners[0, 0, 0] + u * (corners[1, 0, 0] - corners[0, 0, 0])
    x10 = corners[0, 1, 0] + u * (corners[1, 1, 0] - corners[0, 1, 0])
    x01 = corners[0, 0, 1] + u * (corners[1, 0, 1] - corners[0, 0, 1])
    x11 = corners[0, 1, 1] + u * (corners[1, 1, 1] - corners[0, 1, 1])
    y0 = x00 + v * (x10 - x00)
    y1 = x01 + v * (x11 - x01)
    return y0 + w * (y1 - y0)


# --- the wind on a Simulation -----------------------------------------------------------------
def blow(sim, specs, wind_scale: float, frame: int, to_world, positions, shell: bool) -> None:
    """Set the fields' wind on ``sim`` for its next step: with a lattice (``shell``), at each
    control vertex (``set_wind_field``, each its own wind on the motion) and their mean as the
    uniform wind (the fire front and the particles); without, the fields at the sheet's centre
    (``positions``: its vertices now). Evaluated in the world (``to_world``: the bake frame's
    map, bake_frame.py), turned into the bake frame. No fields: no wind."""
    if not specs:
        sim.wind = (0.0, 0.0, 0.0)
        return
    if shell:
        points = np.asarray(sim.lattice_positions(), dtype=np.float64).reshape(-1, 3)
    else:
        points = np.asarray(positions, dtype=np.float64).mean(axis=0, keepdims=True)
    world = wind_at(specs, bake_frame.to_world(to_world, points), frame) * wind_scale
    local = bake_frame.direction_to_bake(to_world, world)
    if shell:
        sim.set_wind_field(local)
    sim.wind = tuple(float(c) for c in local.mean(axis=0))
