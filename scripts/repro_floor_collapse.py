import numpy as np, thinburn
from thinburn import _core
from thinburn.scenes import rect_sheet
v,f=rect_sheet(0.21,0.297,43,61)
sim=thinburn.Simulation(v,f,floor=0.0, buoyancy=0.0, wind_drag=0.0)
sim.ignite((0.004,0.004,0),radius=0.006)
Ds=[]; 
for k in range(3):
    sim.step(1/24); Ds.append(sim.rotation().ravel().copy())
M=sim.lattice_size; h=sim.lattice_thickness
rest=sim.lattice_rest_positions().reshape(-1,3); m=sim.control_masses().ravel()
print("D0 max", np.abs(Ds[0]).max(), "D1 max", np.abs(Ds[1]).max(), "min mass", m.min(), m.max())
lat=_core.FfdLattice(M, rest)
dyn=_core.LatticeDynamics(lat, k_structure=0.05,k_shear=0.05,k_flex=0.05,c_damping=1.7,k_transverse=0.05, has_floor=True, floor_z=-h/2, buoyancy=0.0, wind_drag=0.0)
dyn.set_masses(m)
for k in range(3):
    st=dyn.step(1/24, Ds[k], np.zeros(2*M*M))
    x=lat.positions
    print(k, st, "top z far", x[1::2][200:,2].mean()*1000)
