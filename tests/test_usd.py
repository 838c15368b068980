"""USD out (thinburn.usd): a small bake written and read back with pxr."""
from __future__ import annotations

import numpy as np
import pytest

pxr = pytest.importorskip("pxr")
from pxr import Usd, UsdGeom  # noqa: E402

import thinburn  # noqa: E402
from thinburn.scenes import rect_sheet  # noqa: E402
from thinburn.usd import NEVER, export_frames, times_to_codes, write_usd  # noqa: E402

FPS = 24.0


@pytest.fixture(scope="module")
def bake():
    """8 frames of a 9×9-vertex sheet lying on a floor, lit at a corner: arrays per frame."""
    verts, faces = rect_sheet(0.1, 0.1, nx=9, ny=9)
    sim = thinburn.Simulation(verts, faces, cells=16, threads=1, floor=0.0)
    sim.ignite((0.0, 0.0, 0.0), time=0.0, radius=0.02)
    out = dict(time=[], pos=[], char=[], particles=[])
    for _ in range(8):
        out["time"].append(sim.time)
        out["pos"].append(sim.vertex_positions().astype(np.float32))
        out["char"].append(sim.vertex_char().astype(np.float32))
        out["particles"].append(tuple(np.array(a) for a in sim.particles()))
        sim.step(1 / FPS)
    out.update(faces=faces, ignition=sim.vertex_ignition_times(), burnout=sim.vertex_burnout_times())
    return out


def _write(bake, path):
    codes = times_to_codes(bake["time"], FPS)
    write_usd(path, bake["faces"], codes, np.stack(bake["pos"]), FPS, char=np.stack(bake["char"]),
              ignition=times_to_codes(bake["ignition"], FPS),
              burnout=times_to_codes(bake["burnout"], FPS), particles=bake["particles"])
    return codes


@pytest.mark.parametrize("ext", ["usda", "usdc"])
def test_round_trip_points_primvars_and_particles(bake, tmp_path, ext):
    path = str(tmp_path / f"bake.{ext}")
    codes = _write(bake, path)
    assert np.allclose(codes, np.arange(8))  # time code = t * fps
    stage = Usd.Stage.Open(path)
    assert stage.GetTimeCodesPerSecond() == FPS and stage.GetFramesPerSecond() == FPS
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0.0, 7.0)
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    assert stage.GetDefaultPrim().GetPath() == "/ThinBurn"
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/ThinBurn/Sheet"))
    assert mesh
    assert np.array_equal(np.array(mesh.GetFaceVertexCountsAttr().Get()), np.full(len(bake["faces"]), 3))
    assert np.array_equal(np.array(mesh.GetFaceVertexIndicesAttr().Get()), bake["faces"].ravel())
    points = mesh.GetPointsAttr()
    assert points.GetTimeSamples() == list(codes)
    moved = np.abs(bake["pos"][-1] - bake["pos"][0]).max()
    assert moved > 1e-4  # the sheet curls: the samples differ
    for k in (0, 3, 7):
        got = np.array(points.Get(Usd.TimeCode(codes[k])))
        np.testing.assert_array_equal(got, bake["pos"][k])  # float32 in, float32 out
    api = UsdGeom.PrimvarsAPI(mesh)
    char = api.GetPrimvar("char")
    assert char.GetInterpolation() == UsdGeom.Tokens.vertex
    assert char.GetAttr().GetTimeSamples() == list(codes)
    np.testing.assert_array_equal(np.array(char.Get(Usd.TimeCode(codes[5]))), bake["char"][5])
    assert np.max(bake["char"][7]) > 0
    for name, seconds in (("ignitionTime", bake["ignition"]), ("burnoutTime", bake["burnout"])):
        pv = api.GetPrimvar(name)
        assert pv.GetInterpolation() == UsdGeom.Tokens.vertex
        assert not pv.GetAttr().GetTimeSamples()  # constant
        got = np.array(pv.Get(), dtype=np.float64)
        lit = np.isfinite(seconds)
        assert lit.any() and (~lit).any()
        np.testing.assert_allclose(got[lit], seconds[lit] * FPS, rtol=1e-6, atol=1e-5)
        assert np.all(got[~lit] == NEVER)
    fire = UsdGeom.Points(stage.GetPrimAtPath("/ThinBurn/Sheet_fire"))
    assert fire
    temp = UsdGeom.PrimvarsAPI(fire).GetPrimvar("temperature")
    assert temp.GetInterpolation() == UsdGeom.Tokens.vertex
    counts = []
    for k, (p, t) in enumerate(bake["particles"]):
        tc = Usd.TimeCode(codes[k])
        got_p = np.array(fire.GetPointsAttr().Get(tc)).reshape(-1, 3)
        got_t = np.array(temp.Get(tc))
        np.testing.assert_allclose(got_p, p, rtol=0, atol=1e-6 * max(1.0, np.abs(p).max(initial=0)))
        np.testing.assert_allclose(got_t, t, rtol=1e-6)
        assert len(fire.GetWidthsAttr().Get(tc)) == len(p)
        counts.append(len(p))
    assert max(counts) > 0  # the fire has particles by the last frames


