"""The main job: a built-in scene burnt from start to finish, written as pictures and arrays."""
from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, field

import numpy as np

from . import _validate as V
from . import render
from ._progress import Progress
from .scenes import A4, folded_sheet, lantern, rect_sheet, sphere
from .simulation import Simulation


@dataclass
class Scene:
    """A built-in scene: a mesh, how it is held, where it is lit, and its conditions."""

    description: str
    vertices: np.ndarray
    faces: np.ndarray
    ignite_at: tuple
    ignite_radius: float
    floor: float | None = None
    pinned: np.ndarray | None = None
    wind: tuple = (0.0, 0.0, 0.0)
    params: dict = field(default_factory=dict)
    view_pad: float = 0.35  # room around the sheet in the 3-D view, in sheet sizes
    view: tuple = (32.0, -58.0)  # (elevation, azimuth) of the 3-D view, degrees
    # A second 3-D view in place of the top view of the grid cells (shells on their own
    # surface have no grid): (elevation, azimuth), and a label per view.
    second_view: tuple | None = None
    labels: tuple = ("", "")
    name: str = ""  # the --scene name; "" for a material's default scene


# Curved shells (issue #11): their cells lie on the surface itself (Simulation geometry "surface").
SHELL_SCENES = ("lantern", "sphere", "letter")


def default_scene(material="paper", vertices=None) -> Scene:
    """The scene for a material, after the paper's figures.

    paper, hard_paper: an A4 sheet lying on a table, lit at a corner (Figs 8, 10).
    cloth, silk: a 40 cm square held at its four corners above a table, lit at a corner
    (Figs 9, 11): the denser cloth sags and sinks as it burns.
    curtain: a 1 m × 1.4 m curtain hanging from its top edge, wind from behind, lit at the
    bottom (Fig. 12); flames climb faster than they descend.

    vertices: None for the demo's own mesh, or about this many mesh vertices (the same sheet,
    its grid refined or coarsened with its aspect kept; at least 2 x 2).
    """
    if vertices is not None:
        vertices = V.integer(vertices, "vertices", low=4)
    if material in ("cloth", "silk"):
        nx, ny = _grid(41, 41, vertices)
        v, f = rect_sheet(0.4, 0.4, nx=nx, ny=ny, z=0.25)
        corners = [0, nx - 1, nx * (ny - 1), nx * ny - 1]
        return Scene(f"40 cm square of {material} held at its corners 25 cm above a table, lit at a corner",
                     v, f, (0.03, 0.03, 0.25), 0.012, floor=0.0, pinned=np.array(corners))
    if material == "curtain":
        nx, ny = _grid(41, 57, vertices)
        v, f = rect_sheet(1.0, 1.4, nx=nx, ny=ny, vertical=True, z=0.05)
        top = np.flatnonzero(np.isclose(v[:, 2], v[:, 2].max()))
        return Scene("1 m × 1.4 m curtain hanging from its top edge, wind from behind, lit at the bottom",
                     v, f, (0.5, 0.0, 0.06), 0.02, pinned=top, wind=(0.0, 1.5, 0.0),
                     params=dict(climb=0.4), view_pad=0.05)
    nx, ny = _grid(43, 61, vertices)
    v, f = rect_sheet(A4[0], A4[1], nx=nx, ny=ny)
    return Scene(f"A4 sheet of {material} lying on a table, lit at a corner", v, f,
                 (0.004, 0.004, 0.0), 0.006, floor=0.0)


