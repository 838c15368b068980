"""Unburnt-edge strain of burning shells under three curl settings (docs/dynamics.md §2).

For an A4 sheet on a table lit at a corner, a lantern on a table lit on its side and a sphere
pinned at its top lit on its equator (cells=96, 40 s at 1/24 s): the 99th percentile of
|l/L - 1| over edges whose both vertices are still unburnt, at 10, 20, 30 and 40 s, with
  isotropic: the bimetal curl alike in all directions, bend limit 1.2 rad (the old defaults);
  across:    the curl across the front (anisotropic_curl), bend limit 1.2 rad;
  default:   across the front, bend limit 0.4 rad (the material presets' defaults).
Run: python scripts/shell_strain.py [--cells 96] [--seconds 40]
"""
import argparse

import numpy as np

import thinburn
from thinburn import _surface_shapes as S
from thinburn.scenes import rect_sheet

SETTINGS = {
    "isotropic": dict(anisotropic_curl=False, max_rotation=1.2),
    "across": dict(anisotropic_curl=True, max_rotation=1.2),
    "default": {},
}


def scenes():
    sphere = S.icosphere(4, 0.1)
    return [("A4", rect_sheet(), (0, 0, 0), dict(floor=0.0)),
            ("lantern", S.cylinder(0.1, 0.3, 96, 36), (0.1, 0, 0.15), dict(floor=0.0)),
            ("sphere", sphere, (0.1, 0, 0.0), dict(pinned=np.flatnonzero(sphere[0][:, 2] > 0.098)))]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=96)
    ap.add_argument("--seconds", type=int, default=40)
    a = ap.parse_args()
    for name, (V, F), lit, kw in scenes():
        E = np.unique(np.sort(np.vstack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), 1), axis=0)
        l0 = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
        for setting, extra in SETTINGS.items():
            sim = thinburn.Simulation(V, F, cells=a.cells, **kw, **extra)
            sim.ignite(lit)
            out = []
            for k in range(24 * a.seconds):
                sim.step(1 / 24)
                if k % 240 == 239:
                    P = sim.vertex_positions()
                    r = np.abs(np.linalg.norm(P[E[:, 0]] - P[E[:, 1]], axis=1) / l0 - 1)
                    ch = sim.vertex_char()
                    unburnt = (ch[E[:, 0]] == 0) & (ch[E[:, 1]] == 0)
                    out.append(f"{100 * np.percentile(r[unburnt], 99):5.2f} %")
            print(f"{name:8s} {setting:9s} {sim.geometry:7s} {sim.lattice_couples:4d} couples  unburnt p99: "
                  + "  ".join(out), flush=True)


if __name__ == "__main__":
    main()
