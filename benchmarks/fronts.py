"""The fronts' speed-accuracy parts of ``python -m benchmarks`` (see docs/bench.md).

Cases where no method is exact by construction:

  fire_front     the grid front (every FRONT_METHODS method) on the unit square with the
                 linear speed v = 1 + 2x, a point source at (x, y) = (0.25, 0.5): arrival
                 times in closed form (``linear_speed_time``), so the error is the method's.
  surface_front  the surface front (SurfaceCells + SurfaceFront) on an open cylinder, a unit
                 sphere and a truncated cone against exact geodesics (unrolled, great circle,
                 unrolled round the cut), and on the grid front's flat case (a unit square
                 with v = 1 + 2x), at several resolutions: error against seconds per cell.

``front_fits`` turns the rows of both parts into "fit" rows: the order of convergence of the
max and mean errors per method / shape, and the surface front's cost per cell over the grid
front's (fmm) at the nearest cell count, measured in the same run.
"""
from __future__ import annotations

import math
import time

import numpy as np

from .perf import _pyplot, loglog_slope, save_figure

# The flat case shared by both fronts: v = V0 (1 + A x) on the unit square.
GRADIENT_A = 2.0
GRADIENT_V0 = 1.0
GRADIENT_SOURCE = (0.25, 0.5)  # (x, y)
GRID_SCORED_BEYOND = 8  # grid cells: the grid front's errors are scored at >= 8 cells
SURFACE_SCORED_BEYOND = 3  # spacings: the surface front's at > 3 cell spacings


def linear_speed_time(x, y, x0, y0, a=GRADIENT_A, v0=GRADIENT_V0):
    """Travel time from (x0, y0) to (x, y) through the speed v(x) = v0 (1 + a x) (a != 0,
    1 + a x > 0 on both ends): T = arccosh(1 + a² |d|² / (2 (1 + a x0)(1 + a x))) / (a v0).
    The rays are circular arcs centred on the line 1 + a x = 0 and never cross, so this is the
    first arrival everywhere (tests/test_bench.py checks |grad T| v = 1 and shoots rays)."""
    d2 = (np.asarray(x, float) - x0) ** 2 + (np.asarray(y, float) - y0) ** 2
    return np.arccosh(1.0 + a * a * d2 / (2.0 * (1.0 + a * x0) * (1.0 + a * np.asarray(x, float)))) / (a * v0)


# ---------------------------------------------------------------- surface front


def surface_shapes():
    """name -> (vertices, faces, source point, exact(points), speed(positions) or None,
    distance(points)): exact arrival times at the cells' positions, and the surface distance
    from the source that decides which cells are scored (the same for unit speed).

    cylinder: r = 0.1, h = 0.3, 256 facets round and 32 rings (well-shaped quads: a cheaper
    build than the 8-ring lantern of scripts/bench_surface_front.py), lit on its side at
    mid-height. sphere: unit icosphere (level 5), lit at a vertex. cone: base radius 0.2,
    height 0.3, the apex's quarter of the slant cut away, lit at 0.6 of the slant.
    sheet_gradient: the grid front's flat case (unit square, v = 1 + 2x)."""
    from thinburn import _surface_shapes as S
    cyl_src = np.array([0.1, 0.0, 0.15])
    cone_src = np.array([0.2 * 0.6, 0.0, 0.3 * 0.6])
    sheet_src = np.array([GRADIENT_SOURCE[0], GRADIENT_SOURCE[1], 0.0])
    Vs, Fs = S.icosphere(5)
    cyl = lambda P: S.cylinder_exact(P, cyl_src)  # noqa: E731
    sph = lambda P: S.sphere_exact(P, Vs[0])  # noqa: E731
    con = lambda P: S.cone_exact(P, cone_src)  # noqa: E731
    return {
        "cylinder": (*S.cylinder(nt=256, nz=32), cyl_src, cyl, None, cyl),
        "sphere": (Vs, Fs, Vs[0], sph, None, sph),
        "cone": (*S.cone(nt=128, nr=16), cone_src, con, None, con),
        "sheet_gradient": (*S.sheet(8), sheet_src,
                           lambda P: linear_speed_time(P[:, 0], P[:, 1], *GRADIENT_SOURCE),
                           lambda P: GRADIENT_V0 * (1.0 + GRADIENT_A * P[:, 0]),
                           lambda P: S.plane_exact(P, sheet_src)),
    }


SURFACE_SHAPES = ("cylinder", "sphere", "cone", "sheet_gradient")


