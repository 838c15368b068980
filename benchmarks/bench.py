"""Speed against accuracy of every part's methods, and whole-frame performance, in one run.

    python -m benchmarks [--quick] [--repeat N] [--threads T] [--parts P ...] --out DIR

Parts (in this order; all by default):
  fire_front   every FRONT_METHODS method from a point source in the speed v = 1 + 2x on the
               unit square (closed-form times, no method exact by construction); error = max
               and mean relative error over cells >= 8 cells from the source; n = 65, 129,
               257 (--quick) and 513, 1025.
  surface_front  the surface front (SurfaceCells, SurfaceFront) on a cylinder, a sphere and a
               cone against exact geodesics, and on the grid front's flat case, at N = 16, 32,
               64 (--quick) and 128: error against seconds per cell, beside the grid front.
  integrators  one free vertex of a 2 x 2 lattice (the rest pinned) on its thickness springs,
               damped (c = 3 /s): error at T = 1 s against the closed-form damped oscillator,
               relative to the initial displacement, for several dt; plus the largest stable
               dt (bisection, undamped) at several stiffnesses against theory.
  motion       every preset's demo scene (paper and hard paper on a table, cloth and silk held
               at their corners, each with and without 3 m/s wind along +x; the curtain in its
               wind and in 3 m/s along its plane) at dt = 1/24, 1/48, 1/96 (and 1/192) s with the implicit,
               bdf2 and symplectic integrators: RMS vertex error after 20 s (--quick: 5 s, two
               scenes) against a backward-Euler run at 1/480 s (--quick: 1/240), over the
               reference's RMS motion, against seconds per run (benchmarks/motion.py).
  heat         thinburn.heat.kernel_sum direct vs fast (tolerance 0.01) on a random cloud;
               error = max relative error against the direct sum (direct: 0).
  ffd          FfdLattice.deform throughput, trilinear and B-spline, n = 1e3 .. 1e6 points
               (--quick: .. 2.5e5), against bandwidth / bytes per point, the bandwidth from a
               STREAM triad measured in the same run.
  frames       whole frames (step 1/24 s + vertex_positions) at 128² cells for every preset's
               demo scene, its own mesh and ~16k vertices; the paper's ~10 frames/s beside.
  scaling      per-frame cost against cells (64² .. 1024², --quick .. 256²) on the A4 demo
               scene, and against mesh vertices (1e3 .. 1e6, --quick .. 1e5) at 128² cells.
  active       a 1 m sheet with a 1 cm fire at N = 256, 512, 1024 (--quick: 256, 512): cost per
               unit of active work against N (fire only; shell with M = 17; shell with the
               default lattice, full runs only); and the cost of an ignite against N (a
               moving igniter lights 64 points a frame in the add-on).
  threads      every preset's demo scene (128², ~16k vertices) and two larger sheets (512² with
               ~100k vertices; 128² with ~400k) on 1 thread and on all cores, on the machine as it is and with every core
               loaded by processes the bench starts itself: the all-cores / 1-thread ratio.

Writes DIR/results.json (rows {part, method, resolution or dt, error or seconds, ...}; "fit"
rows hold slopes and ratios), DIR/meta.json, DIR/speed_accuracy.png, DIR/fronts.png, DIR/stability.png, DIR/motion.png,
DIR/performance.png, DIR/scaling.png and DIR/threads.png. One progress line per measurement on stderr.
Seconds of kernels are the best of --repeat runs (default 3; ffd at least 10). Frames: each
frame's fastest time over --repeat runs of the same deterministic simulation, the thread counts' runs
taken in turn (--quick and the
default-lattice active runs: 1 run). Everything runs on --threads threads (default: all
logical cores), set with thinburn.set_threads; meta.json keeps the load average.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time

import numpy as np

from thinburn import _core
from thinburn._threads import hardware_threads, set_threads
from thinburn.fire_front import FRONT_METHODS, method_enum

from . import fronts
from . import motion
from . import perf
from . import threads as threads_part  # "threads" names the thread count below

# ---------------------------------------------------------------- fire front


def front_case(name: str, n: int, e=(0.3, 0.4)):
    """speed (n, n), source (row, col), spacing h, drive or None, exact T, mask of scored cells.

    point: unit speed from the centre. gradient: v = 1 + 2x on the unit square. ellipse: unit
    speed with drive e (focus-at-source ellipse)."""
    if name == "point":
        src = (n // 2, n // 2)
        dr, dc = np.meshgrid(np.arange(n) - src[0], np.arange(n) - src[1], indexing="ij")
        dist = np.hypot(dr, dc).astype(float)
        return np.ones((n, n)), src, 1.0, None, dist, dist >= 8
    if name == "gradient":
        h = 1.0 / (n - 1)
        x = np.arange(n) * h
        xx, yy = np.meshgrid(x, x)
        v = fronts.GRADIENT_V0 * (1.0 + fronts.GRADIENT_A * xx)
        src = (n // 2, n // 4)  # (x, y) = (0.25, 0.5) when n - 1 is a multiple of 4
        exact = fronts.linear_speed_time(xx, yy, x[src[1]], x[src[0]])
        d2 = (xx - x[src[1]]) ** 2 + (yy - x[src[0]]) ** 2
        return v, src, h, None, exact, np.sqrt(d2) >= fronts.GRID_SCORED_BEYOND * h
    if name == "ellipse":
        src = (n // 2, n // 2)
        dr, dc = np.meshgrid(np.arange(n) - src[0], np.arange(n) - src[1], indexing="ij")
        d = np.hypot(dr, dc)
        exact = (d - (e[0] * dr + e[1] * dc)) / (1.0 - e[0] ** 2 - e[1] ** 2)
        return np.ones((n, n)), src, 1.0, e, exact, d >= 8
    raise ValueError(f"case must be point, gradient or ellipse, got {name!r}")


def front_solve(speed, src, h, drive, method, repeat, **options):
    """Arrival times and the best of `repeat` timings of ignite + advance."""
    n = speed.shape[0]
    flat = np.ascontiguousarray(speed, dtype=np.float64).ravel()
    er = ec = None
    if drive is not None:
        er, ec = np.full(n * n, float(drive[0])), np.full(n * n, float(drive[1]))
    best, t = math.inf, None
    for _ in range(repeat):
        front = _core.FireFront(n, n, h, h, method_enum(method), **options)
        front.set_speed(flat, er, ec)
        start = time.perf_counter()
        front.ignite(float(src[0]), float(src[1]), 0.0)
        front.advance(math.inf)
        best = min(best, time.perf_counter() - start)
        t = front.arrival()
    return t, best


def front_score(t, exact, mask):
    rel = np.abs(t - exact)[mask] / exact[mask]
    return dict(max_rel=float(rel.max()), mean_rel=float(rel.mean()),
                max_abs=float(np.abs(t - exact).max()))


def bench_fire_front(sizes, repeat, log, case="gradient"):
    """Rows part "fire_front": method, resolution n (n x n cells), case, error (max relative,
    cells >= 8 from the source), mean_error, max_abs, seconds (ignite + advance, best of
    `repeat`), cells, us_per_cell. The charted case is "gradient" (v = 1 + 2x): in the
    uniform "point" case fmm is exact to rounding, so it would chart nothing about accuracy."""
    rows = []
    for method in FRONT_METHODS:
        for n in sizes:
            speed, src, h, drive, exact, mask = front_case(case, n)
            t, secs = front_solve(speed, src, h, drive, method, repeat)
            s = front_score(t, exact, mask)
            rows.append(dict(part="fire_front", method=method, resolution=n, case=case,
                             error=s["max_rel"], mean_error=s["mean_rel"], max_abs=s["max_abs"],
                             seconds=secs, cells=n * n, us_per_cell=1e6 * secs / (n * n),
                             scored_beyond_cells=fronts.GRID_SCORED_BEYOND))
            log(f"fire_front {method:10s} n={n:5d} error={s['max_rel']:.3e} "
                f"mean={s['mean_rel']:.3e} seconds={secs:.4f}")
    return rows


# ---------------------------------------------------------------- integrators

INTEGRATORS = ("explicit", "symplectic", "implicit")


def oscillator(integrator, k_thickness=1.0, c_damping=3.0, mass=10.0, u0=(1e-6, 2e-6, -3e-6)):
    """A 2 x 2 lattice with every vertex pinned but vertex 1, displaced by u0 from rest, no
    gravity: a linear 3-dof oscillator u'' = -K u - c u'. Returns (lattice, dynamics, K)."""
    from thinburn.lattice import flat_rest
    lat = _core.FfdLattice(2, flat_rest(2, 1.0, 1.0, 0.3))
    dyn = _core.LatticeDynamics(lat, integrator=integrator, substeps=1, sleeping=False,
                                cg_velocity_tolerance=0.0, c_damping=c_damping,
                                gravity=[0, 0, 0], k_thickness=k_thickness)
    dyn.set_masses(np.full(8, mass))
    pinned = np.ones(8, dtype=np.uint8)
    pinned[1] = 0
    dyn.set_pinned(pinned)
    K = -dyn.stiffness_matrix()[3:6, 3:6] / mass
    x = lat.rest.copy()
    x[1] += np.asarray(u0, dtype=float)
    dyn.set_state(x, np.zeros_like(x))
    return lat, dyn, K


