"""The performance parts of ``python -m benchmarks`` (see docs/bench.md).

  ffd      FfdLattice.deform throughput (vertices/s) against a memory-bandwidth bound measured
           in the same run (STREAM triad, thinburn._threads.measure_memory_bandwidth).
  frames   whole simulated frames at 128² cells for every preset's demo scene, with its own
           mesh and remeshed to about 16k vertices; the paper's ~10 frames/s for reference.
  scaling  per-frame cost against the cell count (same scene, same physical fire) and
           against the mesh's vertex count.
  active   per-frame cost on a 1 m sheet with a small fire at several N: cost per unit of
           active work against N.

A frame is ``sim.step(1/24)`` then ``sim.vertex_positions()``; each frame is timed on its own
and ``sim.stats()`` read after the timer stops, after an untimed warm-up. The simulation is
deterministic, so a run is repeated on a fresh simulation and each frame keeps its fastest
time over the runs.
"""
from __future__ import annotations

import math
import time

import numpy as np

from thinburn import _core
from thinburn._threads import measure_memory_bandwidth
from thinburn.demo import build, default_scene
from thinburn.lattice import flat_rest
from thinburn.materials import MATERIALS
from thinburn.scenes import rect_sheet
from thinburn.simulation import Simulation

FRAME_DT = 1.0 / 24.0
STAT_KEYS = ("front_active", "burning", "fringe", "awake", "particles", "cg_iterations", "factorizations")
PAPER_REFERENCE = dict(
    part="frames", method="paper (Liu et al. 2009)", resolution=128, frames_per_second=10.0,
    ms_per_frame=100.0, reference=True,
    machine="Pentium IV, 3.0 GB RAM, nVidia 7800; rendering included",
    quote="All simulations were run on a Pentium IV with 3.0 G RAM, nVidia 7800 display card. "
          "The thin-shell object is divided into 128 × 128 cells. The rendering rates are about "
          "10 frames per second.")
GOAL_FPS = 500.0  # issue #6: 128² cells, 16k-vertex mesh, 2 cores

# ---------------------------------------------------------------- ffd

FFD_M = 33  # couples per side of the benchmark lattice (the Simulation's at N = 512)


def ffd_bytes_per_point(stencil: int) -> int:
    """Bytes FfdLattice.deform moves per point: reads stencil couple indices (int32) and
    weights (float64), r (float64) and the rest point (3 float64); writes the point (3
    float64). The per-couple displacement table (64 B a couple) stays in cache: not counted;
    nor is the write-allocate read of the output (STREAM does not count it either)."""
    return stencil * (4 + 8) + 8 + 3 * 8 + 3 * 8


def ffd_lattice(M: int = FFD_M):
    """A 1 m square lattice, 2 cm thick, displaced by a smooth bump (every couple moves)."""
    rest = flat_rest(M, 1.0, 1.0, 0.02)
    lat = _core.FfdLattice(M, rest)
    x, y = rest[:, 0], rest[:, 1]
    bump = 0.01 * np.sin(np.pi * x) * np.sin(np.pi * y)
    lat.positions = rest + np.stack([0.1 * bump, -0.1 * bump, bump], axis=1)
    return lat


def ffd_points(n: int, M: int = FFD_M):
    """n points in a mesh's order (row-major over a grid covering the lattice), mid-thickness
    as the Simulation embeds its mesh: (lattice coordinates (n, 3), rest positions (n, 3))."""
    side = max(2, math.ceil(math.sqrt(n)))
    k = np.arange(n)
    s = (k // side) / (side - 1) * (M - 1)
    t = (k % side) / (side - 1) * (M - 1)
    params = np.stack([np.minimum(s, M - 1), t, np.full(n, 0.5)], axis=1)
    rest = np.stack([t / (M - 1), params[:, 0] / (M - 1), np.zeros(n)], axis=1)
    return params, rest


def best_seconds(fn, repeat: int, min_seconds: float = 2e-3, budget: float = 0.25) -> float:
    """Seconds per call of fn: the best of at least `repeat` timings, and of as many more as
    fit in `budget` seconds (at most 200), so that a busy machine leaves some clean ones. A
    timing loops fn until min_seconds have passed, so short calls are not timer noise."""
    t0 = time.perf_counter()
    fn()
    once = max(time.perf_counter() - t0, 1e-7)
    calls = max(1, int(math.ceil(min_seconds / once)))
    best, rounds, start = math.inf, 0, time.perf_counter()
    while rounds < repeat or (time.perf_counter() - start < budget and rounds < 200):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - t0) / calls)
        rounds += 1
    return best