def shell_scene(name: str) -> Scene:
    """A curved shell, burnt on its own surface (issue #11).

    lantern: an open paper cylinder, r = 10 cm, h = 30 cm, standing on a table, lit at one
    point half-way up its side (+x); the far side catches last, after about pi r / V0.
    sphere: a paper sphere, r = 10 cm, resting on a table, lit on its equator (+x).
    letter: an A4 sheet folded across its middle, one half on a table, the other raised at
    30 degrees, lit at the far corner of the flat half; the fire crosses the fold and climbs.
    """
    name = V.choice(name, "scene", SHELL_SCENES)
    if name == "lantern":
        v, f = lantern(0.1, 0.3, segments=128, rings=60)
        return Scene("paper lantern (open cylinder r = 10 cm, h = 30 cm) standing on a table, "
                     "lit half-way up its side", v, f, (0.1, 0.0, 0.15), 0.006, floor=0.0,
                     view_pad=0.12, view=(18.0, -25.0), second_view=(18.0, 155.0),
                     labels=("lit side", "far side"), name=name)
    if name == "sphere":
        v, f = sphere(0.1, level=4, centre=(0.0, 0.0, 0.1))
        return Scene("paper sphere (r = 10 cm) resting on a table, lit on its equator", v, f,
                     (0.1, 0.0, 0.1), 0.006, floor=0.0, view_pad=0.12, view=(20.0, -25.0),
                     second_view=(20.0, 155.0), labels=("lit side", "far side"), name=name)
    v, f = folded_sheet(A4[0], A4[1], angle=30.0, nx=43, ny=61)
    return Scene("A4 sheet folded at 30 degrees across its middle, one half on a table, "
                 "lit at a corner of that half", v, f, (0.004, 0.004, 0.0), 0.006, floor=0.0,
                 view=(28.0, -58.0), second_view=(22.0, 20.0), labels=("", "along the fold"),
                 name=name)


def _grid(nx: int, ny: int, vertices) -> tuple:
    """Grid size of a demo sheet: its own (nx, ny), or scaled to about `vertices` in all."""
    if vertices is None:
        return nx, ny
    k = np.sqrt(vertices / (nx * ny))
    return max(2, int(round(nx * k))), max(2, int(round(ny * k)))


def build(scene: Scene, material="paper", cells=128, seed=0, threads=None) -> Simulation:
    sim = Simulation(scene.vertices, scene.faces, material=material, cells=cells, seed=seed,
                     threads=threads, floor=scene.floor, pinned=scene.pinned, **scene.params)
    sim.wind = scene.wind
    sim.ignite(scene.ignite_at, time=0.0, radius=scene.ignite_radius)
    return sim


def run_demo(out_dir, material="paper", cells=128, fps=24.0, max_time=240.0, frames=60, seed=0,
             threads=None, quiet=False, scene=None) -> dict:
    """Burn the material's scene (or the shell scene named by `scene`, one of SHELL_SCENES)
    until nothing is left burning; write PNG frames, a GIF, the per-frame arrays and a
    summary. Returns the summary (also in summary.json)."""
    scene = default_scene(material) if scene is None else shell_scene(scene)
    os.makedirs(out_dir, exist_ok=True)
    sim = build(scene, material, cells, seed, threads)
    dt = 1.0 / fps
    expected = _expected_duration(scene, material, max_time)
    expected_steps = int(np.ceil(expected / dt))
    record_every = max(1, int(round(expected_steps / frames)))
    label = f"burning {material}" + (f" {scene.name}" if scene.name else "")
    progress = None if quiet else Progress(expected_steps, label=label)
    renderer = render.SceneRenderer(scene.faces, sim.vertex_positions(), material, scene.floor,
                                    elev=scene.view[0], azim=scene.view[1], pad=scene.view_pad,
                                    second_view=scene.second_view if sim.geometry == "surface" else None,
                                    labels=scene.labels)
    title = material + (f" {scene.name}" if scene.name else "")
    store = {k: [] for k in ("time", "cell_states", "cell_char", "vertex_positions", "vertex_char",
                             "lattice_positions")}
    particle_frames, images, step, t0, sim_seconds = [], [], 0, time.perf_counter(), 0.0
    aspect = _aspect(sim)
    try:
        while True:
            t_step = time.perf_counter()
            sim.step(dt)
            sim_seconds += time.perf_counter() - t_step
            step += 1
            states = sim.cell_states()
            done = not np.any(states == 1) or sim.time >= max_time
            if step % record_every == 0 or done:
                _record(sim, states, store, particle_frames)
                images.append(_picture(sim, states, renderer, material, aspect, title))
            if progress is not None:
                if not done and step >= progress.total:
                    # The fire outlasts the estimate (a curled sheet slows it): a quarter more
                    # each time, up to the cap. Jumping to the cap at once (240 s) took the
                    # A4 demo's bar from 100 % back to 43 %.
                    cap = int(np.ceil(max_time / dt))
                    progress.total = min(cap, max(progress.total + 1, int(np.ceil(1.25 * step))))
                progress.update(progress.total if done else step,
                                f"t={sim.time:6.1f}s burning={int(np.sum(states == 1))}")
            if done:
                break
    finally:
        renderer.close()
    wall = time.perf_counter() - t0
    return _write_outputs(out_dir, sim, store, particle_frames, images, scene, material, cells, fps,
                          step, wall, sim_seconds)


