# One small YADE scene per contact law of demsplit's registry (DEMSPLIT_LAW selects it):
#   viscel            Law2_ScGeom_ViscElPhys_Basic (ViscElMat, stiffness from young and poisson, cn/cs given)
#   viscofrict        Law2_ScGeom_ViscoFrictPhys_CundallStrack (FrictMat, shearCreep)
#   hertz_linear      Law2_ScGeom_MindlinPhys_HertzWithLinearShear
#   deresiewitz       Law2_ScGeom_MindlinPhys_MindlinDeresiewitz
#   adhesion          Law2_ScGeom_MindlinPhys_Mindlin with includeAdhesion (DMT, surface energy gamma 0.5 J/m^2)
#   capillary         CundallStrack with Law2_ScGeom_CapillaryPhys_Capillarity (no capillary tables: no force)
#   cohfrict          Law2_ScGeom6D_CohFrictPhys_CohesionMoment (cohesive bonds, bending and twisting moments)
#   jcfpm             Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM (bonds made at 1.2 x the contact distance)
# Two materials, spheres settled under gravity in a box of facets. Run headless:
#   DEMSPLIT_SITE=<site-packages with demsplit> DEMSPLIT_OUT=<dir> DEMSPLIT_LAW=viscel yade -n -j1 -x laws_box.py
# Writes DEMSPLIT_OUT/laws_box_<law>.h5 (demsplit.yade snapshots, with the laws' own energy functions).
import os
import site

if os.environ.get("DEMSPLIT_SITE"):
    site.addsitedir(os.environ["DEMSPLIT_SITE"])  # appended: Debian's numpy stays first
import demsplit.yade
from yade import geom, pack, utils

law = os.environ.get("DEMSPLIT_LAW", "viscel")
out = os.environ.get("DEMSPLIT_OUT", ".")
N_ITER = int(os.environ.get("DEMSPLIT_ITER", "20000"))
EVERY = int(os.environ.get("DEMSPLIT_EVERY", "10000"))
snapshot = os.path.join(out, "laws_box_%s.h5" % law)
if os.path.exists(snapshot):
    os.remove(snapshot)

if law == "viscel":
    # stiffness from young (kn_i = 2 E_i R_i, ks_i = poisson kn_i) and the dashpots cn, cs
    mats = [
        ViscElMat(cn=0.5, cs=0.2, young=2e7, poisson=0.3, density=2500, frictionAngle=0.4),
        ViscElMat(cn=0.5, cs=0.2, young=1e8, poisson=0.2, density=2500, frictionAngle=0.4),
    ]
    ip2, law2, ig2 = Ip2_ViscElMat_ViscElMat_ViscElPhys(), Law2_ScGeom_ViscElPhys_Basic(label="law"), "ScGeom"
elif law == "cohfrict":
    mats = [
        CohFrictMat(
            young=2e7,
            poisson=0.3,
            density=2500,
            frictionAngle=0.4,
            isCohesive=True,
            normalCohesion=1e5,
            shearCohesion=1e5,
            momentRotationLaw=True,
            alphaKr=2.0,
            alphaKtw=1.0,
        ),
        CohFrictMat(
            young=1e8,
            poisson=0.2,
            density=2500,
            frictionAngle=0.4,
            isCohesive=True,
            normalCohesion=1e5,
            shearCohesion=1e5,
            momentRotationLaw=True,
            alphaKr=2.0,
            alphaKtw=1.0,
        ),
    ]
    ip2 = Ip2_CohFrictMat_CohFrictMat_CohFrictPhys(setCohesionNow=False, setCohesionOnNewContacts=True)
    law2, ig2 = (
        Law2_ScGeom6D_CohFrictPhys_CohesionMoment(useIncrementalForm=True, always_use_moment_law=True, label="law"),
        "ScGeom6D",
    )
