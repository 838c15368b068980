"""A 60 x 60 cm silk (61 x 61 vertices) hanging from its two top corners, 5 s at 1/24 s, no fire
(an artist's trial; docs/dynamics.md §3.4, "Sweeps"): per lattice, the largest strain of the
couples' sides after each of the first three frames (and their substeps), of the mesh's edges after them and over
seconds 1 to 5, the mesh's largest move in a frame over the last second, and the seconds taken.

With --corners, instead: after 3 s, per pin the largest strain of the mesh edges within 3 cm
of it (--mirror mirrors the mesh in x, so its diagonals run the other way), the couples' sides
and the diagonal x_b + x_c - 2 x_a at the two pinned corners, and the most squashed edge and
where it lies.

    python scripts/pinned_silk.py [--lattices 16 32] [--k-limit 1] [--corners [--mirror]]
"""
import argparse
import time

import numpy as np

import thinburn
from thinburn._mesh_measures import EdgeStrain
from thinburn.scenes import rect_sheet


def side_strain(sim, m):
    c = sim.lattice_positions().reshape(m, m, 2, 3).mean(2)
    r = sim.lattice_rest_positions().reshape(m, m, 2, 3).mean(2)
    sx = np.linalg.norm(c[:, 1:] - c[:, :-1], axis=-1) / np.linalg.norm(r[:, 1:] - r[:, :-1], axis=-1) - 1
    sy = np.linalg.norm(c[1:] - c[:-1], axis=-1) / np.linalg.norm(r[1:] - r[:-1], axis=-1) - 1
    return max(np.abs(sx).max(), np.abs(sy).max())


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lattices", type=int, nargs="+", default=[16, 32])
    ap.add_argument("--k-limit", type=float, default=None, help="the knee's coefficient (default the core's)")
    ap.add_argument("--corners", action="store_true", help="the strains near each pin after 3 s")
    ap.add_argument("--mirror", action="store_true", help="with --corners: the mesh mirrored in x")
    a = ap.parse_args()
    v, f = rect_sheet(0.6, 0.6, nx=61, ny=61, vertical=True, z=0.5)
    if a.mirror:
        v[:, 0] = 0.6 - v[:, 0]
        f = np.ascontiguousarray(f[:, ::-1])
    top = np.flatnonzero(np.isclose(v[:, 2], v[:, 2].max()))
    pins = [top[np.argmin(v[top, 0])], top[np.argmax(v[top, 0])]]
    strain = EdgeStrain(v, f)
    if a.corners:
        return corners(v, f, pins, strain, a)
    for m in a.lattices:
        kw = {} if a.k_limit is None else dict(k_limit=a.k_limit)
        sim = thinburn.Simulation(v, f, material="silk", cells=48, pinned=pins, lattice=m, **kw)
        t0 = time.perf_counter()
        sides, mesh, later, moves, substeps = [], [], 0.0, [], 0
        prev = sim.vertex_positions()
        for frame in range(1, 121):
            sim.step(1 / 24)
            x = sim.vertex_positions()
            if frame <= 3:
                substeps += sim.step_stats()["substeps"]
                sides.append(side_strain(sim, m))
                mesh.append(strain(x).max())
            if frame > 24:
                later = max(later, strain(x).max())
            if frame > 96:
                moves.append(np.linalg.norm(x - prev, axis=1).max())
            prev = x
        print(f"lattice {m}: couples' sides {', '.join(f'{100 * s:.2f}' for s in sides)} % and mesh edges "
              f"{', '.join(f'{100 * s:.2f}' for s in mesh)} % after frames 1-3 ({substeps} substeps); mesh edges at most "
              f"{100 * later:.2f} % over seconds 1-5; largest move in a frame over the last second "
              f"{1e3 * max(moves):.3f} mm; {time.perf_counter() - t0:.1f} s", flush=True)


def corners(v, f, pins, strain, a):
    edges = strain.edges
    mid = 0.5 * (v[edges[:, 0]] + v[edges[:, 1]])
    rest = np.linalg.norm(v[edges[:, 0]] - v[edges[:, 1]], axis=1)
    for m in a.lattices:
        kw = {} if a.k_limit is None else dict(k_limit=a.k_limit)
        sim = thinburn.Simulation(v, f, material="silk", cells=48, pinned=pins, lattice=m, **kw)
        sim.run(3.0, dt=1 / 24)
        x = sim.vertex_positions()
        signed = np.linalg.norm(x[edges[:, 0]] - x[edges[:, 1]], axis=1) / rest - 1.0
        c = sim.lattice_positions().reshape(m, m, 2, 3).mean(2)
        r = sim.lattice_rest_positions().reshape(m, m, 2, 3).mean(2)
        side = lambda p, q: 100 * (np.linalg.norm(c[p] - c[q]) / np.linalg.norm(r[p] - r[q]) - 1)  # noqa: E731
        # The corner's diagonal x_b + x_c - 2 x_a (docs/dynamics.md §3.4, "Corners").
        diag = lambda a, b, d: 100 * (np.linalg.norm(c[b] + c[d] - 2 * c[a]) /  # noqa: E731
                                      np.linalg.norm(r[b] + r[d] - 2 * r[a]) - 1)
        near = [100 * signed[np.linalg.norm(mid - v[p], axis=1) < 0.03].max() for p in pins]
        k = int(np.argmin(signed))
        print(f"lattice {m}{' (mirrored)' if a.mirror else ''}: edges within 3 cm of the pin at x = "
              f"{v[pins[0], 0]:.1f} m at most {near[0]:.2f} % long, of the pin at x = {v[pins[1], 0]:.1f} m "
              f"{near[1]:.2f} %; the pinned corners' couple sides {side((-1, 0), (-1, 1)):.2f} / "
              f"{side((-1, 0), (-2, 0)):.2f} % and {side((-1, -1), (-1, -2)):.2f} / {side((-1, -1), (-2, -1)):.2f} %, "
              f"their diagonals {diag((-1, 0), (-1, 1), (-2, 0)):.2f} and {diag((-1, -1), (-1, -2), (-2, -1)):.2f} %; "
              f"the most squashed edge {100 * signed[k]:.2f} % at x = {mid[k, 0]:.3f}, z = {mid[k, 2]:.3f} m "
              f"(rest)", flush=True)


if __name__ == "__main__":
    main()