def oscillator_exact(K, u0, c, T):
    """Closed-form displacement at T of u'' = -K u - c u' from rest at u0 (underdamped modes)."""
    w2, V = np.linalg.eigh(K)
    q0 = V.T @ np.asarray(u0, dtype=float)
    wd = np.sqrt(w2 - c * c / 4)
    q = np.exp(-c * T / 2) * (q0 * np.cos(wd * T) + c * q0 / (2 * wd) * np.sin(wd * T))
    return V @ q


def oscillator_omega(K) -> float:
    return float(np.sqrt(np.linalg.eigvalsh(K).max()))


def oscillator_error(integrator, steps, T=1.0, c=3.0, k_thickness=1.0):
    """(relative error at T, seconds of the stepping loop) for `steps` steps of T / steps."""
    u0 = np.array([1e-6, 2e-6, -3e-6])
    lat, dyn, K = oscillator(integrator, k_thickness=k_thickness, c_damping=c, u0=u0)
    D, heat = np.zeros(4), np.zeros(8)
    dt = T / steps
    t0 = time.perf_counter()
    for _ in range(steps):
        dyn.step(dt, D, heat)
    secs = time.perf_counter() - t0
    err = np.linalg.norm(lat.positions[1] - lat.rest[1] - oscillator_exact(K, u0, c, T))
    return float(err / np.linalg.norm(u0)), secs


