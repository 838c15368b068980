"""How far frame-sized steps are from a fine-step run once the lattice bends softly
(docs/materials.md, "Why paper keeps its lattice's bending"; docs/dynamics.md §1.1).

    python -m benchmarks.soft_bending_dt paper     # the A4 demo, B and wind varied
    python -m benchmarks.soft_bending_dt fabrics   # cloth, silk, curtain at their presets B

Each run is the motion bench's (benchmarks/motion.py: 64 cells, one thread, 20 s); the
error is the RMS vertex distance from a 1/480 s backward-Euler run over that run's RMS motion,
at 1/24 s (backward Euler and symplectic) and at 1/96 s (backward Euler).
"""
import sys

import numpy as np

from benchmarks import motion as bm

PAPER = ((None, 3.0), (1e-3, 1.0), (1e-3, 3.0), (3e-4, 3.0), (6e-5, 2.0))


def rigidity(B):
    """Make the bench's scenes use flexural_rigidity B (None: the preset's)."""
    build = bm.__dict__.setdefault("_plain_build", bm.build)
    if B is None:
        bm.build = build
        return

    def with_B(*a, **k):
        sim = build(*a, **k)
        sim.set_dynamics(flexural_rigidity=B)
        return sim
    bm.build = with_B


def compare(material, wind, B):
    rigidity(B)
    rest, ref, _ = bm.motion_run(material, wind, "implicit", 1 / 480, 20.0)
    moved = np.sqrt(((ref - rest) ** 2).sum(1).mean())
    errs = []
    for integrator, dt in (("implicit", 1 / 24), ("implicit", 1 / 96), ("symplectic", 1 / 24)):
        _, x, _ = bm.motion_run(material, wind, integrator, dt, 20.0)
        errs.append(bm.relative_error(x, ref, rest))
    print(f"{material:8s} B={'preset' if B is None else f'{B:g}':7s} wind={wind} m/s  reference moved "
          f"{moved * 1e3:9.2f} mm RMS  backward Euler {100 * errs[0]:.3g} % (1/96 s: {100 * errs[1]:.3g} %)  "
          f"symplectic {100 * errs[2]:.3g} %", flush=True)


def main(which):
    if which == "paper":
        for B, wind in PAPER:
            compare("paper", wind, B)
    else:
        for material in ("cloth", "silk", "curtain"):
            compare(material, None, None)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "fabrics")