def bench_ffd(sizes, repeat, log, bandwidth_bytes=512 * 2**20, bandwidth_repeat=10, M=FFD_M):
    """FFD throughput rows and the bandwidth row. The bandwidth is probed before, between and
    after the deform timings of each method; the highest probe makes the bound (the fraction
    errs low; other work on the machine lowers a probe more often than it raises a timing)."""
    threads = int(_core.num_threads())
    rep = max(bandwidth_repeat, repeat)
    probes = [measure_memory_bandwidth(bandwidth_bytes, rep)]
    lat = ffd_lattice(M)
    rows = []
    for method in ("trilinear", "bspline"):
        if method != "trilinear":
            probes.append(measure_memory_bandwidth(bandwidth_bytes, rep))
        for n in sizes:
            params, rest = ffd_points(int(n), M)
            e = lat.embed(params, rest, method)
            out = np.empty((len(e), 3))
            secs = best_seconds(lambda: lat.deform_into(e, out), rep)
            alloc = best_seconds(lambda: lat.deform(e), rep)
            rows.append(dict(part="ffd", method=method, resolution=int(n), seconds=secs,
                             seconds_allocating=alloc, vertices_per_second=n / secs,
                             bytes_per_point=ffd_bytes_per_point(e.stencil), stencil=e.stencil,
                             lattice=M, threads=threads))
    probes.append(measure_memory_bandwidth(bandwidth_bytes, rep))
    bw = max(probes)
    for r in rows:
        r["bandwidth_bytes_per_second"] = bw
        r["bound_vertices_per_second"] = bw / r["bytes_per_point"]
        r["fraction"] = r["vertices_per_second"] / r["bound_vertices_per_second"]
        log(f"ffd         {r['method']:10s} n={r['resolution']:8d} {r['vertices_per_second'] / 1e6:7.1f} "
            f"Mvert/s bound {r['bound_vertices_per_second'] / 1e6:7.1f} fraction={r['fraction']:.2f}")
    rows.insert(0, dict(part="ffd", method="bandwidth", resolution=int(bandwidth_bytes),
                        seconds=3 * 8 * (bandwidth_bytes // 24) / bw, bytes_per_second=bw,
                        probes=probes, repeat=rep, threads=threads))
    log(f"ffd         bandwidth  {bandwidth_bytes / 2**20:.0f} MiB triad {bw / 1e9:.2f} GB/s "
        f"on {threads} thread(s) (probes {', '.join(f'{b / 1e9:.1f}' for b in probes)})")
    return rows


# ---------------------------------------------------------------- frames


def run_frames(sim, frames: int, warmup: int, dt: float = FRAME_DT):
    """Step `warmup` frames untimed, then time `frames` frames of step + vertex_positions.

    Returns (step ms (frames,), vertex_positions ms (frames,), {stat: (frames,)}) with the
    STAT_KEYS read from sim.stats() after each frame (0 where a key is absent)."""
    for _ in range(warmup):
        sim.step(dt)
    step_ms, pos_ms = np.empty(frames), np.empty(frames)
    stats = {k: np.zeros(frames) for k in STAT_KEYS}
    for f in range(frames):
        t0 = time.perf_counter()
        sim.step(dt)
        t1 = time.perf_counter()
        sim.vertex_positions()
        t2 = time.perf_counter()
        step_ms[f], pos_ms[f] = 1e3 * (t1 - t0), 1e3 * (t2 - t1)
        st = sim.stats()
        for k in STAT_KEYS:
            stats[k][f] = float(st.get(k, 0))
    return step_ms, pos_ms, stats


def best_frames(make_sim, frames: int, warmup: int, repeat: int, dt: float = FRAME_DT):
    """run_frames on `repeat` fresh simulations from make_sim(); the simulation is
    deterministic, so frame k does the same work in every run and its time is the fastest of
    the runs (the frames' best-of). Returns (step ms, vertex_positions ms, stats of run 1, sim)."""
    best_step = best_pos = stats = sim = None
    for _ in range(repeat):
        sim = make_sim()
        step_ms, pos_ms, st = run_frames(sim, frames, warmup, dt)
        if best_step is None:
            best_step, best_pos, stats = step_ms, pos_ms, st
        else:
            best_step, best_pos = np.minimum(best_step, step_ms), np.minimum(best_pos, pos_ms)
    return best_step, best_pos, stats, sim


def interleaved_best_frames(makers, frames, warmup, repeat, dt: float = FRAME_DT):
    """best_frames for several thread counts ({threads: make_sim}), their runs taken in turn
    (1, n, 1, n, ...) so that a change in the machine's other load between runs biases no
    count. Returns {threads: (step ms, vertex_positions ms, stats of run 1, sim)}."""
    best = {}
    for _ in range(max(1, repeat)):
        for threads, make in makers.items():
            step_ms, pos_ms, stats, sim = best_frames(make, frames, warmup, 1, dt)
            if threads in best:
                b = best[threads]
                step_ms, pos_ms, stats = np.minimum(b[0], step_ms), np.minimum(b[1], pos_ms), b[2]
            best[threads] = (step_ms, pos_ms, stats, sim)
    return best


def frame_summary(step_ms, pos_ms, stats) -> dict:
    """Per-run figures: fps = frames / total time, the mean and median frame, the share of
    vertex_positions (the mesh's FFD), and the mean of every active count."""
    ms = step_ms + pos_ms
    secs = float(ms.sum()) / 1e3
    out = dict(frames=int(len(ms)), seconds=secs, ms_per_frame=float(ms.mean()),
               median_ms=float(np.median(ms)), frames_per_second=len(ms) / secs,
               positions_ms=float(pos_ms.mean()))
    out.update({k: float(v.mean()) for k, v in stats.items()})
    return out


def bench_frames(materials, cells, frames, warmup, vertex_counts, repeat, thread_counts, log):
    """Rows per material, mesh (None = the demo's own) and thread count, plus the paper's
    reference row."""
    rows = []
    timed = {}
    for material in materials:  # the thread counts' runs interleave (interleaved_best_frames)
        for target in vertex_counts:
            scene = default_scene(material, vertices=target)
            makers = {t: (lambda t=t: build(scene, material, cells=cells, threads=t)) for t in thread_counts}
            for threads, result in interleaved_best_frames(makers, frames, warmup, repeat).items():
                timed[threads, material, target] = (scene, result)
    for threads in thread_counts:
        for material in materials:
            for target in vertex_counts:
                scene, (step_ms, pos_ms, stats, sim) = timed[threads, material, target]
                s = frame_summary(step_ms, pos_ms, stats)
                mesh = "demo" if target is None else f"{round(target / 1000)}k"
                rows.append(dict(part="frames", method=material, resolution=cells, mesh=mesh,
                                 vertices=int(len(scene.vertices)), lattice=sim.lattice_size,
                                 threads=sim.threads, warmup_frames=warmup, **s))
                log(f"frames      {material:10s} {mesh:>4s} mesh ({len(scene.vertices):6d} vertices) "
                    f"N={cells} M={sim.lattice_size} threads={sim.threads} {s['ms_per_frame']:7.2f} "
                    f"ms/frame {s['frames_per_second']:7.1f} frames/s awake={s['awake']:.0f} "
                    f"particles={s['particles']:.0f} cg={s['cg_iterations']:.0f} "
                    f"factorizations={s['factorizations']:.2f}")
    rows.append(dict(PAPER_REFERENCE))
    return rows


# ---------------------------------------------------------------- shells


def shell_scenes(target=16000):
    """Curved shells with about `target` vertices (issue #11): a lantern standing on a table
    lit on its side, a sphere pinned at its top lit on its equator, an A4 letter folded at 30
    degrees on a table lit at a corner. (name, vertices, faces, ignite at, Simulation keywords)."""
    from thinburn import _surface_shapes as shapes
    from thinburn.scenes import rect_sheet

    nz = max(4, int(round(np.sqrt(target / 3.0))))
    lantern = shapes.cylinder(0.1, 0.3, nt=3 * nz, nz=nz - 1)
    level = int(np.clip(round(np.log(target / 12.0) / np.log(4.0)), 2, 7))
    sphere = shapes.icosphere(level, 0.1)
    nx = max(4, int(round(np.sqrt(target * 0.707))))
    v, f = rect_sheet(0.21, 0.297, nx=nx, ny=int(round(nx * 1.414)))
    m = v[:, 0] > 0.105
    d = v[m, 0] - 0.105
    v[m, 0], v[m, 2] = 0.105 + d * np.cos(np.radians(150)), d * np.sin(np.radians(150))
    return [
        ("lantern", *lantern, (0.1, 0.0, 0.15), dict(floor=0.0)),
        ("sphere", *sphere, (0.1, 0.0, 0.0), dict(pinned=np.flatnonzero(sphere[0][:, 2] > 0.0995))),
        ("letter", v, f, (0.0, 0.0, 0.0), dict(floor=0.0)),
    ]


def bench_shells(cells, frames, warmup, repeat, threads, log, target=16000):
    """Frames per second of the curved shells (geometry "surface"), beside the flat demo."""
    rows = []
    for name, V, F, at, kw in shell_scenes(target):
        builds = []  # seconds of each Simulation's construction: the surface cells' build

        def make(V=V, F=F, at=at, kw=kw):
            t0 = time.perf_counter()
            sim = Simulation(V, F, cells=cells, threads=threads, **kw)
            builds.append(time.perf_counter() - t0)
            sim.ignite(at, time=0.0)
            return sim
        step_ms, pos_ms, stats, probe = best_frames(make, frames, warmup, repeat)
        build_s = min(builds)
        s = frame_summary(step_ms, pos_ms, stats)
        rows.append(dict(part="shells", method=name, resolution=cells, vertices=int(len(V)),
                         cells=int(probe.num_cells), couples=int(probe.lattice_couples), geometry=probe.geometry,
                         threads=probe.threads, build_seconds=build_s, warmup_frames=warmup, **s))
        log(f"shells      {name:8s} {len(V):6d} vertices {probe.num_cells:6d} cells {probe.lattice_couples:4d} "
            f"couples (build {build_s:5.2f} s) {s['ms_per_frame']:7.2f} ms/frame {s['frames_per_second']:7.1f} frames/s "
            f"awake={s['awake']:.0f}")
    return rows


# ---------------------------------------------------------------- scaling


def loglog_slope(x, y) -> float:
    """Least-squares slope of log y against log x."""
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])


