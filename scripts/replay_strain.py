"""Replay a scene file (thinburn.scenefile, as the add-on exports it) in the core and print
how its unburnt mesh stretches: every `--every` frames the p99 of |l/L - 1| over edges whose
two vertices are unburnt, as chords (the mesh) and along the surface (SurfaceStrain), the worst
edge along the surface, the lowest couple centre (mm) and the burning cells; at the end the
seconds per phase and the steps' substeps and stretch redos. The Blender pile's strain and cost
reproduced outside Blender (docs/blender.md, "pile"; docs/dynamics.md §9):

    python scripts/render_drape.py --scenes pile --frames 120 --render --export-scene /tmp/scenes
    python scripts/replay_strain.py /tmp/scenes/pile.npz [--dynamics contact_rounds=0]
"""
import argparse

import numpy as np

from thinburn import scenefile, wedge
from thinburn._mesh_measures import EdgeStrain, SurfaceStrain


def number(text):
    """An int where the text is one, else a float (1e-3, 0.5)."""
    try:
        return int(text)
    except ValueError:
        return float(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", help="a scene file (.npz or .json)")
    ap.add_argument("--every", type=int, default=12, help="frames between measures")
    ap.add_argument("--dynamics", nargs="*", default=[], metavar="KEY=VALUE",
                    help="set_dynamics overrides, e.g. contact_rounds=0")
    a = ap.parse_args()
    spec = scenefile.load_scene(a.scene)
    sim, _, fps, frames = wedge.simulation_for(spec, {})
    if a.dynamics:
        sim.set_dynamics(**{k: number(v) for k, v in (kv.split("=", 1) for kv in a.dynamics)})
    v, f = np.asarray(spec.vertices), np.asarray(spec.faces)
    chord, surface = EdgeStrain(v, f), SurfaceStrain(v, f)
    e = chord.edges
    print(f"{a.scene}: {frames} frames at {fps:g} fps, lattice {sim.lattice_size}, {sim.lattice_couples} couples")

    work = {"substeps": 0, "stretch_redos": 0, "redone frames": 0}

    def measure(k, s):
        if k:  # the step before this frame's record
            st = s.step_stats()
            work["substeps"] += st["substeps"]
            work["stretch_redos"] += st["stretch_redos"]
            work["redone frames"] += st["stretch_redos"] > 0
        if k % a.every:
            return
        char = s.vertex_char()
        keep = (char[e[:, 0]] == 0) & (char[e[:, 1]] == 0)
        on_surface = surface(s)[keep]
        lowest = 1000 * s.lattice_positions().reshape(-1, 2, 3).mean(axis=1)[:, 2].min()
        print(f"frame index {k:4d}: unburnt p99 chords {100 * np.percentile(chord(s.vertex_positions())[keep], 99):5.2f} %, "
              f"along the surface {100 * np.percentile(on_surface, 99):5.2f} % (worst edge {100 * on_surface.max():5.1f} %), "
              f"lowest couple centre {lowest:6.2f} mm, burning cells {int((s.cell_states() == 1).sum())}", flush=True)

    wedge.run_frames(sim, spec, fps, frames, measure)
    print("seconds per phase:", {k: round(v, 2) for k, v in sim.phase_seconds().items()})
    print("steps' work (substeps of each step's last pass; stretch redos, docs/dynamics.md §4):", work)


if __name__ == "__main__":
    main()
