"""Version 2 of the scene file (thinburn.scenefile): the per-frame inputs a Blender bake gives
its core (mesh igniters, Flames, collision objects, keyframed motion, painted maps, Heat
Ignites, Burn Duration), their round trip, their errors, and how thinburn.wedge.run_frames
applies them (thinburn.scene_run)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from thinburn import force_fields, scenefile, wedge
from thinburn.colliders import Colliders
from thinburn.scenes import rect_sheet
from thinburn.simulation import Simulation

FRAMES, FPS = 6, 24.0
# A noisy Wind with a sphere falloff along +y (a FieldSpec, as the add-on reads Blender's).
GUST = dict(kind="WIND", origin=(0.0, 0.0, 0.2), axis=(0.0, 1.0, 0.0), shape="POINT", strength=2.0,
            noise=1.0, seed=3, z_direction="BOTH", falloff="SPHERE", power=1.0, use_min=False,
            min_distance=0.0, use_max=False, max_distance=0.0)


def _box(half=0.05, centre=(0.1, 0.1, -0.06)):
    """A closed cube mesh (12 triangles) below the sheet."""
    c = np.array([[x, y, z] for x in (-half, half) for y in (-half, half) for z in (-half, half)])
    faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
             [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    return (c + centre).tolist(), faces


def _v2_spec() -> scenefile.SceneSpec:
    """A 0.2 m sheet (corners (0, 0) and (0.2, 0.2)) with every version-2 field set."""
    verts, faces = rect_sheet(0.2, 0.2, nx=11, ny=11)
    n = len(verts)
    speed = np.ones(n)
    speed[:11] = 2.0
    ignite = np.zeros(n)
    ignite[-1] = 1.0
    box_v, box_f = _box()
    g = [0.0, 0.0, -9.81]
    return scenefile.SceneSpec(
        verts, faces, material="paper", cells=16, fps=FPS, frames=FRAMES, floor=None,
        igniters=[{"point": [0.0, 0.0, 0.0], "time": 0.0, "radius": 0.02}],
        params={"buoyancy": 1.0, "gravity": g}, heat_ignites=True, finish_within=20.0,
        ignite_frame=2, wind=[[0.0, 0.1 * k, 0.0] for k in range(FRAMES)],
        fields=[{"frame": k + 1, "wind_scale": 0.5, "fields": [dict(GUST, origin=(0.1 * k, 0.0, 0.2))]}
                for k in range(FRAMES)],
        maps={"speed_map": speed.tolist(), "fuel_map": np.ones(n).tolist(), "ignite_map": ignite.tolist()},
        surfaces=[{"points": [[0.2, 0.0, 0.0], [0.2, 0.01, 0.0]], "time": 1 / FPS, "radius": 0.01}],
        flames=[[] if k < 3 else [[0.1, 0.1, -0.02, 0.01]] for k in range(FRAMES)],
        dynamics=[{"buoyancy": 1.0 + 0.5 * (k >= 4), "gravity": g} for k in range(FRAMES)],
        colliders=[{"name": "Box", "vertices": box_v, "faces": box_f, "thickness": 0.001,
                    "friction": [0.5] * 3 + [0.2] * 3, "rotation": [np.eye(3).tolist()] * FRAMES,
                    "translation": [[0.0, 0.001 * k, 0.0] for k in range(FRAMES)]}],
        to_world=[np.eye(4).tolist()] * FRAMES)


@pytest.mark.parametrize("ext", ["json", "npz"])
def test_version_2_fields_round_trip(tmp_path, ext):
    spec = _v2_spec()
    path = scenefile.save_scene(spec, tmp_path / f"scene.{ext}")
    back = scenefile.load_scene(path)
    assert back.to_dict() == spec.to_dict()
    d = back.to_dict()
    assert d["version"] == 2 and d["settings"]["finish_within"] == 20.0 and d["settings"]["heat_ignites"]
    assert back.colliders[0]["friction"][3] == 0.2 and back.flames[3] == [[0.1, 0.1, -0.02, 0.01]]


def test_a_scene_without_version_2_fields_is_written_as_version_1(tmp_path):
    """So an older thinburn on a farm still reads the scenes it could read before."""
    d = scenefile.demo_scene("paper", vertices=30).to_dict()
    assert d["version"] == 1 and "heat_ignites" not in d["settings"] and "maps" not in d


def test_an_older_reader_is_told_to_upgrade():
    d = _v2_spec().to_dict()
    d["version"] = scenefile.VERSION + 1
    with pytest.raises(ValueError, match=r"scene version 3 is newer than this thinburn reads \(2\): install"):
        scenefile.from_dict(d)


@pytest.mark.parametrize("change, error, match", [
    ({"settings": {"finish_within": 0.0}}, ValueError, "finish_within must be > 0"),
    ({"settings": {"heat_ignites": 1}}, TypeError, "heat_ignites must be true or false"),
    ({"settings": {"heat_ignites": True, "shell": False}}, ValueError, "heat_ignites: .*shell"),
    ({"settings": {"ignite_frame": FRAMES}}, ValueError, f"ignite_frame must be <= {FRAMES - 1}"),
    ({"settings": {"ignite_frame": None}}, ValueError, "maps.ignite_map: needs the setting ignite_frame"),
    ({"maps": {"speed_map": [1.0, 2.0]}}, ValueError, r"maps.speed_map has invalid shape"),
    ({"maps": {"heat_map": []}}, ValueError, r"maps: unknown maps \['heat_map'\]"),
    ({"flames": [[]]}, ValueError, f"flames: need one entry per frame \\({FRAMES}\\), got 1"),
    ({"dynamics": [{"bouyancy": 1.0}] * FRAMES}, ValueError, r"dynamics\[0\]: unknown motion parameters"),
    ({"surfaces": [{"points": [[0, 0]]}]}, ValueError, r"surfaces\[0\].points has invalid shape"),
    ({"to_world": [np.eye(3).tolist()] * FRAMES}, ValueError, r"to_world\[0\] has invalid shape"),
    ({"fields": [{"frame": 1, "fields": [dict(GUST, kind="VORTEX")]}] * FRAMES}, ValueError,
     r"fields\[0\].fields\[0\].kind: unknown value 'VORTEX'"),
    ({"fields": [{"frame": 1, "fields": [dict(GUST, gusty=True)]}] * FRAMES}, ValueError,
     r"fields\[0\].fields\[0\]: unknown field settings \['gusty'\]"),
    ({"fields": [{"frame": 1, "fields": [{k: v for k, v in GUST.items() if k != "power"}]}] * FRAMES},
     ValueError, r"fields\[0\].fields\[0\]: .*power"),
])
def test_bad_version_2_fields_are_named(change, error, match):
    d = _v2_spec().to_dict()
    for key, value in change.items():
        d[key] = {**d[key], **value} if key == "settings" else value
    with pytest.raises(error, match=match):
        scenefile.from_dict(d)


@pytest.mark.parametrize("field, value, match", [
    ("friction", -1.0, r"colliders\[0\].friction must be >= 0"),
    ("rotation", None, r"colliders\[0\].rotation: missing"),
    ("translation", [[0, 0, 0]], r"colliders\[0\].translation: need one entry per frame"),
    ("faces", [[0, 1, 99]], r"colliders\[0\].faces has indices out of range"),
])
def test_bad_colliders_are_named(field, value, match):
    d = _v2_spec().to_dict()
    d["colliders"][0][field] = value
    with pytest.raises(ValueError, match=match):
        scenefile.from_dict(d)


def _by_hand(spec):
    """The same bake driven call by call, in the add-on worker's order (worker.CoreWorker)."""
    dt = 1.0 / FPS
    c = spec.colliders[0]
    sim = Simulation(spec.vertices, spec.faces, material="paper", cells=16, seed=0, threads=1,
                     heat_ignites=True, finish_within=20.0, speed_map=np.asarray(spec.maps["speed_map"]),
                     fuel_map=np.asarray(spec.maps["fuel_map"]), **spec.params)
    colliders, out = None, []
    for k in range(FRAMES):
        if k == 0:
            sim.ignite([0.0, 0.0, 0.0], time=0.0, radius=0.02)
        if k == 1:
            sim.ignite_near(spec.surfaces[0]["points"], radius=0.01, time=max(dt, sim.time))
        if k == 2:
            sim.ignite_map(spec.maps["ignite_map"], time=max(2 * dt, sim.time))
        out.append(sim.vertex_positions())
        if k == FRAMES - 1:
            break
        rows = np.asarray(spec.flames[k]).reshape(-1, 4)
        sim.set_fire_sources(rows[:, :3], rows[:, 3])
        if colliders is None:
            colliders = Colliders(meshes=[dict(vertices=c["vertices"], faces=c["faces"], friction=0.5,
                                               thickness=0.001)])
            colliders.set_transform(0, c["translation"][0], np.eye(3))
            sim.set_colliders(colliders)
        else:
            colliders.set_transform(0, c["translation"][k], np.eye(3))
        if k == 3:
            colliders.set_friction(0, 0.2)
        # The add-on worker's wind: the fields at the lattice's control vertices (no move here).
        points = np.asarray(sim.lattice_positions()).reshape(-1, 3)
        gust = force_fields.FieldSpec(**dict(GUST, origin=(0.1 * k, 0.0, 0.2)))
        wind = force_fields.wind_at([gust], points, k + 1) * 0.5
        sim.set_wind_field(wind)
        sim.wind = tuple(wind.mean(axis=0))
        if k == 4:
            sim.set_dynamics(buoyancy=1.5)
        sim.step(dt)
    return np.asarray(out), sim


