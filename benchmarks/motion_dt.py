"""How the demo scenes' motion depends on dt (issue #12, item 3), as a table: `python -m
benchmarks.motion_dt [--time 20]` prints the bench's motion part (benchmarks/motion.py)
one line per scene: the RMS distance of the mesh's vertices from a dt = 1/480 s backward-Euler
run after --time seconds, over that run's RMS displacement from rest, and each run's wall time.
`python -m benchmarks --parts motion --out DIR` charts the same rows (DIR/motion.png)."""
from __future__ import annotations

import argparse

from . import motion


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--time", type=float, default=20.0)
    a = ap.parse_args(argv)
    rows = motion.bench_motion([1 / 24, 1 / 48, 1 / 96], 1 / 480, a.time, lambda m: None)
    for scene in dict.fromkeys(r["scene"] for r in rows):
        sr = [r for r in rows if r["scene"] == scene]
        cells = [f"{r['method']} 1/{round(1 / r['dt'])} {r['error']:.3f} ({r['seconds']:.2f} s)" for r in sr]
        print(f"{scene}: moved {1000 * sr[0]['moved']:.1f} mm | " + " | ".join(cells), flush=True)


if __name__ == "__main__":
    main()
