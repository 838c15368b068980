#!/usr/bin/env python3
"""How far the lattice's springs sit from their rest lengths on each preset's demo scene.

    python scripts/lattice_strain.py [--seconds 40] [--cells 128] [--k-limit 0]

Per preset: the median, 99th percentile and largest of step_stats()["max_strain"] (the worst
|l / L - 1| among the awake vertices' springs at each step's end), the implicit step's redos
for an overstretched spring, and the most substeps a frame took. docs/dynamics.md §4 quotes it.
"""
from __future__ import annotations

import argparse

import numpy as np

from thinburn.demo import build, default_scene
from thinburn.materials import MATERIALS


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=40.0)
    ap.add_argument("--cells", type=int, default=128)
    ap.add_argument("--k-limit", type=float, default=None, help="the fabrics' knee (default the core's; 0: none)")
    args = ap.parse_args()
    for material in MATERIALS:
        sim = build(default_scene(material), material, cells=args.cells, threads=1)
        if args.k_limit is not None:
            sim.set_dynamics(k_limit=args.k_limit)
        strain, redos, substeps = [], 0, 0
        for _ in range(int(round(args.seconds * 24))):
            sim.step(1 / 24)
            s = sim.step_stats()
            strain.append(s["max_strain"])
            redos += s["stretch_redos"]
            substeps = max(substeps, s["substeps"])
        print(f"{material:10s} max strain median {np.median(strain):.3f} p99 {np.percentile(strain, 99):.3f} "
              f"max {max(strain):.3f}; stretch redos {redos}; most substeps {substeps}", flush=True)


if __name__ == "__main__":
    main()
