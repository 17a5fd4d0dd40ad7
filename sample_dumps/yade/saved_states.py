# A YADE scene that never imports demsplit: Hertz-Mindlin, two materials, spheres settled in a box of
# facets, the state saved with O.save every EVERY iterations (binary .yade.gz and XML .xml.bz2 alternately),
# from a PyRunner placed between the InteractionLoop and the NewtonIntegrator (the instant whose positions
# the forces were computed from). Run headless:
#   DEMSPLIT_OUT=<dir> yade -n -j1 -x saved_states.py
# With DEMSPLIT_SITE set, the same PyRunner also writes demsplit's in-run snapshot (saved_states.h5), so
# that the saved-state path can be compared with it (tests/test_yade_state.py).
import os

from yade import geom, pack, utils

out = os.environ.get("DEMSPLIT_OUT", ".")
N_ITER = int(os.environ.get("DEMSPLIT_ITER", "20000"))
EVERY = int(os.environ.get("DEMSPLIT_EVERY", "10000"))
compare = bool(os.environ.get("DEMSPLIT_SITE"))
if compare:
    import site

    site.addsitedir(os.environ["DEMSPLIT_SITE"])
    import demsplit.yade

soft = O.materials.append(FrictMat(young=2e7, poisson=0.3, density=2500, frictionAngle=0.4, label="soft"))
stiff = O.materials.append(FrictMat(young=1e8, poisson=0.2, density=2500, frictionAngle=0.4, label="stiff"))
sp = pack.SpherePack()
sp.makeCloud((0.001, 0.001, 0.001), (0.049, 0.049, 0.03), rMean=0.004, rRelFuzz=0.25, seed=11)
for k, (c, r) in enumerate(sp):
    O.bodies.append(utils.sphere(c, r, material=soft if k % 2 else stiff))
O.bodies.append(geom.facetBox((0.025, 0.025, 0.025), (0.025, 0.025, 0.025), wallMask=31, material=stiff))


def save_state():
    name = "state-%06d.%s" % (O.iter, "yade.gz" if (O.iter // EVERY) % 2 else "xml.bz2")
    O.save(os.path.join(out, name))
    if compare:
        demsplit.yade.snapshot(os.path.join(out, "saved_states.h5"))


O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Facet_Aabb()]),
    InteractionLoop(
        [Ig2_Sphere_Sphere_ScGeom(), Ig2_Facet_Sphere_ScGeom()],
        [Ip2_FrictMat_FrictMat_MindlinPhys()],
        [Law2_ScGeom_MindlinPhys_Mindlin(label="law")],
    ),
    PyRunner(command="save_state()", iterPeriod=EVERY, initRun=False),
    NewtonIntegrator(gravity=(0, 0, -50.0), damping=0.4),
]
O.dt = 0.5 * utils.PWaveTimeStep()
O.run(N_ITER + 1, True)
print(
    "saved_states: %d spheres, %d real interactions, iter %d, normElastEnergy %.17g"
    % (len(sp), O.interactions.countReal(), O.iter, law.normElastEnergy())
)
