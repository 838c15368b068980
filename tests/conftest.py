import pytest

from thinburn.scenes import rect_sheet


@pytest.fixture
def a4():
    """An A4 sheet lying flat: (vertices, faces)."""
    return rect_sheet(0.210, 0.297, nx=22, ny=31)


@pytest.fixture
def square():
    """A 0.2 m square sheet lying flat: (vertices, faces)."""
    return rect_sheet(0.2, 0.2, nx=21, ny=21)


@pytest.fixture
def hanging_curtain():
    """A burning half-size pleated curtain (0.5 m x 0.7 m, 2 cm pleats 20 cm apart, 443
    couples), pinned along its top, lit at its hem, 5 s at 1/24 s with the factor preconditioner.
    Called with sleeping and set_dynamics keywords; returns the simulation and the summed
    step_stats (passes, factorizations, cg_iterations) with the most CG iterations of a step."""
    import numpy as np
    import thinburn

    def run(sleeping=True, seconds=5.0, **dynamics):
        v, f = rect_sheet(0.5, 0.7, nx=41, ny=57, vertical=True, z=0.05)
        v[:, 1] = 0.02 * np.sin(2 * np.pi * v[:, 0] / 0.2)
        top = np.flatnonzero(np.isclose(v[:, 2], v[:, 2].max()))
        sim = thinburn.Simulation(v, f, material="curtain", cells=64, pinned=top, climb=0.4, sleeping=sleeping)
        sim.set_dynamics(preconditioner="ldlt", **dynamics)
        sim.ignite((0.25, 0.0, 0.06), radius=0.02)
        counts = dict(passes=0, factorizations=0, cg_iterations=0, most_cg=0)
        for _ in range(round(24 * seconds)):
            sim.step(1 / 24)
            st = sim.step_stats()
            for key in ("passes", "factorizations", "cg_iterations"):
                counts[key] += st[key]
            counts["most_cg"] = max(counts["most_cg"], st["cg_iterations"])
        return sim, counts

    return run
