# Linear CundallStrack sample scene for demsplit: two materials in a periodic
# cell compressed isotropically by PeriTriaxController. Run headless:
#   DEMSPLIT_SITE=<site-packages with demsplit> DEMSPLIT_OUT=<dir> yade -n -j1 -x cundall_periodic.py
# Writes to DEMSPLIT_OUT (default .): cundall_periodic.h5 (HDF5 snapshots, if
# h5py imports), cundall_periodic.npys (numpy-only snapshot format), and, at
# the last snapshot, cundall_periodic-spheres/-intrs VTKExporter files and
# cundall_periodic.txt (export.text, format x_y_z_r: %g, no ids).
import os
import site

if os.environ.get("DEMSPLIT_SITE"):
    site.addsitedir(os.environ["DEMSPLIT_SITE"])  # appended: Debian's numpy stays first
import demsplit.yade
from yade import export, pack, utils

out = os.environ.get("DEMSPLIT_OUT", ".")
N_ITER = int(os.environ.get("DEMSPLIT_ITER", "9000"))
EVERY = int(os.environ.get("DEMSPLIT_EVERY", "3000"))
snapshot_h5 = os.path.join(out, "cundall_periodic.h5")
snapshot_npy = os.path.join(out, "cundall_periodic.npys")
for f in (snapshot_h5, snapshot_npy):
    if os.path.exists(f):
        os.remove(f)

# CundallStrack: kn = 2 EaRa EbRb/(EaRa + EbRb); 'poisson' is ks/kn per material.
soft = O.materials.append(FrictMat(young=5e7, poisson=0.3, density=2600, frictionAngle=0.5, label="soft"))
stiff = O.materials.append(FrictMat(young=2e8, poisson=0.4, density=2600, frictionAngle=0.5, label="stiff"))

O.periodic = True
O.cell.setBox(0.03, 0.03, 0.03)
sp = pack.SpherePack()
sp.makeCloud((0, 0, 0), (0.03, 0.03, 0.03), rMean=0.002, rRelFuzz=0.3, periodic=True, seed=3)
for k, (c, r) in enumerate(sp):
    O.bodies.append(utils.sphere(c, r, material=soft if k % 2 else stiff))
O.trackEnergy = True


def export_state():
    demsplit.yade.snapshot(snapshot_h5)
    demsplit.yade.snapshot(snapshot_npy, format="npy")
    if O.iter >= N_ITER:
        vtk = export.VTKExporter(os.path.join(out, "cundall_periodic"))
        vtk.exportSpheres(what=dict(id="b.id", matId="b.material.id"), numLabel=O.iter)
        vtk.exportInteractions(
            what=dict(id1="i.id1", id2="i.id2", kn="i.phys.kn", ks="i.phys.ks", shearForce="i.phys.shearForce"),
            numLabel=O.iter,
        )
        export.text(os.path.join(out, "cundall_periodic.txt"))


O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb()]),
    InteractionLoop(
        [Ig2_Sphere_Sphere_ScGeom()],
        [Ip2_FrictMat_FrictMat_FrictPhys()],
        [Law2_ScGeom_FrictPhys_CundallStrack(label="cundall")],
    ),
    # Between InteractionLoop and NewtonIntegrator: geometry, forces and positions of the same instant.
    PyRunner(command="export_state()", iterPeriod=EVERY, initRun=False),
    PeriTriaxController(
        goal=(-2e5, -2e5, -2e5), stressMask=7, maxUnbalanced=1e-3, maxStrainRate=(20, 20, 20), dynCell=True, mass=0.05
    ),
    NewtonIntegrator(damping=0.4),
]
O.dt = 0.5 * utils.PWaveTimeStep()
O.run(N_ITER + 1, True)
print(
    "cundall_periodic: %d spheres, %d real interactions, iter %d, elastPotential %.17g, elasticEnergy %.17g"
    % (len(sp), O.interactions.countReal(), O.iter, O.energy["elastPotential"], cundall.elasticEnergy())
)