def surface_solve(cells, source, speed, repeat):
    """Arrival times and the best of `repeat` timings of ignite + advance to +inf (a fresh
    SurfaceFront each time, built and given its speeds outside the timer, as the grid's)."""
    from thinburn.surface_front import SurfaceFront
    best, t = math.inf, None
    for _ in range(repeat):
        front = SurfaceFront(cells, speed=speed)
        start = time.perf_counter()
        front.ignite(source)
        front.advance(math.inf)
        best = min(best, time.perf_counter() - start)
        t = front.arrival
    return t, best


def bench_surface_front(sizes, repeat, log, shapes=SURFACE_SHAPES):
    """Rows part "surface_front": method = shape, resolution N (about N² cells), cells,
    error (max relative, over cells > 3 spacings from the source), mean_error, max_abs,
    seconds (ignite + advance, best of `repeat`), us_per_cell, build_seconds, spacing; for
    sheet_gradient also error_beyond_8h (scored as the grid front is, >= 8 spacings)."""
    from thinburn.surface_front import SurfaceCells
    table = surface_shapes()
    rows = []
    for name in shapes:
        V, F, src, exact, speed_fn, distance = table[name]
        for n in sizes:
            t0 = time.perf_counter()
            sc = SurfaceCells(V, F, cells=n)
            build = time.perf_counter() - t0
            speed = 1.0 if speed_fn is None else speed_fn(sc.positions)
            t, secs = surface_solve(sc, src, speed, repeat)
            ex, dist = exact(sc.positions), distance(sc.positions)
            err = np.abs(t - ex)
            mask = dist > SURFACE_SCORED_BEYOND * sc.spacing
            rel = err[mask] / ex[mask]
            row = dict(part="surface_front", method=name, resolution=n, cells=len(sc),
                       error=float(rel.max()), mean_error=float(rel.mean()),
                       max_abs=float(err.max()), seconds=secs, us_per_cell=1e6 * secs / len(sc),
                       build_seconds=build, spacing=float(sc.spacing),
                       scored_beyond_spacings=SURFACE_SCORED_BEYOND)
            if name == "sheet_gradient":
                far = dist >= GRID_SCORED_BEYOND * sc.spacing
                row["error_beyond_8h"] = float((err[far] / ex[far]).max())
            rows.append(row)
            log(f"surface_front {name:14s} N={n:4d} cells={len(sc):6d} error={row['error']:.3e} "
                f"mean={row['mean_error']:.3e} us/cell={row['us_per_cell']:.2f} build={build:.2f}s")
    return rows


# ---------------------------------------------------------------- fits


def _order(rows, key):
    """Order of convergence: slope of log(error) against log(spacing), spacing ~ 1/sqrt(cells)."""
    h = [1.0 / math.sqrt(r["cells"]) for r in rows]
    return loglog_slope(h, [max(r[key], 1e-300) for r in rows])


def front_fits(rows):
    """Fit rows of the fronts: per grid method and per surface shape the orders of the max and
    mean errors (``max_order``, ``mean_order``: error ~ h^order); per shape the surface front's
    cost per cell over the grid fmm's at the nearest cell count, where the two counts are within
    a factor 2 (``cost_ratio``: the median over the pairs; ``pairs``: (surface cells, grid
    cells, ratio)); no ratio row without such a pair."""
    fits = []
    groups = {}
    for r in rows:
        if r["part"] in ("fire_front", "surface_front"):
            groups.setdefault((r["part"], r["method"]), []).append(r)
    for (part, method), grp in groups.items():
        if len(grp) < 2:
            continue
        grp = sorted(grp, key=lambda r: r["cells"])
        fits.append(dict(part="fit", method=f"{part}_order_{method}", max_order=_order(grp, "error"),
                         mean_order=_order(grp, "mean_error"),
                         resolutions=[r["resolution"] for r in grp]))
    grid = groups.get(("fire_front", "fmm"), [])
    for (part, method), grp in groups.items():
        if part != "surface_front" or not grid:
            continue
        pairs = []
        for r in sorted(grp, key=lambda r: r["cells"]):
            g = min(grid, key=lambda q: abs(math.log(q["cells"] / r["cells"])))
            if abs(math.log(g["cells"] / r["cells"])) <= math.log(2.0):
                pairs.append((r["cells"], g["cells"], r["us_per_cell"] / g["us_per_cell"]))
        if not pairs:
            continue
        fits.append(dict(part="fit", method=f"surface_cost_ratio_{method}",
                         cost_ratio=float(np.median([p[2] for p in pairs])), pairs=pairs))
    return fits


# ---------------------------------------------------------------- figure


