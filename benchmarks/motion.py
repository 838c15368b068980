"""The motion part of ``python -m benchmarks``: how far the demo scenes' motion at a step dt is
from a fine-step reference, against what the run cost (issue #12: the motion's row of speed
against accuracy).

Each scene runs `duration` seconds of simulated time at 64 cells on one thread. The error is the
RMS distance of the mesh's vertices from the reference run's (backward Euler at `ref_dt`), as a
share of the reference's RMS displacement from rest. The reference is the finest run, not an
exact solution: an integrator converging to another answer shows as an error that stops falling.
"""
from __future__ import annotations

import time

import numpy as np

from thinburn.demo import build, default_scene

from .perf import _pyplot, save_figure

MOTION_INTEGRATORS = ("implicit", "bdf2", "symplectic")
# (label, preset, wind along +x in m/s or None for the scene's own)
# Every preset's demo scene (demo.default_scene), with and without wind (issue #12, item 3).
MOTION_SCENES = (("paper on a table", "paper", None), ("paper on a table, 3 m/s wind", "paper", 3.0),
                 ("hard paper on a table", "hard_paper", None),
                 ("hard paper on a table, 3 m/s wind", "hard_paper", 3.0),
                 ("cloth held at its corners", "cloth", None), ("cloth held, 3 m/s wind", "cloth", 3.0),
                 ("silk held at its corners", "silk", None), ("silk held, 3 m/s wind", "silk", 3.0),
                 ("curtain in its wind", "curtain", None),
                 # Along its plane the curtain flutters or stands out as a sail (docs/dynamics.md §9).
                 ("curtain, 3 m/s wind along its plane", "curtain", 3.0))


def motion_run(material, wind, integrator, dt, duration, threads=1):
    """(rest, final vertex positions, seconds) of one run of the preset's demo scene."""
    sim = build(default_scene(material), material=material, cells=64, threads=threads)
    sim.set_dynamics(integrator=integrator)
    if wind is not None:
        sim.wind = (wind, 0.0, 0.0)
    rest = sim.vertex_positions()
    t0 = time.perf_counter()
    sim.run(duration, dt=dt)
    return rest, sim.vertex_positions(), time.perf_counter() - t0


def relative_error(x, ref, rest) -> float:
    """RMS vertex distance of x from ref over ref's RMS displacement from rest."""
    moved = np.sqrt(((ref - rest) ** 2).sum(1).mean())
    return float(np.sqrt(((x - ref) ** 2).sum(1).mean()) / max(moved, 1e-12))


def bench_motion(dts, ref_dt, duration, log, scenes=MOTION_SCENES, integrators=MOTION_INTEGRATORS):
    rows = []
    for label, material, wind in scenes:
        rest, ref, ref_s = motion_run(material, wind, "implicit", ref_dt, duration)
        moved = float(np.sqrt(((ref - rest) ** 2).sum(1).mean()))
        for integ in integrators:
            for dt in dts:
                _, x, secs = motion_run(material, wind, integ, dt, duration)
                err = relative_error(x, ref, rest)
                rows.append(dict(part="motion", scene=label, material=material, wind=wind,
                                 method=integ, dt=dt, duration=duration, ref_dt=ref_dt,
                                 moved=moved, error=err, seconds=secs, ref_seconds=ref_s))
                log(f"motion      {label:30s} {integ:10s} dt=1/{round(1 / dt):<4d} "
                    f"error={err:.3f} seconds={secs:.3f} (moved {1000 * moved:.1f} mm)")
    return rows


def plot_motion(rows, path):
    plt = _pyplot()
    mrows = [r for r in rows if r["part"] == "motion"]
    scenes = list(dict.fromkeys(r["scene"] for r in mrows))
    # Scenes in bands of at most five columns, each band a row against dt over one against time.
    ncols = min(5, len(scenes))
    bands = -(-len(scenes) // ncols)
    fig, grid = plt.subplots(2 * bands, ncols, figsize=(4.2 * ncols, 7.5 * bands), squeeze=False)
    for ax in grid.flat:
        ax.set_visible(False)
    for k, scene in enumerate(scenes):
        band, col = divmod(k, ncols)
        axes = grid[2 * band: 2 * band + 2]
        srows = [r for r in mrows if r["scene"] == scene]
        for j, m in enumerate(MOTION_INTEGRATORS):
            mr = sorted((r for r in srows if r["method"] == m), key=lambda r: -r["dt"])
            if not mr:
                continue
            err = [max(r["error"], 1e-4) for r in mr]
            axes[0][col].plot([r["dt"] for r in mr], err, "o-", color=f"C{j}", label=m)
            axes[1][col].plot([r["seconds"] for r in mr], err, "o-", color=f"C{j}", label=m)
        axes[0][col].set_title(f"{scene}\n(reference moved {1000 * srows[0]['moved']:.3g} mm)", fontsize=9)
        for row, xl in ((0, "dt (s)"), (1, "seconds per run")):
            ax = axes[row][col]
            ax.set_visible(True)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.axhline(0.15, color="k", lw=0.8, ls="--", label="15 % (issue #12)")
            ax.set_xlabel(xl)
            ax.set_ylabel("RMS error / RMS motion (floor 1e-4)")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
    save_figure(fig, path)
