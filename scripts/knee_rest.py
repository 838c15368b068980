"""Where a held fabric rests against the substeps it takes (docs/dynamics.md §3.4, "The knee"):
the silk demo (or --material's) held at its corners, per k_limit, the lowest mesh point after 10 s at 1, 4, 16, 64
and 256 substeps a frame (64 cells, no fire); with --burning, the same demo at 128 cells on the
bench's 16k mesh, lit, the lowest point over seconds 1.5 to 3.75 at 1, 4, 16 and 64 substeps.
A rest that does not depend on the step gives one height per row. k_limit "off" takes the
strain limit off as well (strain_limit=0).

    python scripts/knee_rest.py [--k-limits 0 0.3 1 3 off] [--burning] [--material cloth]
"""
import argparse

import numpy as np

import thinburn
from thinburn.demo import build, default_scene


def still(k_limit, substeps, material):
    scene = default_scene(material)
    kw = dict(strain_limit=0.0) if k_limit == "off" else dict(k_limit=float(k_limit))
    sim = thinburn.Simulation(scene.vertices, scene.faces, material=material, cells=64, floor=scene.floor,
                              pinned=scene.pinned, substeps=substeps, **kw, **scene.params)
    sim.run(10.0, dt=1 / 24)
    return [1e3 * sim.vertex_positions()[:, 2].min()]


def burning(k_limit, substeps, material):
    sim = build(default_scene(material, vertices=16000), material, cells=128)
    sim.set_dynamics(substeps=substeps, **(dict(strain_limit=0.0) if k_limit == "off" else dict(k_limit=float(k_limit))))
    sim.run(1.5, dt=1 / 24)
    low = []
    for _ in range(54):
        sim.step(1 / 24)
        low.append(1e3 * sim.vertex_positions()[:, 2].min())
    return low


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--k-limits", nargs="+", default=["0", "1"])
    ap.add_argument("--burning", action="store_true")
    ap.add_argument("--material", default="silk", choices=sorted(thinburn.MATERIALS))
    a = ap.parse_args()
    counts, run = ((1, 4, 16, 64), burning) if a.burning else ((1, 4, 16, 64, 256), still)
    for k in a.k_limits:
        cells = []
        for n in counts:
            z = run(k, n, a.material)
            cells.append(f"{n}: {min(z):.1f}" + (f"-{max(z):.1f}" if len(z) > 1 else "") + " mm")
        print(f"k_limit {k}: lowest point at " + ", ".join(cells), flush=True)


if __name__ == "__main__":
    main()