def test_mesh_transform_and_polygons(tmp_path):
    quads = (np.array([4]), np.array([0, 1, 2, 3]))
    pos = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]], dtype=np.float32)
    m = np.eye(4)
    m[:3, 3] = (1.0, 2.0, 3.0)
    path = str(tmp_path / "quad.usda")
    write_usd(path, quads, [10.0], pos, 25.0, name="My Sheet.001", transform=m)
    stage = Usd.Stage.Open(path)
    prim = stage.GetPrimAtPath("/ThinBurn/My_Sheet_001")
    mesh = UsdGeom.Mesh(prim)
    assert list(mesh.GetFaceVertexCountsAttr().Get()) == [4]
    world = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode(10.0))
    assert tuple(world.Transform((1.0, 0.0, 0.0))) == (2.0, 2.0, 3.0)
    assert not stage.GetPrimAtPath("/ThinBurn/My_Sheet_001_fire")


def test_a_moving_sheet_has_a_transform_per_time_code(tmp_path):
    """An animated sheet's object-space points go under each frame's matrix (time samples)."""
    tri = [[0, 1, 2]]
    pos = np.zeros((3, 3, 3), np.float32)
    pos[:, 1, 0] = 1.0
    m = np.repeat(np.eye(4)[None], 3, axis=0)
    m[:, 0, 3] = (0.0, 0.5, 1.0)  # 0.5 m along x per frame
    path = str(tmp_path / "moving.usda")
    write_usd(path, tri, [1.0, 2.0, 3.0], pos, 24.0, transform=m)
    stage = Usd.Stage.Open(path)
    prim = stage.GetPrimAtPath("/ThinBurn/Sheet")
    for code, x in ((1.0, 1.0), (2.0, 1.5), (3.0, 2.0)):
        world = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode(code))
        assert tuple(world.Transform((1.0, 0.0, 0.0))) == (x, 0.0, 0.0)
    with pytest.raises(ValueError, match=r"transform has invalid shape: expected \(4, 4\) or \(3, 4, 4\)"):
        write_usd(str(tmp_path / "bad.usda"), tri, [1.0, 2.0, 3.0], pos, 24.0, transform=m[:2])
    with pytest.raises(ValueError, match="transform has invalid shape"):  # checked before the old file goes
        write_usd(path, tri, [1.0, 2.0, 3.0], pos, 24.0, transform=m[:2])
    assert Usd.Stage.Open(path).GetPrimAtPath("/ThinBurn/Sheet")


def test_bad_input_names_the_argument(tmp_path):
    path = str(tmp_path / "x.usda")
    pos = np.zeros((2, 3, 3), np.float32)
    tri = [[0, 1, 2]]
    with pytest.raises(ValueError, match="positions"):
        write_usd(path, tri, [0.0], pos, 24)
    with pytest.raises(ValueError, match="time_codes"):
        write_usd(path, tri, [1.0, 0.0], pos, 24)
    with pytest.raises(ValueError, match="fps"):
        write_usd(path, tri, [0.0, 1.0], pos, 0)
    with pytest.raises(ValueError, match="faces"):
        write_usd(path, [[0, 1, 5]], [0.0, 1.0], pos, 24)
    with pytest.raises(ValueError, match="char"):
        write_usd(path, tri, [0.0, 1.0], pos, 24, char=np.zeros((2, 4)))
    with pytest.raises(ValueError, match="ignitionTime"):
        write_usd(path, tri, [0.0, 1.0], pos, 24, ignition=np.zeros(4))
    with pytest.raises(ValueError, match="particles"):
        write_usd(path, tri, [0.0, 1.0], pos, 24, particles=[(np.zeros((0, 3)), np.zeros(0))])


def test_export_frames_from_an_npz(bake, tmp_path):
    """The demo's and the wedge's frames.npz layout, fps from summary.json beside it."""
    import json
    folder = tmp_path / "demo"
    folder.mkdir()
    arrays = dict(time=np.array(bake["time"]), vertex_positions=np.stack(bake["pos"]),
                  vertex_char=np.stack(bake["char"]), faces=bake["faces"],
                  vertex_ignition_times=bake["ignition"], vertex_burnout_times=bake["burnout"])
    arrays.update({f"particles_{k:04d}": np.column_stack(p).astype(np.float32)
                   for k, p in enumerate(bake["particles"])})
    np.savez(folder / "frames.npz", **arrays)
    with pytest.raises(ValueError, match="fps"):
        export_frames(folder / "frames.npz", tmp_path / "a.usda")
    (folder / "summary.json").write_text(json.dumps({"fps": FPS}))
    path = export_frames(folder / "frames.npz", tmp_path / "a.usda")
    stage = Usd.Stage.Open(path)
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/ThinBurn/Sheet"))
    np.testing.assert_array_equal(np.array(mesh.GetPointsAttr().Get(Usd.TimeCode(6.0))), bake["pos"][6])
    assert stage.GetPrimAtPath("/ThinBurn/Sheet_fire")