def bench_scaling(cell_sizes, vertex_counts, frames, warmup, repeat, threads, log, material="paper",
                  vertex_cells=128):
    """The material's demo scene (the same physical fire at every size): per-frame cost
    against N² at its own mesh, and against the mesh's vertices at vertex_cells² cells."""
    rows = []
    for kind, values in (("cells", cell_sizes), ("vertices", vertex_counts)):
        for value in values:
            cells, target = (value, None) if kind == "cells" else (vertex_cells, value)
            scene = default_scene(material, vertices=target)
            step_ms, pos_ms, stats, sim = best_frames(
                lambda: build(scene, material, cells=cells, threads=threads), frames, warmup, repeat)
            s = frame_summary(step_ms, pos_ms, stats)
            rows.append(dict(part="scaling", method=kind, resolution=int(value), cells=cells * cells,
                             vertices=int(len(scene.vertices)), lattice=sim.lattice_size,
                             scene=material, threads=sim.threads, **s))
            log(f"scaling     {kind:10s} N={cells:5d} vertices={len(scene.vertices):8d} "
                f"M={sim.lattice_size:3d} {s['ms_per_frame']:8.2f} ms/frame (positions "
                f"{s['positions_ms']:.2f}) front={s['front_active']:.0f} burning={s['burning']:.0f} "
                f"awake={s['awake']:.0f} particles={s['particles']:.0f}")
        sub = [r for r in rows if r["method"] == kind]
        if len(sub) >= 2:
            x = [r["cells"] if kind == "cells" else r["vertices"] for r in sub]
            fit = dict(part="fit", method=f"scaling_{kind}", x=kind,
                       slope=loglog_slope(x, [r["ms_per_frame"] for r in sub]),
                       positions_slope=loglog_slope(x, [r["positions_ms"] for r in sub]))
            rows.append(fit)
            log(f"scaling     fit ms/frame ~ {kind}^{fit['slope']:.2f} "
                f"(vertex_positions ~ {kind}^{fit['positions_slope']:.2f})")
    return rows


