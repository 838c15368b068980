"""Issue #12 item 4, large steps: a 1 x 2 m sheet (21 x 41 vertices) pinned at a corner falls
from flat, at dt = 1/24 s for 10 s and at dt = 1 s and 10 s for three steps each. Prints the
99th percentile (worst over the steps) and the last step's largest |strain| of the mesh edges,
and the farthest vertex from the pin over the sheet's diagonal: `python scripts/big_steps.py`."""
import numpy as np, thinburn
from thinburn.scenes import rect_sheet
v, f = rect_sheet(1.0, 2.0, nx=21, ny=41)
E = np.unique(np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1), axis=0)
L0 = np.linalg.norm(v[E[:, 0]] - v[E[:, 1]], axis=1)
for mat in ["cloth", "paper"]:
    for dt in [1/24, 1.0, 10.0]:
        sim = thinburn.Simulation(v, f, material=mat, cells=32, pinned=[0])
        n = max(1, int(round(10.0 / dt))) if dt < 1 else 3
        worst = 0; far = 0
        for _ in range(n):
            sim.step(dt); p = sim.vertex_positions()
            L = np.linalg.norm(p[E[:, 0]] - p[E[:, 1]], axis=1)
            worst = max(worst, np.percentile(np.abs(L / L0 - 1), 99)); far = max(far, np.linalg.norm(p - p[0], axis=1).max() / np.hypot(1, 2))
        print(mat, dt, "p99 edge strain %.4f" % worst, "max |strain| %.3f" % np.abs(L/L0-1).max(), "farthest/diag %.3f" % far, sim.step_stats()["substeps"], flush=True)
