"""Heat ignites (docs/heat.md): two 15 cm paper sheets, the lower on a table lit at its centre,
the upper held `gap` above it; when does the upper catch fire from the heat, and how hot does it
get? `python scripts/heat_ignition.py [gap ...]` (defaults 0.01 0.03 0.1 0.5 m)."""
import sys

import numpy as np

import thinburn
from thinburn.scenes import rect_sheet


def stack(gap, n=21, size=0.15):
    a, fa = rect_sheet(size, size, nx=n, ny=n, z=0.0)
    b, fb = rect_sheet(size, size, nx=n, ny=n, z=gap)
    return np.vstack([a, b]), np.vstack([fa, fb + len(a)])


def run(gap, seconds=8.0, cells=32):
    v, f = stack(gap)
    sim = thinburn.Simulation(v, f, cells=cells, floor=0.0, pinned=v[:, 2] > gap / 2, heat_ignites=True,
                              threads=1)
    sim.ignite((0.0, 0.0, 0.0), time=0.0, radius=0.008)  # the lower sheet only
    upper = sim.cell_positions()[:, 2] > gap / 2
    first, hottest = None, 0.0
    while sim.time < seconds:
        sim.step(1 / 24)
        hottest = max(hottest, float(sim.cell_temperature()[upper].max()))
        if first is None and (sim.cell_states()[upper] > 0).any():
            first = sim.time
    return first, hottest


if __name__ == "__main__":
    for gap in [float(g) for g in sys.argv[1:]] or [0.01, 0.03, 0.1, 0.5]:
        first, hottest = run(gap)
        print(f"gap {gap:5.2f} m: upper sheet {'ignites at %.2f s' % first if first else 'never ignites'}"
              f" (8 s), hottest {hottest:.4g} K above ambient")