def test_run_frames_applies_every_field_in_the_bakes_order(tmp_path):
    """Bit for bit the same as the calls made by hand (the add-on worker's sequence): every
    field reaches the Simulation, at its frame, and nothing else is called."""
    spec = scenefile.load_scene(scenefile.save_scene(_v2_spec(), tmp_path / "scene.json"))
    sim, _, fps, frames = wedge.simulation_for(spec, {})
    got = []
    wedge.run_frames(sim, spec, fps, frames, lambda k, s: got.append(s.vertex_positions()))
    want, ref = _by_hand(spec)
    np.testing.assert_array_equal(np.asarray(got), want)
    np.testing.assert_array_equal(sim.vertex_ignition_times(), ref.vertex_ignition_times())
    lit = np.isfinite(sim.vertex_ignition_times())
    assert lit[-1] and lit[0] and lit[10]  # the ignite map's vertex, the igniter's and the surface's corner
    assert json.loads(json.dumps(spec.to_dict())) == spec.to_dict()


def test_a_wedge_of_a_moving_sheet_writes_world_positions(tmp_path, capsys):
    """to_world carries the bake frame along (here 1 cm along x per frame): frames.npz holds
    the simulated positions moved by it, to float32 rounding of the same doubles (exact)."""
    from thinburn.__main__ import main
    spec = _v2_spec()
    spec.to_world = [[[1, 0, 0, 0.01 * k], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]] for k in range(FRAMES)]
    path = scenefile.save_scene(spec, tmp_path / "moving.json")
    assert main(["wedge", "--scene", str(path), "--workers", "0", "--out", str(tmp_path / "w"),
                 "--param", "seed=0", "--render-frames", "0"]) == 0
    with np.load(tmp_path / "w" / "seed-0" / "frames.npz") as d:
        got = d["vertex_positions"]
    spec = scenefile.load_scene(path)
    sim, _, fps, frames = wedge.simulation_for(spec, {})
    want = []
    wedge.run_frames(sim, spec, fps, frames,
                     lambda k, s: want.append(s.vertex_positions() + [0.01 * k, 0, 0]))
    np.testing.assert_array_equal(got, np.asarray(want, dtype=np.float32))
