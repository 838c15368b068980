"""A cloth strip draped over a box's edge (tests/test_colliders.py's scene; docs/lattice.md,
"Where the lattice folds"): after 3 s, the p99 and largest |l/L - 1| of the mesh's edges and the
lattice's largest turn between couples, per lattice size.

    python scripts/box_edge_drape.py [--lattices 16 8]
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
    a = ap.parse_args()
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


if __name__ == "__main__":
    main()
