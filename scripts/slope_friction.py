"""Coulomb's law on a slope (docs/dynamics.md §3, "On a slope"): a sheet lying on the floor
under gravity tilted by an angle, which is the floor tilted by that angle. With friction mu it
holds while tan(angle) <= mu and otherwise slides 1/2 g (sin - mu cos) t^2 in t.

Two cases, each per angle, integrator and step size:
- `lattice`: a 10 cm paper lattice (M = 9, 3 mm thick, 100 g/m^2) lying on the floor, no damping,
  friction 0.5, 1 s; printed: how far its mean moved (mm) against the closed form;
- `sheet`: a Simulation's 10 cm cloth square (lattice 9, no damping) on its table, friction 1,
  20 degrees; printed: how far it moved in the first second (its landing) and in the two after.

    python scripts/slope_friction.py [--case lattice sheet] [--angles 20 25 30 35 45]
"""
import argparse

import numpy as np

import thinburn
from thinburn import _core
from thinburn.dynamics import preset, vertex_masses
from thinburn.materials import MATERIALS
from thinburn.scenes import rect_sheet

G = 9.81
RUNS = (("implicit", 24), ("implicit", 96), ("implicit", 480), ("bdf2", 24), ("symplectic", 96))


def tilted(angle_deg):
    th = np.radians(angle_deg)
    return [G * np.sin(th), 0.0, -G * np.cos(th)]


def coulomb_slide(angle_deg, friction, seconds):
    """Closed form: how far a block slides from rest in `seconds` (m)."""
    th = np.radians(angle_deg)
    return 0.5 * max(0.0, G * (np.sin(th) - friction * np.cos(th))) * seconds ** 2


def lattice_slide(angle_deg, dt, integrator="implicit", friction=0.5, seconds=1.0, M=9, spacing=0.0125,
                  thickness=0.003):
    """How far (m) a flat lattice lying on the floor moves along the slope in `seconds`."""
    idx = np.arange(2 * M * M)
    k, c = idx % 2, idx // 2
    i, j = c // M, c % M
    rest = np.column_stack([j * spacing, i * spacing, (k - 0.5) * thickness])
    lat = _core.FfdLattice(M, rest)
    dyn = _core.LatticeDynamics(lat, **preset("paper", integrator=integrator, has_floor=True, floor_z=-thickness / 2,
                                              friction=friction, c_damping=0.0, wind_drag=0.0, buoyancy=0.0,
                                              gravity=tilted(angle_deg)))
    dyn.set_masses(vertex_masses(M, ((M - 1) * spacing) ** 2, 0.1))
    D, heat = np.zeros(M * M), np.zeros(2 * M * M)
    x0 = lat.positions[:, 0].mean()
    for _ in range(int(round(seconds / dt))):
        dyn.step(dt, D, heat)
    return lat.positions[:, 0].mean() - x0


def sheet_creep(angle_deg, dt, friction=1.0):
    """A Simulation's 10 cm cloth square on its table: how far (m) it moves in its first second
    and in the two after."""
    v, f = rect_sheet(0.1, 0.1, nx=21, ny=21)
    sim = thinburn.Simulation(v, f, material=MATERIALS["cloth"].with_(C_damping=0.0), cells=32, floor=0.0,
                              wind_drag=0.0, friction=friction, lattice=9, gravity=tilted(angle_deg))
    x0 = sim.vertex_positions()[:, 0].mean()
    sim.run(1.0, dt=dt)
    x1 = sim.vertex_positions()[:, 0].mean()
    sim.run(2.0, dt=dt)
    return x1 - x0, sim.vertex_positions()[:, 0].mean() - x1


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", nargs="+", default=["lattice", "sheet"], choices=["lattice", "sheet"])
    ap.add_argument("--angles", nargs="+", type=float, default=[20, 25, 30, 35, 45])
    a = ap.parse_args()
    if "lattice" in a.case:
        print("lattice, friction 0.5, 1 s: distance slid (mm)")
        print("angle  closed form  " + "  ".join(f"{i[:4]} 1/{s:<4d}" for i, s in RUNS))
        for angle in a.angles:
            row = [f"{lattice_slide(angle, 1 / s, i) * 1e3:11.2f}" for i, s in RUNS]
            print(f"{angle:5.0f}  {coulomb_slide(angle, 0.5, 1.0) * 1e3:11.2f}  " + "  ".join(row), flush=True)
    if "sheet" in a.case:
        print("Simulation sheet, friction 1, 20 degrees: moved in the first 1 s / the next 2 s (mm)")
        for s in (24, 96, 480):
            first, after = sheet_creep(20.0, 1 / s)
            print(f"implicit 1/{s}: {first * 1e3:.3f} / {after * 1e3:.3f}", flush=True)


if __name__ == "__main__":
    main()