# ---------------------------------------------------------------- active work

ACTIVE_MODES = {
    # mode: (Simulation keywords, what counts as the active work of a frame)
    "fire": (dict(shell=False), "front_active"),
    "shell_lattice17": (dict(lattice=17), "awake*cg_iterations"),
    "shell_auto_lattice": (dict(), "awake*cg_iterations"),
}


def active_work(stats, mode) -> np.ndarray:
    """Per frame: the fire's narrow band (fire only), or awake vertices times CG iterations
    (the lattice solve, which dominates a frame with the shell)."""
    if ACTIVE_MODES[mode][1] == "front_active":
        return stats["front_active"]
    return stats["awake"] * stats["cg_iterations"]


def active_scene():
    """A 1 m square of paper on a table, 41 x 41 vertices, lit at its centre (radius 1 cm)."""
    v, f = rect_sheet(1.0, 1.0, nx=41, ny=41)
    return v, f, (0.5, 0.5, 0.0), 0.01


def bench_active(sizes, modes, frames, warmup, repeat, threads, log):
    """Per mode and N: the per-frame series and cost per unit of active work; per mode a fit
    row comparing that cost at the largest N with the smallest, against the N² ratio."""
    v, f, at, radius = active_scene()
    rows = []
    for mode in modes:
        kw = ACTIVE_MODES[mode][0]
        for N in sizes:
            def make_sim():
                sim = Simulation(v, f, material="paper", cells=N, threads=threads, floor=0.0, **kw)
                sim.ignite(at, time=0.0, radius=radius)
                return sim

            step_ms, pos_ms, stats, sim = best_frames(make_sim, frames, warmup, repeat)
            s = frame_summary(step_ms, pos_ms, stats)
            work = active_work(stats, mode)
            ms = step_ms + pos_ms
            rows.append(dict(part="active", method=mode, resolution=N, cells=N * N,
                             lattice=sim.lattice_size, work=ACTIVE_MODES[mode][1],
                             mean_work=float(work.mean()),
                             ms_per_unit_work=float(ms.sum() / max(work.sum(), 1.0)),
                             series_ms=ms.tolist(),
                             series_work=work.tolist(),
                             series={k: stats[k].tolist() for k in STAT_KEYS},
                             threads=sim.threads, warmup_frames=warmup, **s))
            log(f"active      {mode:18s} N={N:5d} M={sim.lattice_size:3d} {s['ms_per_frame']:9.3f} "
                f"ms/frame work={work.mean():10.0f} ({ACTIVE_MODES[mode][1]}) "
                f"ms/unit={rows[-1]['ms_per_unit_work']:.3e}")
        sub = [r for r in rows if r["method"] == mode]
        if len(sub) >= 2:
            a, b = sub[0], sub[-1]
            rows.append(dict(part="fit", method=f"active_{mode}", n_small=a["resolution"],
                             n_large=b["resolution"], cells_ratio=b["cells"] / a["cells"],
                             ms_ratio=b["ms_per_frame"] / a["ms_per_frame"],
                             work_ratio=b["mean_work"] / max(a["mean_work"], 1e-300),
                             cost_per_work_ratio=b["ms_per_unit_work"] / a["ms_per_unit_work"]))
            r = rows[-1]
            log(f"active      fit {mode}: N² x{r['cells_ratio']:.0f}, ms/frame x{r['ms_ratio']:.2f}, "
                f"active work x{r['work_ratio']:.2f}, cost per unit work x{r['cost_per_work_ratio']:.2f}")
    return rows