def oscillator_grows(integrator, dt, k_thickness, steps=200) -> bool:
    """Whether the undamped oscillator's displacement grows 1e4-fold within `steps` steps."""
    u0 = np.array([1e-8, 2e-8, -3e-8])
    lat, dyn, _ = oscillator(integrator, k_thickness=k_thickness, c_damping=0.0, u0=u0)
    D, heat = np.zeros(4), np.zeros(8)
    lim = 1e4 * np.linalg.norm(u0)
    for _ in range(steps):
        dyn.step(dt, D, heat)
        if not np.linalg.norm(lat.positions[1] - lat.rest[1]) < lim:
            return True
    return False


def largest_stable_omega_dt(integrator, k_thickness, lo=0.5, hi=3.0, iters=14):
    """Bisection of the largest stable omega * dt in [lo, hi], and omega."""
    w = oscillator_omega(oscillator(integrator, k_thickness=k_thickness)[2])
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if oscillator_grows(integrator, mid / w, k_thickness) else (mid, hi)
    return 0.5 * (lo + hi), w


def bench_integrators(steps_list, stiffnesses, repeat, log):
    rows = []
    w = oscillator_omega(oscillator("explicit")[2])
    for name in INTEGRATORS:
        for N in steps_list:
            dt = 1.0 / N
            if name != "implicit" and w * dt > 0.9 * math.sqrt(2.0):
                continue  # beyond the explicit schemes' stability limit
            best, err = math.inf, None
            for _ in range(repeat):
                err, secs = oscillator_error(name, N)
                best = min(best, secs)
            rows.append(dict(part="integrators", method=name, dt=dt, steps=N, error=err,
                             seconds=best, omega=w, omega_dt=w * dt))
            log(f"integrators {name:10s} dt={dt:.2e} error={err:.3e} seconds={best:.4f}")
    for k in stiffnesses:
        for name in ("symplectic", "explicit"):
            s, wk = largest_stable_omega_dt(name, k)
            theory = _core.explicit_stability_limit(name, wk, 0.0) * wk
            rows.append(dict(part="stability", method=name, k_thickness=k, omega=wk,
                             dt=s / wk, omega_dt=s, theory_omega_dt=theory, stable=True))
            log(f"stability   {name:10s} k={k:g} omega={wk:.1f} omega*dt={s:.4f} (theory {theory:.4f})")
        wk = oscillator_omega(oscillator("implicit", k_thickness=k)[2])
        dt = 100.0 / wk
        ok = not oscillator_grows("implicit", dt, k)
        rows.append(dict(part="stability", method="implicit", k_thickness=k, omega=wk, dt=dt,
                         omega_dt=wk * dt, theory_omega_dt=math.inf, stable=ok))
        log(f"stability   implicit   k={k:g} omega={wk:.1f} bounded at omega*dt={wk * dt:.0f}: {ok}")
    return rows


