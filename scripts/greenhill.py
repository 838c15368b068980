"""A sheet pinned along its bottom edge against Greenhill's self-weight buckling: a column clamped
at its base stands while shorter than l_c = (7.837 B / q)^(1/3) (B: flexural rigidity per unit
width, q: weight per unit area) and falls over when taller. The sheet starts bowed by the
`imperfection` (docs/dynamics.md §1.2); this finds, by bisection on the height, where its
out-of-plane deflection stops decaying and grows, and prints that height over Greenhill's l_c for
lattices of M couples up the sheet:  python scripts/greenhill.py [--lattices 5 9 17]
With --issue, issue #12's 1 x 1.4 m paper sheet (64 cells, chosen lattice) instead: how far its
top edge leans out of its plane, and how high it stands, every 4 s for 24 s."""
import argparse

import numpy as np

import thinburn
from thinburn.scenes import rect_sheet

GREENHILL = 7.837  # (l_c^3 q / B) of a column clamped at its base, free at its top


def standing_sheet(height, lattice, material="paper", cells=32, **params):
    """A square paper sheet of side height standing in the xz-plane, its bottom edge pinned."""
    v, f = rect_sheet(height, height, nx=2 * lattice + 1, ny=2 * lattice + 1, vertical=True)
    bottom = np.flatnonzero(v[:, 2] == v[:, 2].min())
    top = np.flatnonzero(v[:, 2] == v[:, 2].max())
    sim = thinburn.Simulation(v, f, material=material, cells=cells, lattice=lattice, pinned=bottom, **params)
    return sim, top


def critical_height(sim, height):
    """Greenhill's l_c for the sheet: its flexural rigidity (the lattice's own, or the share of
    it a material's membrane springs keep) and its weight per area."""
    q = sim.control_masses().sum() * 9.81 / height ** 2
    return (GREENHILL * sim.bending_share * sim.lattice_rigidity / q) ** (1.0 / 3.0)


def falls(height, lattice, material="paper", seconds=16.0, dt=1 / 24, **params):
    """Whether the top edge ends, after seconds, farther from where the sheet's mesh put it than
    ten times the bow it started with (a fallen sheet hangs from its pins, 2 heights away; a
    standing one springs back flat, squashed by its weight well under the bow)."""
    sim, top = standing_sheet(height, lattice, material, **params)
    start = sim.vertex_positions()[top]  # bowed; the mesh's input is flat in y = 0
    start[:, 1] = 0.0
    bow = sim.params.imperfection * np.sqrt(2.0) * height
    sim.run(seconds, dt=dt)
    return np.linalg.norm(sim.vertex_positions()[top] - start, axis=1).mean() > 10.0 * bow


def threshold(lattice, material="paper", iterations=8, **params):
    """The height where the sheet starts to fall, over Greenhill's l_c at that height (a lattice
    finer than 4 cm spacing is thinner, and its rigidity goes as its thickness squared), by
    bisection on the height in [0.3, 3] x l_c of a 1 m sheet; and the bracket, likewise."""
    def over_lc(height):
        return height / critical_height(standing_sheet(height, lattice, material, **params)[0], height)

    lo, hi = 0.3, 3.0
    lc1 = critical_height(standing_sheet(1.0, lattice, material, **params)[0], 1.0)
    for _ in range(iterations):
        mid = np.sqrt(lo * hi)
        if falls(mid * lc1, lattice, material, **params):
            hi = mid
        else:
            lo = mid
    height = np.sqrt(lo * hi) * lc1
    return height, over_lc(height), (over_lc(lo * lc1), over_lc(hi * lc1))


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--lattices", type=int, nargs="+", default=[5, 9, 17])
    ap.add_argument("--material", default="paper")
    ap.add_argument("--issue", action="store_true")
    args = ap.parse_args()
    if args.issue:
        v, f = rect_sheet(1.0, 1.4, nx=41, ny=57, vertical=True)
        sim = thinburn.Simulation(v, f, material="paper", cells=64, pinned=np.flatnonzero(v[:, 2] == 0.0))
        top = np.flatnonzero(v[:, 2] == v[:, 2].max())
        for _ in range(6):
            sim.run(4.0)
            p = sim.vertex_positions()[top]
            print(f"t = {sim.time:4.1f} s: top edge {100 * np.abs(p[:, 1]).mean():5.1f} cm out of plane, "
                  f"at z = {p[:, 2].mean():.2f} m (pins at 0)", flush=True)
        raise SystemExit
    for m in args.lattices:
        height, ratio, (lo, hi) = threshold(m, args.material)
        print(f"{args.material} lattice {m:>2}: falls from {100 * height:.1f} cm = {ratio:.3f} x Greenhill's l_c "
              f"(bracket {lo:.3f}-{hi:.3f})", flush=True)
