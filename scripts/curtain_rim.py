"""Why a pleated curtain's side edge stretches in wind (docs/lattice.md, "Detail finer than the
lattice"): the mesh beyond the outermost couples is extrapolated from them. Builds the curtain
of scripts/pleated_curtain.py (2 cm pleats every 20 cm, 1.5 m/s wind, 64 cells, lattice=22),
runs it 2 s, and re-embeds its side edge (x = 0) in a control surface built alike (its couples
matched to the simulation's by nearest rest position). Prints the MLS weights' sum of |w| on
the rim and inside, the largest weights of a rim point, and how much the embedding stretches
along the side edge and 1.25 cm in from it, beside the couples' own largest strain.

    python scripts/curtain_rim.py
"""
import numpy as np
from scipy.spatial import cKDTree

import thinburn
from thinburn import _core
from pleated_curtain import pleated  # scripts/ is on the path when a script runs


def main():
    v, f = pleated(0.02, 0.2)
    top = np.flatnonzero(np.isclose(v[:, 2], v[:, 2].max()))
    sim = thinburn.Simulation(v, f, material="curtain", cells=64, pinned=top, climb=0.4, lattice=22)
    # lattice=22 counts couples along sqrt(area): spacing sqrt(area) / 21 (cpp/shell.cpp).
    cs = _core.ControlSurface(v, f, np.sqrt(np.sum(sim.cell_areas())) / 21, sim.lattice_thickness)
    rest = sim.lattice_rest_positions().reshape(-1, 3)
    gap, perm = cKDTree(rest).query(np.asarray(cs.rest))
    cg = gap.reshape(-1, 2).max(1)
    off = np.asarray(cs.rest)[1::2][cg > 1e-6]
    print(f"{cs.couples} couples ({sim.lattice_couples} in the simulation); {len(off)} not the simulation's "
          f"(up to {1000 * cg.max():.1f} mm off), the nearest {1000 * np.min(np.hypot(off[:, 0], off[:, 2] - 1.3), initial=np.inf):.0f} mm from the spot")
    w = np.abs(np.asarray(cs.embed(v).weight)).sum(1)
    rim = (v[:, 0] < 1e-9) | (v[:, 0] > 1 - 1e-9) | (v[:, 2] < 0.05 + 1e-9) | (v[:, 2] > 1.45 - 1e-9)
    print("sum |w|: inside p50 %.2f max %.2f; rim p50 %.2f max %.2f"
          % (np.median(w[~rim]), w[~rim].max(), np.median(w[rim]), w[rim].max()))
    sim.wind = (0.0, 1.5, 0.0)
    sim.ignite((0.5, 0.0, 0.06), radius=0.02)
    for _ in range(48):
        sim.step(1 / 24)
    x = sim.lattice_positions().reshape(-1, 3)[perm]
    mid, mid0 = 0.5 * (x[0::2] + x[1::2]), 0.5 * (np.asarray(cs.rest)[0::2] + np.asarray(cs.rest)[1::2])
    z = np.linspace(1.25, 1.36, 45)
    for inset in (0.0, 0.0125):
        pts = np.c_[np.full_like(z, inset), np.full_like(z, 0.02 * np.sin(2 * np.pi * inset / 0.2)), z]
        e = cs.embed(pts)
        p = np.asarray(cs.deform(e, x))
        stretch = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(z)
        print(f"x = {inset:.4f} m, z 1.25-1.36 m: the embedding stretches up to {stretch.max():.2f}x")
        if inset == 0.0:
            k = int(np.argmax(stretch))
            ww = np.asarray(e.weight)[k]
            print("  a rim point's weights:", np.round(np.sort(ww[ww != 0])[::-1], 2).tolist())
    near = np.flatnonzero((mid0[:, 0] < 0.12) & (mid0[:, 2] > 1.1))
    tree = cKDTree(mid0)
    worst = 0.0
    for i in near:
        for j in tree.query_ball_point(mid0[i], 0.08):
            if j != i:
                worst = max(worst, abs(np.linalg.norm(mid[i] - mid[j]) / np.linalg.norm(mid0[i] - mid0[j]) - 1))
    print(f"the couples there: largest change of distance between neighbours {100 * worst:.1f} %")


if __name__ == "__main__":
    main()