elif law == "jcfpm":
    mats = [
        JCFpmMat(young=2e7, poisson=0.3, density=2500, frictionAngle=0.4, tensileStrength=1e5, cohesion=1e5),
        JCFpmMat(young=1e8, poisson=0.2, density=2500, frictionAngle=0.4, tensileStrength=1e5, cohesion=1e5),
    ]
    ip2 = Ip2_JCFpmMat_JCFpmMat_JCFpmPhys(cohesiveTresholdIteration=1)
    law2, ig2 = Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM(label="law"), "ScGeom-bonds"
else:
    mats = [
        FrictMat(young=2e7, poisson=0.3, density=2500, frictionAngle=0.4),
        FrictMat(young=1e8, poisson=0.2, density=2500, frictionAngle=0.4),
    ]
    if law == "viscofrict":
        ip2 = Ip2_FrictMat_FrictMat_ViscoFrictPhys()
        law2 = Law2_ScGeom_ViscoFrictPhys_CundallStrack(shearCreep=True, viscosity=1e3, label="law")
    elif law == "hertz_linear":
        ip2, law2 = Ip2_FrictMat_FrictMat_MindlinPhys(), Law2_ScGeom_MindlinPhys_HertzWithLinearShear(label="law")
    elif law == "capillary":
        ip2, law2 = Ip2_FrictMat_FrictMat_CapillaryPhys(), Law2_ScGeom_FrictPhys_CundallStrack(label="law")
    elif law == "adhesion":
        ip2 = Ip2_FrictMat_FrictMat_MindlinPhys(gamma=0.5)
        law2 = Law2_ScGeom_MindlinPhys_Mindlin(includeAdhesion=True, label="law")
    elif law == "deresiewitz":
        ip2, law2 = Ip2_FrictMat_FrictMat_MindlinPhys(), Law2_ScGeom_MindlinPhys_MindlinDeresiewitz(label="law")
    else:
        raise SystemExit("unknown DEMSPLIT_LAW %r" % law)
    ig2 = "ScGeom"
soft, stiff = [O.materials.append(m) for m in mats]

L, H = 0.05, 0.03
sp = pack.SpherePack()
sp.makeCloud((0.001, 0.001, 0.001), (L - 0.001, L - 0.001, H), rMean=0.004, rRelFuzz=0.25, seed=11)
for k, (c, r) in enumerate(sp):
    O.bodies.append(utils.sphere(c, r, material=soft if k % 2 else stiff))
O.bodies.append(geom.facetBox((L / 2, L / 2, H / 2), (L / 2, L / 2, H / 2), wallMask=31, material=stiff))


def export_state():
    demsplit.yade.snapshot(snapshot)


bonds = 1.2 if ig2 == "ScGeom-bonds" else 1.0  # JCFpm bonds spheres within 1.2 x their contact distance
if ig2 == "ScGeom6D":
    geoms = [Ig2_Sphere_Sphere_ScGeom6D(), Ig2_Facet_Sphere_ScGeom6D()]
else:
    geoms = [Ig2_Sphere_Sphere_ScGeom(interactionDetectionFactor=bonds), Ig2_Facet_Sphere_ScGeom()]
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(aabbEnlargeFactor=bonds), Bo1_Facet_Aabb()]),
    InteractionLoop(geoms, [ip2], [law2]),
    *([Law2_ScGeom_CapillaryPhys_Capillarity(capillaryPressure=1e3)] if law == "capillary" else []),
    # Between InteractionLoop and NewtonIntegrator: geometry, forces and positions of the same instant.
    PyRunner(command="export_state()", iterPeriod=EVERY, initRun=False),
    NewtonIntegrator(gravity=(0, 0, -50.0), damping=0.4),
]
O.dt = 0.5 * utils.PWaveTimeStep()
O.run(N_ITER + 1, True)
print("laws_box_%s: %d spheres, %d real interactions, iter %d" % (law, len(sp), O.interactions.countReal(), O.iter))