# ---------------------------------------------------------------- heat sum


def bench_heat(counts, repeat, log, n_targets=2048, tolerance=0.01):
    from thinburn.heat import kernel_sum
    rng = np.random.default_rng(0)
    tgt = rng.uniform(-0.5, 0.5, size=(n_targets, 3))
    rows = []
    for n in counts:
        src = rng.uniform(-0.5, 0.5, size=(n, 3))
        w = rng.uniform(0.5, 1.5, size=n)
        ref = None
        for method in ("direct", "fast"):
            best, out = math.inf, None
            for _ in range(repeat if n * n_targets < 1e8 else 1):
                t0 = time.perf_counter()
                out = kernel_sum(src, w, tgt, power=2, method=method, tolerance=tolerance)
                best = min(best, time.perf_counter() - t0)
            if ref is None:
                ref = out
            err = float(np.max(np.abs(out - ref) / ref))
            rows.append(dict(part="heat", method=method, resolution=n, targets=n_targets,
                             error=err, seconds=best, tolerance=tolerance))
            log(f"heat        {method:10s} n={n:6d} error={err:.3e} seconds={best:.4f}")
    return rows


# ---------------------------------------------------------------- figures


def pareto(points):
    """Indices of the points not dominated in both error and seconds (lower is better)."""
    keep = []
    for i, (e, s) in enumerate(points):
        if not any((e2 <= e and s2 <= s) and (e2 < e or s2 < s) for e2, s2 in points):
            keep.append(i)
    return sorted(keep, key=lambda i: points[i][1])


ERROR_FLOOR = 1e-16  # where exact (zero-error) points are drawn on the log axis


