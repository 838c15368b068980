"""Shape of the default flame and cost of the particle system.

Shape: a straight fire front 0.2 m long on a horizontal sheet (z = 0) burns for 1 s at
60 steps/s with the default parameters, in still air and in a 1 m/s wind along +x. Reports
the steady live count (expected birth_rate * length * lifetime), heights of hot particles
(temperature above temperature0 / e) and of all particles, their spread, and in the wind
the lean of the flame (mean x over mean z).

Cost: one step and one emit with a full pool of 20000 particles (best of repeats).

    python scripts/bench_particles.py [--out bench_out/bench_particles.json] [--threads 1]
"""
from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

import thinburn
from thinburn.particles import DEFAULTS, ParticleSystem

DT = 1.0 / 60.0


def line_front(k=64, length=0.2):
    x = np.linspace(-length / 2, length / 2, k)
    return (np.c_[x, np.zeros(k), np.zeros(k)], np.tile([0.0, 0.0, 1.0], (k, 1)),
            np.full(k, length / k))


def flame(wind, seconds=1.0, seed=0):
    pos, nrm, ln = line_front()
    ps = ParticleSystem(seed=seed)
    counts = []
    for _ in range(int(round(seconds / DT))):
        ps.emit(pos, nrm, ln, DT)
        ps.step(DT, wind)
        counts.append(ps.count)
    x, t = ps.positions(), ps.temperatures()
    hot = t > DEFAULTS["temperature0"] / np.e
    return {
        "wind": list(wind),
        "live_count_mean_last_half_s": float(np.mean(counts[len(counts) // 2:])),
        "live_count_expected": DEFAULTS["birth_rate"] * 0.2 * DEFAULTS["lifetime"],
        "hot_fraction": float(hot.mean()),
        "hot_z_mean_m": float(x[hot, 2].mean()),
        "hot_z_p90_m": float(np.percentile(x[hot, 2], 90)),
        "z_mean_m": float(x[:, 2].mean()),
        "z_p90_m": float(np.percentile(x[:, 2], 90)),
        "z_max_m": float(x[:, 2].max()),
        "y_rms_m": float(x[:, 1].std()),
        "x_mean_m": float(x[:, 0].mean()),
        "lean_mean_x_over_mean_z": float(x[:, 0].mean() / x[:, 2].mean()),
    }


def closed_form_heights():
    """Rise without turbulence (drag == cooling == k): z(t) = v0 (1 - e^-kt)/k
    + b/k^2 (1 - e^-kt (1 + kt)); at t = 1/cooling, at the mean lifetime, and as t -> inf."""
    b, k, c, v0 = (DEFAULTS[n] for n in ("buoyancy", "drag", "cooling", "birth_speed"))
    assert k == c, "the closed form below assumes drag == cooling"

    def z(t):
        return v0 * (1 - np.exp(-k * t)) / k + b / k**2 * (1 - np.exp(-k * t) * (1 + k * t))

    return {"z_at_T0_over_e_m": float(z(1 / c)), "z_at_mean_lifetime_m": float(z(DEFAULTS["lifetime"])),
            "z_limit_m": float(v0 / k + b / (k * c))}


def cost(repeats=5):
    rng = np.random.default_rng(0)
    k = 2000
    pos, nrm = rng.random((k, 3)), np.tile([0.0, 0.0, 1.0], (k, 1))
    ln = np.full(k, 0.01)
    ps = ParticleSystem(capacity=20000, birth_rate=20000 / (k * 0.01 * 0.1), lifetime=100.0)
    ps.emit(pos, nrm, ln, 0.1)  # fills the pool: 20000 births expected
    best_step = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        ps.step(DT, (0.3, 0.0, 0.0))
        best_step = min(best_step, time.perf_counter() - t0)
    ps2 = ParticleSystem(capacity=20000, birth_rate=1e4)
    best_emit = np.inf
    for _ in range(repeats):
        ps2 = ParticleSystem(capacity=20000, birth_rate=1e4)
        t0 = time.perf_counter()
        ps2.emit(pos, nrm, ln, DT)
        best_emit = min(best_emit, time.perf_counter() - t0)
    return {"particles": ps.count, "step_s": best_step, "step_ns_per_particle":
            1e9 * best_step / ps.count, "emit_births": ps2.count, "emit_s": best_emit,
            "emit_ns_per_birth": 1e9 * best_emit / max(ps2.count, 1)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="bench_out/bench_particles.json")
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args()
    thinburn.set_threads(args.threads)
    res = {"defaults": DEFAULTS, "threads": thinburn.get_threads(),
           "still": flame((0.0, 0.0, 0.0)), "wind_1ms": flame((1.0, 0.0, 0.0)), "cost": cost(),
           "closed_form": closed_form_heights()}
    for name in ("still", "wind_1ms"):
        f = res[name]
        print(f"{name:>9}: live {f['live_count_mean_last_half_s']:.0f} "
              f"(expected {f['live_count_expected']:.0f}), hot z mean {100 * f['hot_z_mean_m']:.1f} cm "
              f"p90 {100 * f['hot_z_p90_m']:.1f} cm, all z mean {100 * f['z_mean_m']:.1f} cm "
              f"p90 {100 * f['z_p90_m']:.1f} cm max {100 * f['z_max_m']:.1f} cm, "
              f"y rms {100 * f['y_rms_m']:.1f} cm, mean x {100 * f['x_mean_m']:.1f} cm, "
              f"lean x/z {f['lean_mean_x_over_mean_z']:.2f}")
    z = res["closed_form"]
    print(f"closed form (no turbulence): z at T0/e {100 * z['z_at_T0_over_e_m']:.1f} cm, at the mean "
          f"lifetime {100 * z['z_at_mean_lifetime_m']:.1f} cm, limit {100 * z['z_limit_m']:.1f} cm")
    c = res["cost"]
    print(f"     cost: step {1e3 * c['step_s']:.2f} ms for {c['particles']} particles "
          f"({c['step_ns_per_particle']:.0f} ns each); emit {1e3 * c['emit_s']:.2f} ms for "
          f"{c['emit_births']} births ({c['emit_ns_per_birth']:.0f} ns each), "
          f"{res['threads']} thread(s)")
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
    with open(args.out, "w") as f:
        json.dump(res, f, indent=1)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
