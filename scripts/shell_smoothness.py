"""Issue #12 item 2, facets: the angle between adjacent faces of a fine mesh away from the fire.
`python scripts/shell_smoothness.py [--seconds 40]` burns the A4 demo scene (paper on its table,
lit at a corner) on a mesh of about 85 x 121 vertices (2.5 mm edges) at 128 cells and prints, every 10 s, the 99.5th
percentile and the largest dihedral angle between adjacent faces whose vertices are unburnt and
at least 3 cm (rest distance) from any charred vertex, with the lattice's spacing."""
from __future__ import annotations

import argparse

import numpy as np

from thinburn import demo
from thinburn._mesh_measures import dihedral_angles, face_adjacency, far_from_fire


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=40.0)
    ap.add_argument("--material", default="paper")
    a = ap.parse_args(argv)
    scene = demo.default_scene(a.material, vertices=85 * 121)
    sim = demo.build(scene, material=a.material, cells=128)
    pairs = face_adjacency(scene.faces)
    edge = np.linalg.norm(scene.vertices[scene.faces[:, 0]] - scene.vertices[scene.faces[:, 1]], axis=1).max()
    print(f"lattice {sim.lattice_size} x {sim.lattice_size} couples, {len(scene.vertices)} vertices, "
          f"longest first edge {1000 * edge:.1f} mm")
    for t in np.arange(10.0, a.seconds + 1e-9, 10.0):
        sim.run(10.0, dt=1 / 24)
        x = sim.vertex_positions()
        keep = far_from_fire(scene.vertices, scene.faces, sim.vertex_char(), 0.03)
        sel = keep[pairs[:, 0]] & keep[pairs[:, 1]]
        ang = dihedral_angles(x, scene.faces, pairs[sel])
        print(f"t={t:.0f} s: {sel.sum()} face pairs away from the fire, dihedral p99.5 {np.percentile(ang, 99.5):.2f} deg, "
              f"max {ang.max():.2f} deg", flush=True)


if __name__ == "__main__":
    main()