def _expected_duration(scene, material, max_time) -> float:
    """The burn's length from the fire alone (cheap: no shell), for the progress bar and the
    frame spacing."""
    probe = Simulation(scene.vertices, scene.faces, material=material, cells=48, shell=False,
                       **{k: v for k, v in scene.params.items() if k in ("climb",)})
    probe.ignite(scene.ignite_at, time=0.0, radius=scene.ignite_radius)
    while probe.time < max_time:
        probe.step(1.0)
        if not np.any(probe.cell_states() == 1):
            break
    return min(probe.time, max_time)


def _aspect(sim) -> float:
    dv, du = sim.cell_size
    return dv / du


def _vertex_states(sim) -> np.ndarray:
    ign, out = sim.vertex_ignition_times(), sim.vertex_burnout_times()
    return np.where(sim.time < ign, 0, np.where(sim.time < out, 1, 2)).astype(np.uint8)


def _picture(sim, states, renderer, material, aspect, title=None) -> np.ndarray:
    title = material if title is None else title
    if renderer.second_view is not None:
        cell_img = None  # cells on a surface have no grid to draw: a second 3-D view instead
    else:
        cell_img = render.cell_image(states, sim.cell_char(), sim.inside(), material, aspect, width=240)
    return renderer.frame(sim.vertex_positions(), sim.vertex_char(), _vertex_states(sim), cell_img,
                          sim.particles(), title=f"{title}   t = {sim.time:5.1f} s")


def _record(sim, states, store, particle_frames) -> None:
    store["time"].append(sim.time)
    store["cell_states"].append(states)
    store["cell_char"].append(sim.cell_char().astype(np.float32))
    store["vertex_positions"].append(sim.vertex_positions().astype(np.float32))
    store["vertex_char"].append(sim.vertex_char().astype(np.float32))
    store["lattice_positions"].append(sim.lattice_positions().astype(np.float32))
    p, t = sim.particles()
    particle_frames.append(np.column_stack([p, t]).astype(np.float32))


def _write_outputs(out_dir, sim, store, particle_frames, images, scene, material, cells, fps, steps,
                   wall, sim_seconds):
    frame_dir = os.path.join(out_dir, "frames")
    os.makedirs(frame_dir, exist_ok=True)
    for k, img in enumerate(images):
        render.save_png(img, os.path.join(frame_dir, f"frame_{k:04d}.png"))
    render.save_gif(images, os.path.join(out_dir, "burn.gif"), fps=12)
    arrays = {k: np.asarray(v) for k, v in store.items()}
    # Particle counts differ per frame: one (k, 4) array [x, y, z, temperature] per frame.
    arrays.update({f"particles_{k:04d}": p for k, p in enumerate(particle_frames)})
    arrays["faces"] = scene.faces
    # Per vertex, at the end (s; inf = never): the USD export's ignitionTime / burnoutTime.
    arrays["vertex_ignition_times"] = sim.vertex_ignition_times()
    arrays["vertex_burnout_times"] = sim.vertex_burnout_times()
    np.savez_compressed(os.path.join(out_dir, "frames.npz"), **arrays)
    burnt = float(np.mean(sim.cell_states()[sim.inside() == 1] == 2))
    summary = {
        "scene": scene.description, "material": material, "cells": cells, "lattice": sim.lattice_size,
        "geometry": sim.geometry, "num_cells": sim.num_cells, "lattice_couples": sim.lattice_couples,
        "fps": fps, "simulated_seconds": round(sim.time, 3), "steps": steps,
        "wall_seconds": round(wall, 3), "simulation_seconds": round(sim_seconds, 3),
        "simulated_frames_per_second": round(steps / sim_seconds, 1) if sim_seconds > 0 else None,
        "frames_written": len(images), "burnt_fraction": round(burnt, 4),
        "outputs": ["frames/frame_*.png", "burn.gif", "frames.npz", "summary.json"],
    }
    with open(os.path.join(out_dir, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    return summary

