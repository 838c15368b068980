"""Static friction on curved colliders (docs/dynamics.md §3.2): does a sheet at rest on a sphere
stay where Coulomb's cone says it should?

Two scenes, printed as markdown tables:
- **Cone.** A 0.3 m cloth square laid on a 1 m sphere, tilted by theta from its top, friction 0.5.
  It must stay put while tan(theta) < 0.5 (theta < 26.6 deg) and slide beyond. The table gives
  the centre's slide along the sphere (mm/s) between 1 s and 4 s.
- **Drape.** A 1 m cloth square dropped on a 0.3 m sphere that it drapes over: the speed of the
  part resting on the sphere's top (mesh vertices within 0.15 m of the axis), seconds 4 to 8.

    python scripts/collider_friction.py [--quick | --track]
"""
import argparse

import numpy as np

import thinburn
from thinburn.scenes import rect_sheet

QUIET = dict(speed_noise=0.0, duration_noise=0.0)


def tilted_sheet(theta, radius, centre, **kw):
    """A 0.3 m square cloth tangent to the sphere, 6 mm above it, tilted by theta (rad) about y."""
    v, f = rect_sheet(0.3, 0.3, nx=31, ny=31)
    v = v - v.mean(0)
    v[:, 2] += radius + 0.006
    c, s = np.cos(theta), np.sin(theta)
    v = v @ np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]).T + centre
    return thinburn.Simulation(v, f, cells=16, lattice=6, material="cloth", **QUIET, **kw)


def cone_slide(theta_deg, friction=0.5, samples=4, **kw):
    """mm/s of the sheet's centre along the sphere, seconds 1 to 4."""
    radius, centre = 1.0, np.array([0.0, 0.0, 1.2])
    sim = tilted_sheet(np.radians(theta_deg), radius, centre, **kw)
    sim.set_colliders(spheres=[dict(centre=tuple(centre), radius=radius, friction=friction)], samples=samples)

    def angle():
        p = sim.vertex_positions().mean(0) - centre
        return np.arctan2(p[0], p[2])

    for _ in range(24):
        sim.step(1 / 24)
    a = angle()
    for _ in range(72):
        sim.step(1 / 24)
    return abs(angle() - a) * radius * 1e3 / 3.0


def draped(friction, **kw):
    """The 1 m cloth 2 cm over the 0.3 m sphere, and which of its vertices rest on its top."""
    sim = thinburn.Simulation(*rect_sheet(1.0, 1.0, nx=49, ny=49, z=0.32), cells=32, lattice=12,
                              material="cloth", **QUIET, **kw)
    sim.set_colliders(spheres=[dict(centre=(0.5, 0.5, 0.0), radius=0.3, friction=friction)])
    x0 = sim.vertex_positions()
    return sim, np.hypot(x0[:, 0] - 0.5, x0[:, 1] - 0.5) < 0.15


def drape_creep(friction=0.5, **kw):
    """mm/s of the mean of the vertices resting on the sphere's top, seconds 4 to 8."""
    sim, top = draped(friction, **kw)
    for _ in range(96):
        sim.step(1 / 24)
    a = sim.vertex_positions()[top].mean(0)
    for _ in range(96):
        sim.step(1 / 24)
    return np.linalg.norm(sim.vertex_positions()[top].mean(0) - a) * 1e3 / 4.0


def drape_track(friction=2.0, **kw):
    """The drape's top: how far (mm) its mean moved from second 4 to seconds 6, 8, 10, 12."""
    sim, top = draped(friction, **kw)
    sim.run(4.0, dt=1 / 24)
    a = sim.vertex_positions()[top].mean(0)
    out = []
    for _ in range(4):
        sim.run(2.0, dt=1 / 24)
        out.append(1e3 * np.linalg.norm(sim.vertex_positions()[top].mean(0) - a))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the cone table only")
    ap.add_argument("--track", action="store_true",
                    help="only the drape's top at friction 2, with and without the knee (k_limit=0)")
    args = ap.parse_args()
    if args.track:
        for k in (None, 0.0):
            moved = drape_track(**({} if k is None else dict(k_limit=k)))
            print(f"k_limit {'default' if k is None else k}: the top moved "
                  f"{', '.join(f'{m:.2f}' for m in moved)} mm from second 4 to seconds 6, 8, 10, 12")
        return
    print("| tilt (deg) | tan | samples 4: slide (mm/s) | samples 0: slide (mm/s) |")
    print("|---|---|---|---|")
    for theta in (10, 20, 25, 30, 35):
        print(f"| {theta} | {np.tan(np.radians(theta)):.2f} | {cone_slide(theta):.2f} | "
              f"{cone_slide(theta, samples=0):.2f} |")
    if args.quick:
        return
    print()
    print("| friction | substeps | top's creep (mm/s) |")
    print("|---|---|---|")
    for friction in (0.5, 1.0, 2.0):
        for substeps in (0, 16, 128):
            print(f"| {friction} | {substeps or 'auto'} | {drape_creep(friction, substeps=substeps):.2f} |")


if __name__ == "__main__":
    main()
