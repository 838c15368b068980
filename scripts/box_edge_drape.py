"""A cloth strip draped over a box's edge (tests/test_colliders.py's scene; docs/lattice.md,
"Where the lattice folds"): after 3 s, the p99 and largest |l/L - 1| of the mesh's edges and the
lattice's largest turn between couples, per lattice size. With --chair, an artist's trial
instead: a 50 cm cloth (51 x 51) dropped 2 cm onto a 40 cm box 45 cm high (a chair's seat,
friction 50, margin 1 mm), 12 cm off centre so that one side overhangs; after 5 s (128 cells),
the same strains and where the worst edge lies.

    python scripts/box_edge_drape.py [--lattices 16 8] [--chair]
"""
import argparse

import numpy as np

import thinburn
from thinburn._mesh_measures import EdgeStrain
from thinburn.scenes import rect_sheet

BOX = dict(centre=(-0.15, 0.05, -0.51), half_extents=(0.5, 0.5, 0.5), friction=1.0)  # edge at x = 0.35


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lattices", type=int, nargs="+", default=[16, 8])
    ap.add_argument("--chair", action="store_true", help="the chair's seat instead of the strip")
    a = ap.parse_args()
    if a.chair:
        return chair(a.lattices)
    v, f = rect_sheet(0.6, 0.1, nx=61, ny=11)
    for m in a.lattices:
        sim = thinburn.Simulation(v, f, cells=32, lattice=m, material="cloth", speed_noise=0.0, duration_noise=0.0)
        sim.set_colliders(boxes=[BOX])
        sim.run(3.0, dt=1 / 24)
        strain = EdgeStrain(v, f)(sim.vertex_positions())
        c = sim.lattice_positions().reshape(m, m, 2, 3).mean(2)
        d = np.diff(c, axis=1)
        cos = (d[:, :-1] * d[:, 1:]).sum(-1) / np.linalg.norm(d[:, :-1], axis=-1) / np.linalg.norm(d[:, 1:], axis=-1)
        turn = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))).max()
        print(f"lattice {m}: mesh edges p99 {100 * np.percentile(strain, 99):.2f} %, worst {100 * strain.max():.2f} %; "
              f"largest turn along the strip {turn:.1f} deg", flush=True)


def chair(lattices):
    v, f = rect_sheet(0.5, 0.5, nx=51, ny=51, z=0.47)
    v[:, 0] -= 0.13  # x from -0.13 to 0.37: the seat's edge at x = 0.2
    v[:, 1] -= 0.25
    for m in lattices:
        sim = thinburn.Simulation(v, f, cells=128, lattice=m, material="cloth", floor=0.0)
        sim.set_colliders(boxes=[dict(centre=(0.0, 0.0, 0.225), half_extents=(0.2, 0.2, 0.225), friction=50.0)],
                          margin=0.001)
        sim.run(5.0, dt=1 / 24)
        x = sim.vertex_positions()
        strain = EdgeStrain(v, f)(x)
        at = x[EdgeStrain(v, f).edges[np.argmax(strain)]].mean(0)
        print(f"chair, lattice {m}: mesh edges p99 {100 * np.percentile(strain, 99):.2f} %, worst "
              f"{100 * strain.max():.2f} % at x = {at[0]:.3f} m, z = {at[2]:.3f} m (the seat's edge: 0.2, 0.45)",
              flush=True)


if __name__ == "__main__":
    main()
