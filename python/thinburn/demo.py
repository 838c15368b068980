"""The main job: a built-in scene burnt from start to finish, written as pictures and arrays."""
from __future__ import annotations

import json
import os
import time

import numpy as np

from . import render
from ._progress import Progress
from .materials import MATERIALS
from .scenes import A4, rect_sheet
from .simulation import Simulation


def default_scene(material="paper", cells=128, seed=0, threads=None):
    """An A4 sheet lying flat, lit at one corner: (simulation, description)."""
    verts, faces = rect_sheet(A4[0], A4[1], nx=43, ny=61)
    sim = Simulation(verts, faces, material=material, cells=cells, seed=seed, threads=threads)
    corner = np.array([0.004, 0.004, 0.0])
    sim.ignite(corner, time=0.0, radius=0.006)
    return sim, f"A4 sheet of {material} lying flat, lit at the corner (0, 0)"


def run_demo(out_dir, material="paper", cells=128, fps=24.0, max_time=240.0, frames=60, seed=0,
             threads=None, quiet=False) -> dict:
    """Burn the default scene until nothing is left burning; write PNG frames, a GIF and arrays.

    Returns a summary dict (also written to summary.json).
    """
    os.makedirs(out_dir, exist_ok=True)
    sim, description = default_scene(material, cells, seed, threads)
    dt = 1.0 / fps
    aspect = A4[1] / A4[0]
    # A first pass finds how long the burn takes, so the frames span the whole of it.
    expected_steps = int(np.ceil(_estimate_duration(sim, max_time) / dt))
    record_every = max(1, int(round(expected_steps / frames)))
    sim, _ = default_scene(material, cells, seed, threads)
    progress = None if quiet else Progress(expected_steps, label=f"burning {material}")
    store = {"time": [], "cell_states": [], "cell_char": [], "vertex_positions": [], "vertex_char": []}
    images, step, t0 = [], 0, time.perf_counter()
    while True:
        sim.step(dt)
        step += 1
        states = sim.cell_states()
        done = not np.any(states == 1) or sim.time >= max_time
        if step % record_every == 0 or done:
            _record(sim, states, store)
            images.append(render.cell_image(states, sim.cell_char(), sim.inside(), material, aspect))
        if progress is not None:
            progress.update(min(step, progress.total - (not done)),
                            f"t={sim.time:6.1f}s burning={int(np.sum(states == 1))}")
        if done:
            break
    wall = time.perf_counter() - t0
    return _write_outputs(out_dir, sim, store, images, description, material, cells, fps, step, wall)


def _estimate_duration(sim, max_time) -> float:
    dt = 0.5
    while sim.time < max_time:
        sim.step(dt)
        if not np.any(sim.cell_states() == 1):
            break
    return sim.time


def _record(sim, states, store) -> None:
    store["time"].append(sim.time)
    store["cell_states"].append(states)
    store["cell_char"].append(sim.cell_char().astype(np.float32))
    store["vertex_positions"].append(sim.vertex_positions().astype(np.float32))
    store["vertex_char"].append(sim.vertex_char().astype(np.float32))


def _write_outputs(out_dir, sim, store, images, description, material, cells, fps, steps, wall):
    frame_dir = os.path.join(out_dir, "frames")
    os.makedirs(frame_dir, exist_ok=True)
    for k, img in enumerate(images):
        render.save_png(img, os.path.join(frame_dir, f"frame_{k:04d}.png"))
    render.save_gif(images, os.path.join(out_dir, "burn.gif"), fps=12)
    arrays = {k: np.asarray(v) for k, v in store.items()}
    np.savez_compressed(os.path.join(out_dir, "frames.npz"), **arrays)
    burnt = float(np.mean(sim.cell_states()[sim.inside() == 1] == 2))
    summary = {
        "scene": description, "material": material, "cells": cells, "fps": fps,
        "simulated_seconds": round(sim.time, 3), "steps": steps, "wall_seconds": round(wall, 3),
        "steps_per_second": round(steps / wall, 1) if wall > 0 else None,
        "frames_written": len(images), "burnt_fraction": round(burnt, 4),
        "outputs": ["frames/frame_*.png", "burn.gif", "frames.npz", "summary.json"],
    }
    with open(os.path.join(out_dir, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    return summary


MATERIAL_NAMES = tuple(MATERIALS)
