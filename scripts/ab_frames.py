"""Frame cost of the build on PYTHONPATH, for comparing two builds run in turn (A/B) on the
same machine in the same minutes: per preset, the demo scene remeshed to 16k vertices at 128²
cells on 2 threads, 120 frames after 24 of warm-up, the best of 3 runs per frame
(benchmarks/perf.py's best_frames).

    PYTHONPATH=OLD/python:. python scripts/ab_frames.py silk paper
    PYTHONPATH=python:. python scripts/ab_frames.py silk paper
"""
import sys

from benchmarks.perf import best_frames, frame_summary
from thinburn.demo import build, default_scene

for material in sys.argv[1:] or ["paper"]:
    scene = default_scene(material, vertices=16000)
    step_ms, pos_ms, stats, _ = best_frames(lambda: build(scene, material, cells=128, threads=2), 120, 24, 3)
    s = frame_summary(step_ms, pos_ms, stats)
    print(f"{material:10s} {s['ms_per_frame']:.3f} ms/frame (mesh {s['positions_ms']:.3f}) awake {s['awake']:.0f} "
          f"cg {s['cg_iterations']:.1f}", flush=True)