IGNITES_PER_FRAME = 64  # the add-on's moving igniter: one ignite per sub-frame sample


def bench_ignite(sizes, repeat, log):
    """Seconds per ignite (a moving igniter's IGNITES_PER_FRAME points along a line) on the A4
    demo sheet after 2 s of burning and curling, against N; a fit row holds the ratio of the
    largest N's cost to the smallest's beside the N² ratio (a scan of every cell: equal)."""
    scene = default_scene("paper")
    rows = []
    for N in sizes:
        sim = build(scene, "paper", cells=N, threads=1)
        for _ in range(48):
            sim.step(FRAME_DT)
        points = [(0.05 + 0.1 * k / IGNITES_PER_FRAME, 0.1, 0.0) for k in range(IGNITES_PER_FRAME)]

        def frame():
            for p in points:
                sim.ignite(p)
        secs = best_seconds(frame, repeat, budget=0.1) / IGNITES_PER_FRAME
        rows.append(dict(part="ignite", method="ignite", resolution=N, cells=N * N,
                         lattice=sim.lattice_size, seconds=secs, per_frame_ms=1e3 * secs * IGNITES_PER_FRAME))
        log(f"ignite      N={N:5d} M={sim.lattice_size:3d} {1e6 * secs:8.1f} µs per ignite "
            f"({IGNITES_PER_FRAME} a frame: {rows[-1]['per_frame_ms']:.2f} ms)")
    if len(rows) >= 2:
        a, b = rows[0], rows[-1]
        rows.append(dict(part="fit", method="ignite", cells_ratio=b["cells"] / a["cells"],
                         seconds_ratio=b["seconds"] / a["seconds"]))
        log(f"ignite      fit: N² x{rows[-1]['cells_ratio']:.0f}, seconds per ignite x{rows[-1]['seconds_ratio']:.2f}")
    return rows


