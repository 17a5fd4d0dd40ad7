# Hertz-Mindlin sample scene for demsplit: two materials, spheres settled under
# gravity in a box of utils.wall side walls, a floor of two facets and a small
# fixed utils.box on the floor. Run headless:
#   DEMSPLIT_SITE=<site-packages with demsplit> DEMSPLIT_OUT=<dir> yade -n -j1 -x mindlin_box.py
# Writes to DEMSPLIT_OUT (default .): mindlin_box.h5 (HDF5 snapshots, if h5py
# imports), mindlin_box.npys (the numpy-only snapshot format), and, at the last
# snapshot, mindlin_box-spheres/-intrs VTKExporter files and mindlin_box.txt
# (export.textExt, format id_x_y_z_r_matId).
import os
import site

if os.environ.get("DEMSPLIT_SITE"):
    site.addsitedir(os.environ["DEMSPLIT_SITE"])  # appended: Debian's numpy stays first
import demsplit.yade
from yade import export, pack, utils

out = os.environ.get("DEMSPLIT_OUT", ".")
N_ITER = int(os.environ.get("DEMSPLIT_ITER", "24000"))
EVERY = int(os.environ.get("DEMSPLIT_EVERY", "8000"))
snapshot_h5 = os.path.join(out, "mindlin_box.h5")
snapshot_npy = os.path.join(out, "mindlin_box.npys")
for f in (snapshot_h5, snapshot_npy):
    if os.path.exists(f):
        os.remove(f)

soft = O.materials.append(FrictMat(young=2e7, poisson=0.3, density=2500, frictionAngle=0.4, label="soft"))
stiff = O.materials.append(FrictMat(young=1e8, poisson=0.2, density=2500, frictionAngle=0.4, label="stiff"))

L, H = 0.06, 0.06
sp = pack.SpherePack()
sp.makeCloud((0.001, 0.001, 0.001), (L - 0.001, L - 0.001, H), rMean=0.004, rRelFuzz=0.25, seed=7)
for k, (c, r) in enumerate(sp):
    O.bodies.append(utils.sphere(c, r, material=soft if k % 2 else stiff))
O.bodies.append(
    [
        utils.wall(0, axis=0, sense=1, material=stiff),
        utils.wall(L, axis=0, sense=-1, material=stiff),
        utils.wall(0, axis=1, sense=1, material=soft),
        utils.wall(L, axis=1, sense=-1, material=soft),
    ]
)
O.bodies.append(
    [
        utils.facet([(0, 0, 0), (L, 0, 0), (L, L, 0)], material=stiff),
        utils.facet([(0, 0, 0), (L, L, 0), (0, L, 0)], material=stiff),
    ]
)
O.bodies.append(utils.box((L / 2, L / 2, 0.004), (0.008, 0.008, 0.004), fixed=True, material=soft))


def export_state():
    demsplit.yade.snapshot(snapshot_h5)
    demsplit.yade.snapshot(snapshot_npy, format="npy")
    if O.iter >= N_ITER:
        vtk = export.VTKExporter(os.path.join(out, "mindlin_box"))
        vtk.exportSpheres(what=dict(id="b.id", matId="b.material.id"), numLabel=O.iter)
        vtk.exportInteractions(
            what=dict(
                id1="i.id1",
                id2="i.id2",
                penetrationDepth="i.geom.penetrationDepth",
                normal="i.geom.normal",
                refR1="i.geom.refR1",
                refR2="i.geom.refR2",
                kno="i.phys.kno",
                kn="i.phys.kn",
                ks="i.phys.ks",
                normalForce="i.phys.normalForce",
                shearForce="i.phys.shearForce",
                shearElastic="i.phys.shearElastic",
                contactPoint="i.geom.contactPoint",
            ),
            numLabel=O.iter,
        )
        export.textExt(os.path.join(out, "mindlin_box.txt"), format="id_x_y_z_r_matId")


O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb(), Bo1_Facet_Aabb(), Bo1_Box_Aabb()]),
    InteractionLoop(
        [Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom(), Ig2_Facet_Sphere_ScGeom(), Ig2_Box_Sphere_ScGeom()],
        [Ip2_FrictMat_FrictMat_MindlinPhys()],
        [Law2_ScGeom_MindlinPhys_Mindlin(label="mindlin")],
    ),
    # Between InteractionLoop and NewtonIntegrator: geometry, forces and positions of the same instant.
    PyRunner(command="export_state()", iterPeriod=EVERY, initRun=False),
    NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.4),
]
O.dt = 0.5 * utils.PWaveTimeStep()
O.run(N_ITER + 1, True)
print(
    "mindlin_box: %d spheres, %d real interactions, iter %d, normElastEnergy %.17g"
    % (len(sp), O.interactions.countReal(), O.iter, mindlin.normElastEnergy())
)
