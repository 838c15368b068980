"""python -m thinburn.bench --quick: rows for every part and method, exact checks on the
fire front's errors, the symplectic stability limit, and two valid images."""
import json
import math
import os

import pytest
from PIL import Image

from thinburn import FRONT_METHODS
from thinburn import bench


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    assert bench.main(["--quick", "--out", out]) == 0
    with open(out / "results.json") as f:
        rows = json.load(f)
    return out, rows


def test_rows_for_every_part_and_method(quick_run):
    _, rows = quick_run
    methods = {}
    for r in rows:
        methods.setdefault(r["part"], set()).add(r["method"])
    assert methods["fire_front"] == set(FRONT_METHODS)
    assert methods["integrators"] == set(bench.INTEGRATORS)
    assert methods["stability"] == set(bench.INTEGRATORS)
    assert methods["heat"] == {"direct", "fast"}
    for r in rows:
        if r["part"] == "stability":
            continue
        assert math.isfinite(r["error"]) and r["error"] >= 0, r
        assert r["seconds"] > 0, r


def test_fire_front_errors(quick_run):
    _, rows = quick_run
    front = [r for r in rows if r["part"] == "fire_front"]
    assert {r["resolution"] for r in front} == {65, 129, 257}
    for r in front:
        if r["method"] == "fmm":
            assert r["error"] < 1e-9, r
        if r["method"] == "cellular":
            # the octagonal front is 1/cos(22.5 deg) - 1 = 8.24 % late along the 22.5 deg rays
            assert abs(r["error"] - 0.0824) < 0.002, r


def test_integrator_errors_shrink_with_dt(quick_run):
    _, rows = quick_run
    for name in bench.INTEGRATORS:
        rs = sorted((r for r in rows if r["part"] == "integrators" and r["method"] == name),
                    key=lambda r: r["dt"])
        assert len(rs) >= 2
        assert rs[0]["error"] < rs[-1]["error"]  # first order: smaller dt, smaller error


def test_heat_fast_within_tolerance(quick_run):
    _, rows = quick_run
    for r in rows:
        if r["part"] == "heat":
            assert r["error"] <= (0.0 if r["method"] == "direct" else r["tolerance"]), r


def test_stability_against_theory(quick_run):
    _, rows = quick_run
    st = [r for r in rows if r["part"] == "stability"]
    sym = [r for r in st if r["method"] == "symplectic"]
    assert len(sym) >= 3
    for r in sym:
        assert abs(r["omega_dt"] / 2.0 - 1.0) < 0.10, r
    for r in st:
        if r["method"] == "explicit":
            assert abs(r["omega_dt"] / math.sqrt(2.0) - 1.0) < 0.10, r
        if r["method"] == "implicit":
            assert r["stable"], r


def test_images(quick_run):
    out, _ = quick_run
    for name in ("speed_accuracy.png", "stability.png"):
        path = os.path.join(out, name)
        with Image.open(path) as im:
            im.verify()
        with Image.open(path) as im:
            assert im.size[0] > 100 and im.size[1] > 100


def test_bad_arguments(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        bench.main(["--bogus", "--out", tmp_path])
    assert e.value.code == 2
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(SystemExit) as e:
        bench.main(["--out", blocker / "sub"])
    assert e.value.code == 2
    assert "not a writable directory" in capsys.readouterr().err