# ---------------------------------------------------------------- figures


def _count(n) -> str:
    """1026 -> '1.03k', 1e6 -> '1M'."""
    return f"{n / 1e6:.3g}M" if n >= 1e6 else f"{n / 1e3:.3g}k"


def _log_ticks(ax, values, labels):
    """Log x axis with a labelled tick at each measured value and no minor labels."""
    import matplotlib.ticker
    ax.set_xscale("log")
    ax.set_xticks(values)
    ax.set_xticklabels(labels)
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


BAR_COLOURS = ("C0", "C1", "C2", "C4", "C5", "C6")  # no red: the paper's line is red


def plot_performance(rows, path):
    """FFD throughput against the bound, and frames per second per preset."""
    plt = _pyplot()
    ffd = [r for r in rows if r["part"] == "ffd" and r["method"] != "bandwidth"]
    frames = [r for r in rows if r["part"] == "frames" and not r.get("reference")]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    ax = axes[0]
    bw = [r for r in rows if r["part"] == "ffd" and r["method"] == "bandwidth"]
    for j, m in enumerate(("trilinear", "bspline")):
        mr = sorted((r for r in ffd if r["method"] == m), key=lambda r: r["resolution"])
        if not mr:
            continue
        n = [r["resolution"] for r in mr]
        ax.plot(n, [r["vertices_per_second"] for r in mr], "o-", color=f"C{j}",
                label=f"{m} ({mr[0]['bytes_per_point']} B/point)")
        ax.axhline(mr[0]["bound_vertices_per_second"], color=f"C{j}", ls="--", lw=1,
                   label=f"{m} bound = bandwidth / {mr[0]['bytes_per_point']} B")
        ax.annotate(f"{100 * mr[-1]['fraction']:.0f} % of bound", (n[-1], mr[-1]["vertices_per_second"]),
                    xytext=(6, -3), textcoords="offset points", ha="left", fontsize=8, color=f"C{j}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.margins(x=0.25)
    ax.set_xlabel("embedded points n")
    ax.set_ylabel("vertices per second")
    title = "FFD deform throughput vs memory-bandwidth bound"
    if bw:
        title += f"\n(triad {bw[0]['bytes_per_second'] / 1e9:.1f} GB/s, {bw[0]['threads']} thread(s))"
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    ax = axes[1]
    mats = list(dict.fromkeys(r["method"] for r in frames))
    groups = list(dict.fromkeys((r["mesh"], r["threads"]) for r in frames))
    width = 0.8 / max(1, len(groups))
    for k, (mesh, threads) in enumerate(groups):
        sub = {r["method"]: r for r in frames if r["mesh"] == mesh and r["threads"] == threads}
        verts = sorted({r["vertices"] for r in sub.values()})
        size = f"{verts[0] / 1000:.1f}k-{verts[-1] / 1000:.1f}k" if len(verts) > 1 else f"{verts[0]}"
        ax.bar(np.arange(len(mats)) + (k - (len(groups) - 1) / 2) * width,
               [sub[m]["frames_per_second"] if m in sub else 0 for m in mats], width,
               label=f"{mesh} mesh ({size} vertices), {threads} thread(s)",
               color=BAR_COLOURS[k % len(BAR_COLOURS)])
    ax.axhline(GOAL_FPS, color="k", ls="--", lw=1, label=f"issue #6 goal: {GOAL_FPS:.0f} frames/s")
    ax.axhline(PAPER_REFERENCE["frames_per_second"], color="tab:red", ls=":", lw=1.5,
               label="paper: ~10 frames/s (Pentium IV, with rendering)")
    ax.set_xticks(np.arange(len(mats)))
    ax.set_xticklabels(mats)
    ax.set_yscale("log")
    top = max([GOAL_FPS] + [r["frames_per_second"] for r in frames])
    ax.set_ylim(5, top * 100)  # room above the bars for the legend
    ax.set_ylabel("simulated frames per second (dt = 1/24 s)")
    cells = frames[0]["resolution"] if frames else 128
    ax.set_title(f"whole frames at {cells}² cells (step 1/24 s + vertex_positions), demo scenes",
                 fontsize=9)
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    save_figure(fig, path)


def plot_scaling(rows, path):
    """Per-frame cost against cells and vertices (log-log), and against active work."""
    plt = _pyplot()
    fits = {r["method"]: r for r in rows if r["part"] == "fit"}
    fig, axes = plt.subplots(2, 2, figsize=(12, 9))
    for ax, kind, xkey, xlabel in ((axes[0, 0], "cells", "cells", "cells N² (same A4 sheet and fire)"),
                                   (axes[0, 1], "vertices", "vertices", "mesh vertices (A4 sheet, 128² cells)")):
        sub = [r for r in rows if r["part"] == "scaling" and r["method"] == kind]
        fit = fits.get(f"scaling_{kind}")
        if sub:
            x = [r[xkey] for r in sub]
            lab = f" (slope {fit['slope']:.2f})" if fit else ""
            ax.plot(x, [r["ms_per_frame"] for r in sub], "o-", label="whole frame" + lab)
            lab = f" (slope {fit['positions_slope']:.2f})" if fit else ""
            ax.plot(x, [r["positions_ms"] for r in sub], "s--", label="of which vertex_positions (FFD)" + lab)
            for r, xv in zip(sub, x):
                note = (f"M={r['lattice']}, front {r['front_active']:.0f}\nawake {r['awake']:.0f}"
                        if kind == "cells" else f"M={r['lattice']}")
                ax.annotate(note, (xv, r["ms_per_frame"]), fontsize=6, xytext=(4, 4),
                            textcoords="offset points")
            _log_ticks(ax, x, [f"{r['resolution']}²" if kind == "cells" else _count(r["vertices"])
                               for r in sub])
        ax.set_yscale("log")
        ax.margins(x=0.15, y=0.2)
        ax.set_xlabel(xlabel)
        ax.set_ylabel("ms per frame")
        ax.set_title(f"per-frame cost vs {kind}", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    act = [r for r in rows if r["part"] == "active"]
    modes = list(dict.fromkeys(r["method"] for r in act))
    ax = axes[1, 0]
    for j, mode in enumerate(modes):
        sub = [r for r in act if r["method"] == mode]
        ax.plot([r["cells"] for r in sub], [r["ms_per_frame"] for r in sub], "o-", color=f"C{j}",
                label=f"{mode} (active work: {sub[0]['work']})")
        for r in sub:  # modes alternate above and below their points so labels do not collide
            ax.annotate(f"M={r['lattice']}\nwork {r['mean_work']:.3g}", (r["cells"], r["ms_per_frame"]),
                        fontsize=6, xytext=(4, (4, -16, 14)[j % 3]), textcoords="offset points",
                        color=f"C{j}")
    for j, mode in enumerate(modes):
        sub = [r for r in act if r["method"] == mode]
        cs = np.array([r["cells"] for r in sub], dtype=float)
        ax.plot(cs, sub[0]["ms_per_frame"] * cs / cs[0], ":", color=f"C{j}", lw=1,
                label="∝ N² from the first point" if j == 0 else None)
    if act:
        sizes = sorted({r["resolution"] for r in act})
        _log_ticks(ax, [n * n for n in sizes], [f"{n}²" for n in sizes])
    ax.set_yscale("log")
    ax.margins(x=0.15, y=0.15)
    ax.set_xlabel("cells N² (1 m sheet, same 1 cm fire)")
    ax.set_ylabel("ms per frame")
    ax.set_title("small fire on a large sheet: per-frame cost", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    if act:  # room below the lowest point for the legend
        ax.set_ylim(bottom=min(r["ms_per_frame"] for r in act) / 50)
    ax.legend(fontsize=7, loc="lower right")
    ax = axes[1, 1]
    for j, mode in enumerate(modes):
        sub = [r for r in act if r["method"] == mode]
        base = sub[0]["ms_per_unit_work"]
        ax.plot([r["resolution"] for r in sub], [r["ms_per_unit_work"] / base for r in sub], "o-",
                color=f"C{j}", label=f"{mode}: ms / ({sub[0]['work']})")
    ax.set_yscale("log")
    if act:
        ns = np.array(sorted({r["resolution"] for r in act}), dtype=float)
        ax.plot(ns, (ns / ns[0]) ** 2, "k:", lw=1, label="N² / N₀² (cost that followed the cells)")
        _log_ticks(ax, ns, [f"{int(n)}" for n in ns])
    ax.margins(x=0.1)
    ax.set_xlabel("N (cells per side)")
    ax.set_ylabel(f"cost per unit of active work, relative to N = {act[0]['resolution'] if act else ''}")
    ax.set_title("flat = the cost follows the active work, not N²", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    save_figure(fig, path)


def save_figure(fig, path) -> None:
    """Lay out, write (110 dpi, every chart of the bench) and close a matplotlib figure."""
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    _pyplot().close(fig)


PERF_PARTS = ("ffd", "frames", "shells", "scaling", "active")
ALL_MATERIALS = tuple(MATERIALS)
