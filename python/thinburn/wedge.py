"""Wedges: one scene baked once per combination of parameter values, as Dask tasks.

``python -m thinburn wedge --scene paper --param crumple_gain=0.1,0.3,1 --param v0=0.0035,0.01``

Every combination is one task (``bake_wedge``) on a Dask cluster: a ``LocalCluster`` of
``--workers`` processes by default, or the scheduler at ``--scheduler ADDRESS`` (the same
code; the workers must have thinburn installed and see the output folder). Each task runs
its Simulation with threads=1: Dask parallelises across tasks. ``--workers 0`` runs the
same tasks in one plain loop in this process (no Dask).

Each wedge writes its own folder under ``--out``: ``frames.npz`` (every frame: time, vertex
positions and char, particles; per vertex ignition and burnout times), ``summary.json``,
``frames.png`` (the chosen frames side by side) and, last, ``DONE`` (the wedge's settings);
a re-run skips a wedge whose ``DONE`` matches its settings. A wedge that raises writes
``error.txt`` and is reported; the others finish. ``contact_sheet.png`` lays the wedges'
strips one above the other, labelled; ``wedges.json`` lists every wedge and its status.

Parameters (``--param NAME=v1,v2,...``): any model scalar of ``Simulation(**params)``
(``crumple_gain``, ``buoyancy``, ``climb``, ``v_floor``, ...), any field of the material
(``V0`` in mm/s, ``mass``, ``Cp``, ``burn_duration``, ...), ``v0`` (the spread speed in m/s, that
is V0 / 1000), and ``cells``, ``seed``, ``fps``, ``frames``.
"""
from __future__ import annotations

import hashlib
import itertools
import json
import os
import time
import traceback

import numpy as np

from .materials import MATERIAL_FIELDS
from .scenefile import SceneSpec, from_dict

DONE = "DONE"
BAKE_SETTINGS = ("cells", "seed", "fps", "frames")


def known_params() -> list:
    from .simulation import _PARAM_BOUNDS, BENDING_KEYS, DYNAMICS_KEYS, PARTICLE_KEYS, PARTICLE_PREFIX

    return sorted(set(_PARAM_BOUNDS) | set(DYNAMICS_KEYS) | set(BENDING_KEYS)
                  | {PARTICLE_PREFIX + k for k in PARTICLE_KEYS} | set(MATERIAL_FIELDS)
                  | {"v0"} | set(BAKE_SETTINGS))


def parse_param(text: str) -> tuple:
    """'name=v1,v2' -> (name, [v1, v2]); errors name the parameter."""
    if "=" not in text:
        raise ValueError(f"--param {text!r}: write NAME=VALUE[,VALUE...]")
    name, _, raw = text.partition("=")
    name = name.strip()
    known = known_params()
    if name not in known:
        raise ValueError(f"--param {name!r}: unknown parameter; parameters are {known}")
    values = []
    for item in raw.split(","):
        item = item.strip()
        try:
            v = float(item)
        except ValueError:
            raise ValueError(f"--param {name}: {item!r} is not a number") from None
        if name in ("cells", "seed", "frames"):
            if v != int(v):
                raise ValueError(f"--param {name}: {item!r} is not an integer")
            v = int(v)
        values.append(v)
    if not values:
        raise ValueError(f"--param {name}: no values")
    return name, values


def combinations(params: list) -> list:
    """Every combination of [(name, values), ...] as a list of {name: value} dicts."""
    names = [n for n, _ in params]
    if len(set(names)) != len(names):
        raise ValueError(f"--param: a parameter is given twice ({names})")
    return [dict(zip(names, combo)) for combo in itertools.product(*[v for _, v in params])]


def wedge_name(values: dict) -> str:
    """A folder name from the values: the same for the same values in any order."""
    if not values:
        return "base"
    parts = [f"{k}-{_fmt(v)}" for k, v in sorted(values.items())]
    return "__".join(p.replace("/", "_") for p in parts)


def wedge_label(values: dict) -> str:
    return "  ".join(f"{k}={_fmt(v)}" for k, v in values.items()) or "base"