def plot_speed_accuracy(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    parts = [p for p in ("fire_front", "integrators", "heat") if any(r["part"] == p for r in rows)]
    fig, axes = plt.subplots(1, len(parts), figsize=(5.5 * len(parts), 4.5), squeeze=False)
    titles = dict(fire_front="fire front (v = 1 + 2x, point source, max rel. error)",
                  integrators="integrators (damped oscillator, T = 1 s)",
                  heat="heat sum (random cloud, vs direct)")
    for ax, part in zip(axes[0], parts):
        prow = [r for r in rows if r["part"] == part]
        methods = list(dict.fromkeys(r["method"] for r in prow))
        for j, m in enumerate(methods):
            mr = [r for r in prow if r["method"] == m]
            xs = [r["seconds"] for r in mr]
            ys = [max(r["error"], ERROR_FLOOR) for r in mr]
            ax.plot(xs, ys, "o-", color=f"C{j}", label=m)
            key = "resolution" if "resolution" in mr[0] else "dt"
            for x, y, r in zip(xs, ys, mr):
                lab = f"{r[key]}" if key == "resolution" else f"{r[key]:.2g}"
                ax.annotate(lab, (x, y), fontsize=6, xytext=(3, 3), textcoords="offset points")
        # Heat: each particle count is its own problem, so the front is taken per count
        # (ringed points only); elsewhere resolution / dt is the accuracy knob of one problem.
        groups = ([[r for r in prow if r["resolution"] == n]
                   for n in dict.fromkeys(r["resolution"] for r in prow)]
                  if part == "heat" else [prow])
        for g, grp in enumerate(groups):
            pts = [(max(r["error"], ERROR_FLOOR), r["seconds"]) for r in grp]
            front = pareto(pts)
            fx = [pts[i][1] for i in front]
            fy = [pts[i][0] for i in front]
            if part != "heat":
                ax.step(fx, fy, where="post", color="k", lw=1, label="Pareto front")
            ax.scatter(fx, fy, s=120, facecolors="none", edgecolors="k", zorder=5,
                       label=("Pareto front (per particle count)" if part == "heat" and g == 0
                              else None))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("seconds")
        ax.set_ylabel("error" + (" (exact drawn at 1e-16)" if part == "heat" else ""))
        ax.set_title(titles[part], fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    perf.save_figure(fig, path)


def plot_stability(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    st = [r for r in rows if r["part"] == "stability"]
    fig, ax = plt.subplots(figsize=(6, 4.5))
    if st:
        ws = np.array(sorted({r["omega"] for r in st}))
        wl = np.geomspace(ws.min() / 1.5, ws.max() * 1.5, 50)
        for j, (name, theory) in enumerate((("symplectic", 2.0), ("explicit", math.sqrt(2.0)))):
            ax.plot(wl, theory / wl, "-", color=f"C{j}", alpha=0.6,
                    label=f"{name} theory: ω dt = {theory:.3g}")
            mr = [r for r in st if r["method"] == name]
            ax.plot([r["omega"] for r in mr], [r["dt"] for r in mr], "o", color=f"C{j}",
                    label=f"{name} measured")
        mr = [r for r in st if r["method"] == "implicit"]
        ax.plot([r["omega"] for r in mr], [r["dt"] for r in mr], "^", color="C2", ms=9,
                label="implicit: bounded at largest dt tried (ω dt = 100)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    if st:
        ax.set_xticks(ws)
        ax.set_xticklabels([f"{w:.3g}" for w in ws])
    ax.set_xlabel("ω (rad/s), largest frequency of the oscillator")
    ax.set_ylabel("largest stable dt (s)")
    ax.set_title("integrator stability (undamped, bisection over 200 steps)", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    perf.save_figure(fig, path)


# ---------------------------------------------------------------- driver


def _load_average():
    """The 1, 5 and 15 minute load averages (None where the platform has none): other work on
    the machine shows in the timings, most of all with several threads."""
    try:
        return list(os.getloadavg())
    except (AttributeError, OSError):
        return None


def _writable_dir(ap, out):
    try:
        os.makedirs(out, exist_ok=True)
        probe = os.path.join(out, ".thinburn_bench_probe")
        with open(probe, "w"):
            pass
        os.remove(probe)
    except OSError as exc:
        ap.error(f"--out {out!r} is not a writable directory: {exc}")


PARTS = ("fire_front", "surface_front", "integrators", "motion", "heat") + perf.PERF_PARTS + ("threads",)
FIGURES = (  # file, plotting function, the row parts it draws
    ("speed_accuracy.png", plot_speed_accuracy, ("fire_front", "integrators", "heat")),
    ("fronts.png", fronts.plot_fronts, ("fire_front", "surface_front")),
    ("stability.png", plot_stability, ("stability",)),
    ("motion.png", motion.plot_motion, ("motion",)),
    ("performance.png", perf.plot_performance, ("ffd", "frames")),
    ("scaling.png", perf.plot_scaling, ("scaling", "active")),
    ("threads.png", threads_part.plot_threads, ("threads",)),
)


def run_perf_parts(parts, quick, repeat, threads, log):
    """Rows of the performance parts (ffd, frames, scaling, active) at the --quick or full sizes.
    Full runs also time the frames on 1 thread when `threads` > 1."""
    rows = []
    frame_repeat = 1 if quick else repeat
    if "ffd" in parts:
        set_threads(threads)
        sizes = [1000, 10000, 100000, 250000] if quick else [1000, 10000, 100000, 300000, 1000000]
        rows += perf.bench_ffd(sizes, repeat, log)
    if "frames" in parts:
        counts = [threads] if quick else sorted({1, threads}, reverse=True)
        rows += perf.bench_frames(perf.ALL_MATERIALS, 128, 24 if quick else 120, 48, [None, 16000],
                                  frame_repeat, counts, log)
    if "shells" in parts:
        rows += perf.bench_shells(128, 24 if quick else 96, 48, frame_repeat, threads, log)
    if "scaling" in parts:
        cells = [64, 128, 256] + ([] if quick else [512, 1024])
        verts = [1000, 10000, 100000] + ([] if quick else [1000000])
        rows += perf.bench_scaling(cells, verts, 24 if quick else 48, 48, frame_repeat, threads, log)
    if "active" in parts:
        sizes = [256, 512] + ([] if quick else [1024])
        rows += perf.bench_active(sizes, ["fire", "shell_lattice17"], 24, 24, frame_repeat, threads, log)
        if not quick:  # the default lattice grows with N: seconds per frame at 1024
            rows += perf.bench_active(sizes, ["shell_auto_lattice"], 6, 24, 1, threads, log)
        rows += perf.bench_ignite([128] + sizes, repeat, log)
    if "threads" in parts:
        rows += threads_part.bench_threads(24 if quick else 48, 48, frame_repeat, log,
                                             threads_part.SCENES[:1] if quick else threads_part.SCENES)
    set_threads(threads)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="directory for results.json and the figures")
    ap.add_argument("--quick", action="store_true", help="small sizes only (about a minute)")
    ap.add_argument("--repeat", type=int, default=None, help="runs per timing, best kept")
    ap.add_argument("--threads", type=int, default=None,
                    help="threads of the core (default: all logical cores)")
    ap.add_argument("--parts", nargs="+", default=list(PARTS), choices=list(PARTS),
                    help="parts to measure")
    args = ap.parse_args(None if argv is None else [str(a) for a in argv])
    if args.repeat is not None and args.repeat < 1:
        ap.error(f"--repeat must be >= 1, got {args.repeat}")
    if args.threads is not None and args.threads < 1:
        ap.error(f"--threads must be >= 1, got {args.threads}")
    out = os.fspath(args.out)
    _writable_dir(ap, out)
    repeat = args.repeat or 3
    threads = set_threads(args.threads)

    def log(msg):
        print(msg, file=sys.stderr, flush=True)

    t_start = time.perf_counter()
    load_start = _load_average()
    rows = []
    if "fire_front" in args.parts:
        sizes = [65, 129, 257] + ([] if args.quick else [513, 1025])
        rows += bench_fire_front(sizes, repeat, log)
    if "surface_front" in args.parts:
        rows += fronts.bench_surface_front([16, 32, 64] + ([] if args.quick else [128]), repeat, log)
    rows += fronts.front_fits(rows)
    if "integrators" in args.parts:
        steps = [50, 100, 200, 400, 800] + ([] if args.quick else [1600, 3200, 6400])
        stiff = [0.25, 1.0, 4.0, 16.0]
        rows += bench_integrators(steps, stiff, repeat, log)
    if "motion" in args.parts:
        rows += motion.bench_motion([1 / 24, 1 / 48, 1 / 96] + ([] if args.quick else [1 / 192]),
                                    1 / 240 if args.quick else 1 / 480, 5.0 if args.quick else 20.0, log,
                                    motion.MOTION_SCENES[:2] if args.quick else motion.MOTION_SCENES)
    if "heat" in args.parts:
        counts = [100, 1000, 10000] + ([] if args.quick else [100000])
        rows += bench_heat(counts, repeat, log)
    rows += run_perf_parts(args.parts, args.quick, repeat, threads, log)
    meta = dict(quick=args.quick, repeat=repeat, threads=threads, parts=args.parts,
                machine=platform.machine(), processor=platform.processor(),
                python=platform.python_version(), cpu_count=os.cpu_count(),
                hardware_threads=hardware_threads(), load_average_start=load_start,
                load_average_end=_load_average(), wall_seconds=time.perf_counter() - t_start)
    with open(os.path.join(out, "results.json"), "w") as f:
        json.dump(rows, f, indent=1)
    with open(os.path.join(out, "meta.json"), "w") as f:
        json.dump(meta, f, indent=1)
    figures = []
    for name, plot, needs in FIGURES:
        if any(r["part"] in needs for r in rows):  # a figure only when one of its parts ran
            plot(rows, os.path.join(out, name))
            figures.append(name)
    log(f"wrote {out}/results.json, {', '.join(figures)} in {meta['wall_seconds']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
