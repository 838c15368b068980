"""Before/after check that a change keeps simulations bit-identical: run with the old build
(`python scripts/bit_identical.py save old.npz`), then with the new (`... compare old.npz`).
The A4 sheet on a table (64 cells, 8 s) and the lantern (40 cells, 6 s): vertex positions and
ignition times."""
import sys, numpy as np
from thinburn import demo
out = {}
for name, scene, cells, T in [("a4", demo.default_scene("paper"), 64, 8.0),
                              ("lantern", demo.shell_scene("lantern"), 40, 6.0)]:
    sim = demo.build(scene, cells=cells)
    sim.run(T, dt=1/24)
    out[name + "_pos"] = sim.vertex_positions()
    out[name + "_t"] = sim.ignition_times()
mode, path = sys.argv[1], sys.argv[2]
if mode == "save":
    np.savez(path, **out)
else:
    ref = np.load(path)
    for k in out:
        a, b = ref[k], out[k]
        same = np.array_equal(a, b)
        print(k, "bit-identical" if same else f"DIFFERS max {np.nanmax(np.abs(np.where(np.isfinite(a-b), a-b, 0)))}")