def _fmt(v) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def task_key(scene: dict, values: dict, render_frames) -> str:
    """A hash of everything that decides a wedge's result: a DONE marker with another key is stale."""
    blob = json.dumps({"scene": scene, "values": values, "render": list(render_frames)}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def is_done(folder: str, key: str) -> bool:
    try:
        with open(os.path.join(folder, DONE)) as f:
            return json.load(f).get("key") == key
    except (OSError, ValueError):
        return False


def default_render_frames(frames: int, count: int = 4) -> list:
    return sorted({int(round(x)) for x in np.linspace(0, frames - 1, min(count, frames))})


# --- one wedge (runs on a Dask worker, or in the plain loop) ---------------------------------
def bake_wedge(scene: dict, values: dict, folder: str, render_frames, key: str,
               label: str = "", usd: bool = False) -> dict:
    """Bake one wedge into ``folder``; returns its summary. Raises on failure (after writing
    ``error.txt``). Writes ``DONE`` last."""
    os.makedirs(folder, exist_ok=True)
    for stale in (DONE, "error.txt"):
        if os.path.exists(os.path.join(folder, stale)):
            os.remove(os.path.join(folder, stale))
    try:
        return _bake(scene, values, folder, list(render_frames), key, label, usd)
    except BaseException as exc:
        with open(os.path.join(folder, "error.txt"), "w") as f:
            f.write(f"{type(exc).__name__}: {exc}\n\n{traceback.format_exc()}")
        raise


def simulation_for(spec: SceneSpec, values: dict, threads: int = 1):
    """The Simulation of a scene with a wedge's values applied; also returns (fps, frames)."""
    from .simulation import Simulation

    values = dict(values)
    bake = {k: values.pop(k) for k in BAKE_SETTINGS if k in values}
    mat_changes = {k: values.pop(k) for k in list(values) if k in MATERIAL_FIELDS}
    if "v0" in values:
        mat_changes["V0"] = 1000.0 * values.pop("v0")
    material = spec.resolved_material(mat_changes)
    params = {**spec.params, **values}
    pinned = None if spec.pinned is None else np.asarray(spec.pinned)
    maps = {k: np.asarray(spec.maps[k]) for k in ("speed_map", "fuel_map") if k in spec.maps}
    sim = Simulation(spec.vertices, spec.faces, material=material,
                     cells=int(bake.get("cells", spec.cells)), seed=int(bake.get("seed", spec.seed)),
                     threads=threads, front=spec.front, lattice=spec.lattice, pinned=pinned,
                     floor=spec.floor, integrator=spec.integrator, shell=bool(spec.shell),
                     heat_ignites=spec.heat_ignites, finish_within=spec.finish_within,
                     **maps, **params)
    fps = float(bake.get("fps", spec.fps))
    frames = int(bake.get("frames", spec.frames))
    if fps <= 0 or frames < 1:
        raise ValueError(f"fps and frames must be positive, got fps={fps}, frames={frames}")
    return sim, material, fps, frames


def run_frames(sim, spec: SceneSpec, fps: float, frames: int, on_frame=None) -> None:
    """Drive a Simulation through the scene's frames as the add-on's bake does: at frame k
    light what is due in [k dt, (k+1) dt) (``scene_run.SceneRun``), record (``on_frame(k,
    sim)``), set the frame's flames, colliders, wind and motion, step (not after the last
    frame)."""
    from .scene_run import SceneRun

    run = SceneRun(spec, fps, frames)
    dt = 1.0 / fps
    for k in range(frames):
        run.before_record(sim, k)
        if on_frame is not None:
            on_frame(k, sim)
        if k < frames - 1:
            run.before_step(sim, k)
            sim.step(dt)


def _bake(scene, values, folder, render_frames, key, label, usd) -> dict:
    from . import render

    spec = from_dict(scene, "scene")
    t0 = time.perf_counter()
    sim, material, fps, frames = simulation_for(spec, values, threads=1)
    render_frames = [f for f in render_frames if 0 <= f < frames] or [frames - 1]
    store = {k: [] for k in ("time", "vertex_positions", "vertex_char")}
    particles, pictures = [], []
    renderer = render.SceneRenderer(spec.faces, sim.vertex_positions(), spec.material_name(),
                                    spec.floor, width_px=480, height_px=240, pad=spec.view_pad)
    dv, du = sim.cell_size
    aspect = dv / du

    def record(k, s):
        # In the world: a moving sheet's scene is simulated in its bake frame (to_world).
        positions = spec.in_world(k, s.vertex_positions())
        store["time"].append(s.time)
        store["vertex_positions"].append(positions.astype(np.float32))
        store["vertex_char"].append(s.vertex_char().astype(np.float32))
        p, t = s.particles() if spec.shell else (np.zeros((0, 3)), np.zeros(0))
        p = spec.in_world(k, np.asarray(p).reshape(-1, 3))
        particles.append(np.column_stack([p, t]).astype(np.float32))
        if k in render_frames:
            states = s.cell_states()
            ign, out = s.vertex_ignition_times(), s.vertex_burnout_times()
            vstate = np.where(s.time < ign, 0, np.where(s.time < out, 1, 2)).astype(np.uint8)
            cells = render.cell_image(states, s.cell_char(), s.inside(), spec.material_name(),
                                      aspect, width=120)
            pictures.append(renderer.frame(positions, s.vertex_char(), vstate, cells,
                                           (p, t), title=f"t = {s.time:5.2f} s"))

    try:
        run_frames(sim, spec, fps, frames, record)
    finally:
        renderer.close()
    wall = time.perf_counter() - t0
    t_write = time.perf_counter()
    arrays = {k: np.asarray(v) for k, v in store.items()}
    arrays.update({f"particles_{k:04d}": p for k, p in enumerate(particles)})
    arrays["faces"] = np.asarray(spec.faces, np.int32)
    arrays["vertex_ignition_times"] = sim.vertex_ignition_times()
    arrays["vertex_burnout_times"] = sim.vertex_burnout_times()
    np.savez_compressed(os.path.join(folder, "frames.npz"), **arrays)
    render.save_png(np.concatenate(pictures, axis=1), os.path.join(folder, "frames.png"))
    write = time.perf_counter() - t_write
    inside = sim.inside() == 1
    summary = {
        "wedge": os.path.basename(folder), "label": label, "values": values,
        "scene": spec.name, "material": material.name, "fps": fps, "frames": frames,
        "cells": sim.cells, "simulated_seconds": round(sim.time, 6),
        "render_frames": render_frames,
        "wall_seconds": round(wall, 3),    # the bake and its pictures
        "write_seconds": round(write, 3),  # frames.npz and frames.png
        "burnt_fraction": round(float(np.mean(sim.cell_states()[inside] == 2)), 6),
        "burning_fraction": round(float(np.mean(sim.cell_states()[inside] == 1)), 6),
        "outputs": ["frames.npz", "frames.png", "summary.json"] + (["bake.usda"] if usd else []),
    }
    with open(os.path.join(folder, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    if usd:
        from .usd import export_frames
        export_frames(os.path.join(folder, "frames.npz"), os.path.join(folder, "bake.usda"), fps=fps)
    with open(os.path.join(folder, DONE), "w") as f:  # last: the wedge is complete
        json.dump({"key": key, "values": values}, f)
    return summary


# --- many wedges ------------------------------------------------------------------------------
def plan(scene: SceneSpec, params: list, out: str, render_frames=None) -> list:
    """The wedges: dicts of name, label, values, folder, key."""
    scene_dict = scene.to_dict()
    frames = scene.frames
    wedges = []
    for values in combinations(params):
        f = int(values.get("frames", frames))
        rf = list(render_frames) if render_frames is not None else default_render_frames(f)
        name = wedge_name(values)
        wedges.append(dict(name=name, label=wedge_label(values), values=values,
                           folder=os.path.join(out, name), render_frames=rf,
                           key=task_key(scene_dict, values, rf)))
    return wedges


def run_wedges(scene: SceneSpec, params: list, out: str, *, render_frames=None, workers: int = 2,
               scheduler: str | None = None, usd: bool = False, log=None) -> dict:
    """Run every wedge (skipping those done); write wedges.json and contact_sheet.png.

    workers: LocalCluster processes (0: a plain loop here, no Dask); scheduler: an address
    instead. Returns {"done": [...], "skipped": [...], "failed": {name: text}, ...}.
    """
    log = log or (lambda text: None)
    os.makedirs(out, exist_ok=True)
    wedges = plan(scene, params, out, render_frames)
    scene_dict = scene.to_dict()
    todo = [w for w in wedges if not is_done(w["folder"], w["key"])]
    skipped = [w["name"] for w in wedges if w not in todo]
    for name in skipped:
        log(f"skip {name}: done before")
    results = {"done": [], "skipped": skipped, "failed": {}}
    t0 = time.perf_counter()

    def finished(w, summary=None, error=None):
        n = len(results["done"]) + len(results["failed"]) + 1
        elapsed = time.perf_counter() - t0
        eta = elapsed / n * (len(todo) - n)
        if error is None:
            results["done"].append(w["name"])
            log(f"[{n}/{len(todo)}] done   {w['label']}  ({summary['wall_seconds']:.1f} s; "
                f"{100 * summary['burnt_fraction']:.0f} % burnt)  elapsed {elapsed:.1f} s, ~{eta:.0f} s left")
        else:
            results["failed"][w["name"]] = error
            log(f"[{n}/{len(todo)}] FAILED {w['label']}: {error}  elapsed {elapsed:.1f} s, ~{eta:.0f} s left")

    args = lambda w: (scene_dict, w["values"], w["folder"], w["render_frames"], w["key"], w["label"], usd)  # noqa: E731
    if todo and workers == 0 and scheduler is None:
        for w in todo:
            try:
                finished(w, bake_wedge(*args(w)))
            except Exception as exc:
                finished(w, error=f"{type(exc).__name__}: {exc}")
    elif todo:
        _run_dask(todo, args, finished, workers, scheduler, log)
    results["wall_seconds"] = round(time.perf_counter() - t0, 3)
    index = []
    for w in wedges:
        status = ("failed" if w["name"] in results["failed"] else
                  "skipped" if w["name"] in skipped else "done")
        index.append({"name": w["name"], "label": w["label"], "values": w["values"], "status": status,
                      "error": results["failed"].get(w["name"])})
    with open(os.path.join(out, "wedges.json"), "w") as f:
        json.dump({"scene": scene.name, "wedges": index}, f, indent=2)
    results["contact_sheet"] = contact_sheet(wedges, os.path.join(out, "contact_sheet.png"), results["failed"])
    return results


def _run_dask(todo, args, finished, workers, scheduler, log):
    from dask.distributed import Client, LocalCluster, as_completed

    cluster = None
    if scheduler is None:
        if workers < 1:
            raise ValueError(f"workers must be >= 0, got {workers}")
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        log(f"dask: a LocalCluster of {workers} worker processes, 1 thread each")
    client = Client(scheduler if scheduler is not None else cluster)
    try:
        if scheduler is not None:
            log(f"dask: scheduler {scheduler}, {len(client.scheduler_info()['workers'])} workers")
        # The scene (the mesh) goes to every worker once, not with every task.
        scene = client.scatter(args(todo[0])[0], broadcast=True, hash=False)
        futures = {}
        for w in todo:
            fut = client.submit(bake_wedge, scene, *args(w)[1:],
                                key=f"thinburn-wedge-{w['key']}-{w['name']}", pure=False, retries=0)
            futures[fut] = w
        for fut in as_completed(futures):
            w = futures[fut]
            try:
                finished(w, fut.result())
            except Exception as exc:
                finished(w, error=f"{type(exc).__name__}: {exc}")
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def contact_sheet(wedges, path, failed=None) -> str | None:
    """Stack the wedges' frames.png strips, each labelled on its left; None if none exist."""
    from PIL import Image, ImageDraw

    failed = failed or {}
    rows = []
    for w in wedges:
        png = os.path.join(w["folder"], "frames.png")
        if os.path.exists(png) and is_done(w["folder"], w["key"]):
            with Image.open(png) as im:
                rows.append((w["label"], np.asarray(im.convert("RGB"))))
        else:
            rows.append((w["label"] + ("  (failed)" if w["name"] in failed else "  (missing)"), None))
    strips = [img for _, img in rows if img is not None]
    if not strips:
        return None
    h = max(s.shape[0] for s in strips)
    wd = max(s.shape[1] for s in strips)
    label_w, pad = 220, 4
    sheet = Image.new("RGB", (label_w + wd, len(rows) * (h + pad)), (30, 30, 34))
    draw = ImageDraw.Draw(sheet)
    for i, (label, img) in enumerate(rows):
        y = i * (h + pad)
        if img is not None:
            sheet.paste(Image.fromarray(img), (label_w, y))
        else:
            draw.rectangle([label_w, y, label_w + wd - 1, y + h - 1], fill=(70, 20, 20))
        for j, line in enumerate(label.replace("  ", "\n").split("\n")):
            draw.text((8, y + 8 + 14 * j), line, fill=(235, 235, 235))
    sheet.save(path)
    return path
