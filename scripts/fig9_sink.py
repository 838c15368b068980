"""Fig. 9: the demo's cloth held at its corners, lit in the middle, sinks as it burns. Prints the
lowest point after 8 s (the sag has settled), its highest value during the burn and after the
whole burn (90 s), for ash strengths 0.1, 0.03 (the fabrics' preset) and 0.01
(docs/materials.md, ash_strength):  python scripts/fig9_sink.py [--k-limit 0]

--k-limit: the fabrics' knee (docs/dynamics.md §3.4; default the core's, 0: none)."""
import argparse

import numpy as np

import thinburn
from thinburn.demo import default_scene


def lowest_points(ash_strength, cells=48, **dynamics):
    scene = default_scene("cloth")
    material = thinburn.MATERIALS["cloth"].with_(ash_strength=ash_strength)
    sim = thinburn.Simulation(scene.vertices, scene.faces, material=material, cells=cells,
                              floor=scene.floor, pinned=scene.pinned, **scene.params, **dynamics)
    sim.ignite(scene.vertices.mean(0), time=0.0, radius=0.01)
    sim.run(8.0, dt=1 / 24)
    low = [sim.vertex_positions()[:, 2].min()]
    while sim.time < 90.0 - 1e-9:
        sim.run(2.0, dt=1 / 24)
        low.append(sim.vertex_positions()[:, 2].min())
    return low[0], max(low), low[-1], float(np.mean(sim.vertex_char() > 0.5))


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--k-limit", type=float, default=None)
    args = ap.parse_args()
    extra = {} if args.k_limit is None else dict(k_limit=args.k_limit)
    for ash in (0.1, 0.03, 0.01):
        before, top, after, burnt = lowest_points(ash, **extra)
        print(f"ash_strength {ash:<5}: lowest point {1e3 * before:.2f} mm at 8 s, up to {1e3 * top:.2f} mm "
              f"while it burns, {1e3 * after:.2f} mm at 90 s ({1e3 * (before - after):.1f} mm down; "
              f"{100 * burnt:.0f} % burnt)", flush=True)