def _pareto(points):
    keep = []
    for i, (e, s) in enumerate(points):
        if not any((e2 <= e and s2 <= s) and (e2 < e or s2 < s) for e2, s2 in points):
            keep.append(i)
    return sorted(keep, key=lambda i: points[i][1])


GRID_MARKERS = dict(cellular="s", cellular16="D", fmm1="v", fmm="o")
SURFACE_COLOURS = dict(cylinder="C4", sphere="C5", cone="C6", sheet_gradient="C9")


def plot_fronts(rows, path):
    """fronts.png: top, the grid front on v = 1 + 2x, max and mean relative error against
    seconds, per method over resolutions (Pareto front ringed); bottom, max and mean error
    against microseconds per cell: the surface front on its shapes beside the grid front."""
    plt = _pyplot()
    grid = [r for r in rows if r["part"] == "fire_front"]
    surf = [r for r in rows if r["part"] == "surface_front"]
    fig, axes = plt.subplots(2, 2, figsize=(11, 9))
    for col, (key, what) in enumerate((("error", "max"), ("mean_error", "mean"))):
        ax = axes[0, col]
        methods = list(dict.fromkeys(r["method"] for r in grid))
        for j, m in enumerate(methods):
            mr = sorted((r for r in grid if r["method"] == m), key=lambda r: r["resolution"])
            xs, ys = [r["seconds"] for r in mr], [r[key] for r in mr]
            ax.plot(xs, ys, GRID_MARKERS.get(m, "o") + "-", color=f"C{j}", label=m)
            for x, y, r in zip(xs, ys, mr):
                ax.annotate(f"{r['resolution']}", (x, y), fontsize=6, xytext=(3, 3),
                            textcoords="offset points")
        if grid:
            pts = [(r[key], r["seconds"]) for r in grid]
            front = _pareto(pts)
            fx, fy = [pts[i][1] for i in front], [pts[i][0] for i in front]
            ax.step(fx, fy, where="post", color="k", lw=1, label="Pareto front")
            ax.scatter(fx, fy, s=120, facecolors="none", edgecolors="k", zorder=5)
        ax.set_title(f"grid front, v = 1 + 2x, point source: {what} rel. error "
                     f"(cells >= {GRID_SCORED_BEYOND} from it)", fontsize=9)
        ax.set_xlabel("seconds (ignite + advance, n × n cells, n annotated)")

        ax = axes[1, col]
        for j, m in enumerate(dict.fromkeys(r["method"] for r in grid)):
            mr = sorted((r for r in grid if r["method"] == m), key=lambda r: r["resolution"])
            ax.plot([r["us_per_cell"] for r in mr], [r[key] for r in mr],
                    GRID_MARKERS.get(m, "o") + ":", color=f"C{j}", alpha=0.7, ms=5,
                    label=f"grid {m} (flat, v = 1 + 2x)")
        for name in dict.fromkeys(r["method"] for r in surf):
            mr = sorted((r for r in surf if r["method"] == name), key=lambda r: r["resolution"])
            xs, ys = [r["us_per_cell"] for r in mr], [r[key] for r in mr]
            label = ("surface, flat, v = 1 + 2x" if name == "sheet_gradient" else f"surface, {name}")
            ax.plot(xs, ys, "*-", color=SURFACE_COLOURS.get(name, "k"), ms=9, label=label)
            for x, y, r in zip(xs, ys, mr):
                ax.annotate(f"{r['resolution']}²", (x, y), fontsize=6, xytext=(3, 3),
                            textcoords="offset points")
        ax.set_title(f"surface front (cylinder, sphere, cone: exact geodesics; cells > "
                     f"{SURFACE_SCORED_BEYOND} spacings\nfrom the source) beside the grid front "
                     f"(flat, v = 1 + 2x): {what} rel. error", fontsize=9)
        ax.set_xlabel("microseconds per cell (ignite + advance / cells)")
    import matplotlib.ticker
    for ax in axes.ravel():
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_ylabel("relative error")
        ax.grid(True, which="both", alpha=0.3)
        if ax.lines:
            ax.legend(fontsize=7)
    xs = [r["us_per_cell"] for r in grid + surf]
    if xs:  # per-cell costs span about a decade: label the 1-2-5 ticks
        ticks = [t for t in (0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50)
                 if min(xs) / 1.3 <= t <= max(xs) * 1.3]
        for ax in axes[1]:
            ax.set_xlim(min(xs) / 1.3, max(xs) * 1.3)
            ax.set_xticks(ticks)
            ax.set_xticklabels([f"{t:g}" for t in ticks])
    save_figure(fig, path)
