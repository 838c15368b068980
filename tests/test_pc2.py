"""The add-on's PC2 writer (blender_addon/cache.py), without Blender.

Checked byte for byte against the PC2 layout that Blender's Mesh Cache modifier reads, and
for the temp-file-then-rename contract: a previous file survives an aborted or failed write.
"""
import importlib.util
import struct
from pathlib import Path

import numpy as np
import pytest

CACHE_PY = Path(__file__).resolve().parent.parent / "blender_addon" / "cache.py"


def _load_cache():
    # cache.py imports nothing from Blender; load it alone (the package needs bpy).
    spec = importlib.util.spec_from_file_location("thinburn_addon_cache", CACHE_PY)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


cache = _load_cache()


def test_layout_is_byte_exact(tmp_path):
    path = tmp_path / "a.pc2"
    frames = [np.arange(6, dtype=float).reshape(2, 3) + 10 * k for k in range(3)]
    with cache.PC2Writer(path, 2, start_frame=5.0, sample_rate=1.0) as w:
        for f in frames:
            w.append(f)
    raw = path.read_bytes()
    head = struct.pack("<12siiffi", b"POINTCACHE2\0", 1, 2, 5.0, 1.0, 3)
    body = np.concatenate(frames).astype("<f4").tobytes()
    assert raw == head + body
    assert not (tmp_path / "a.pc2.partial").exists()


def test_reader_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    data = rng.normal(size=(4, 7, 3))
    with cache.PC2Writer(tmp_path / "b.pc2", 7, start_frame=-2.0) as w:
        for f in data:
            w.append(f)
    head, got = cache.read_pc2(tmp_path / "b.pc2")
    assert head == dict(version=1, points=7, start_frame=-2.0, sample_rate=1.0, samples=4)
    np.testing.assert_allclose(got, data, rtol=1e-7, atol=1e-7)  # float32 rounding only
    assert cache.read_pc2_header(tmp_path / "b.pc2")["samples"] == 4


def test_previous_file_survives_abort_and_exceptions(tmp_path):
    path = tmp_path / "c.pc2"
    with cache.PC2Writer(path, 1) as w:
        w.append([[1.0, 2.0, 3.0]])
    before = path.read_bytes()
    w = cache.PC2Writer(path, 1)
    w.append([[9.0, 9.0, 9.0]])
    assert path.read_bytes() == before  # nothing replaced until commit
    w.abort()
    w.abort()  # twice is fine
    assert path.read_bytes() == before and not (tmp_path / "c.pc2.partial").exists()
    with pytest.raises(RuntimeError):
        with cache.PC2Writer(path, 1) as w:
            w.append([[7.0, 7.0, 7.0]])
            raise RuntimeError("bake failed")
    assert path.read_bytes() == before


def test_bad_input_is_refused(tmp_path):
    with pytest.raises(ValueError, match="n_points"):
        cache.PC2Writer(tmp_path / "d.pc2", 0)
    w = cache.PC2Writer(tmp_path / "d.pc2", 2)
    with pytest.raises(ValueError, match="invalid shape"):
        w.append(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="NaN"):
        w.append([[0, 0, np.nan], [0, 0, 0]])
    w.commit()
    with pytest.raises(ValueError, match="after commit"):
        w.append(np.zeros((2, 3)))
    (tmp_path / "e.pc2").write_bytes(b"NOTAPC2FILE!" + bytes(20))
    with pytest.raises(ValueError, match="not a PC2"):
        cache.read_pc2(tmp_path / "e.pc2")
    (tmp_path / "f.pc2").write_bytes(struct.pack("<12siiffi", b"POINTCACHE2\0", 1, 5, 0, 1, 2))
    with pytest.raises(ValueError, match="promises"):
        cache.read_pc2(tmp_path / "f.pc2")


def test_seconds_to_frames_marks_never():
    got = cache.seconds_to_frames([0.0, 0.5, np.inf], frame_start=10, fps=24)
    assert got.dtype == np.float32
    np.testing.assert_array_equal(got, [10.0, 22.0, cache.NEVER_FRAME])
    assert cache.NEVER_FRAME > 1_048_574  # Blender's last frame
    assert float(np.float32(cache.NEVER_FRAME)) == cache.NEVER_FRAME
