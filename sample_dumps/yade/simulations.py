# States of several small YADE simulations, saved with O.save the ways users save them, for the rule "one run is
# one simulation" (tests/test_yade_simulations.py). The script never imports demsplit. Run headless:
#   DEMSPLIT_OUT=<dir> yade -n -j1 -x simulations.py
# Hertz-Mindlin, the same two materials, spheres falling into an open box, but for the last:
#   facets-<iter>.yade.gz   a box of facets; at 6000 a lid (a Wall of an inline material) is added, pressing on
#                           the spheres, at 9000 one facet of the box is erased: states at 3000, 6000, 9000, 12000
#   again-006000.xml.bz2    the state of iteration 6000 saved a second time, as XML (the same state)
#   changed-006000.yade.gz  iteration 6000 again, after one sphere's velocity was changed (another state)
#   seed-003000.yade.gz     the facet box with spheres of other radii (another simulation, the same shapes)
#   clumps-004500.yade.gz   a box of Walls holding clumps (another simulation: other bodies under the same ids)
#   viscelcap-000020.yade.gz  two spheres on a Wall under Law2_ScGeom_ViscElCapPhys_Basic, a law demsplit does not
#                           analyse
import os
import random

from yade import geom, pack, utils

out = os.environ.get("DEMSPLIT_OUT", ".")


def materials():
    soft = O.materials.append(FrictMat(young=2e7, poisson=0.3, density=2500, frictionAngle=0.4, label="soft"))
    stiff = O.materials.append(FrictMat(young=1e8, poisson=0.2, density=2500, frictionAngle=0.4, label="stiff"))
    return soft, stiff


def spheres(soft, stiff, seed, r=0.003):
    rnd = random.Random(seed)
    for k, b in enumerate(
        pack.regularHexa(pack.inAlignedBox((0.001, 0.001, 0.001), (0.023, 0.023, 0.02)), radius=r, gap=0)
    ):
        s = utils.sphere(b.state.pos, r * rnd.uniform(0.9, 0.99), material=soft if k % 2 else stiff)
        s.state.vel = Vector3(*(rnd.uniform(-0.2, 0.2) for _ in range(3)))
        O.bodies.append(s)


def engines(shapes):
    bo1 = {"Sphere": Bo1_Sphere_Aabb(), "Facet": Bo1_Facet_Aabb(), "Wall": Bo1_Wall_Aabb()}
    ig2 = {"Sphere": Ig2_Sphere_Sphere_ScGeom(), "Facet": Ig2_Facet_Sphere_ScGeom(), "Wall": Ig2_Wall_Sphere_ScGeom()}
    O.engines = [
        ForceResetter(),
        InsertionSortCollider([bo1[s] for s in shapes]),
        InteractionLoop(
            [ig2[s] for s in shapes], [Ip2_FrictMat_FrictMat_MindlinPhys()], [Law2_ScGeom_MindlinPhys_Mindlin()]
        ),
        NewtonIntegrator(gravity=(0, 0, -200.0), damping=0.3),
    ]
    O.dt = 0.5 * utils.PWaveTimeStep()


def save(name):
    O.save(os.path.join(out, name))


def facet_box(seed):
    soft, stiff = materials()
    spheres(soft, stiff, seed)
    box = O.bodies.append(geom.facetBox((0.012, 0.012, 0.015), (0.012, 0.012, 0.015), wallMask=31, material=stiff))
    engines(("Sphere", "Facet", "Wall"))
    return box


O.reset()
box = facet_box(1)
O.run(3000, True)
save("facets-003000.yade.gz")
O.run(3000, True)
save("facets-006000.yade.gz")
save("again-006000.xml.bz2")
first = next(b for b in O.bodies if isinstance(b.shape, Sphere))
kept = Vector3(first.state.vel)
first.state.vel = kept + Vector3(0, 0, 1)
save("changed-006000.yade.gz")
first.state.vel = kept
top = max(b.state.pos[2] + b.shape.radius for b in O.bodies if isinstance(b.shape, Sphere))
lid = O.bodies.append(
    utils.wall(
        top - 1e-4, axis=2, sense=-1, material=FrictMat(young=5e8, poisson=0.25, density=2500, frictionAngle=0.4)
    )
)
O.bodies[lid].state.vel = Vector3(0, 0, -0.01)  # pressing on the spheres
O.run(3000, True)
save("facets-009000.yade.gz")
O.bodies.erase(box[0])
O.run(3000, True)
save("facets-012000.yade.gz")
print(
    "simulations facets: %d bodies, %d real interactions at iteration %d"
    % (len([b for b in O.bodies if b is not None]), O.interactions.countReal(), O.iter)
)

O.reset()
facet_box(2)
O.run(3000, True)
save("seed-003000.yade.gz")

O.reset()
soft, stiff = materials()
rnd = random.Random(3)
for k in range(18):
    c = Vector3(0.005 + 0.008 * (k % 3), 0.005 + 0.008 * (k // 3 % 3), 0.005 + 0.008 * (k // 9))
    a = Vector3(rnd.uniform(-1, 1), rnd.uniform(-1, 1), rnd.uniform(-1, 1)).normalized() * 0.0015
    O.bodies.appendClumped([utils.sphere(c - a, 0.0025, material=soft), utils.sphere(c + a, 0.002, material=stiff)])
O.bodies.append(
    [
        utils.wall(0, axis=2, sense=1, material=stiff),
        utils.wall(0, axis=0, sense=1, material=stiff),
        utils.wall(0.024, axis=0, sense=-1, material=stiff),
        utils.wall(0, axis=1, sense=1, material=stiff),
        utils.wall(0.024, axis=1, sense=-1, material=stiff),
    ]
)
engines(("Sphere", "Wall"))
O.run(4500, True)
save("clumps-004500.yade.gz")
print(
    "simulations clumps: %d bodies, %d real interactions at iteration %d"
    % (len(O.bodies), O.interactions.countReal(), O.iter)
)

O.reset()  # a law demsplit does not analyse (ViscElCap), for `demsplit info`
vec = O.materials.append(ViscElCapMat(kn=1e4, ks=5e3, cn=0, cs=0, density=2500, frictionAngle=0.4, Capillar=False))
O.bodies.append(
    [
        utils.sphere((0, 0, 0.0095), 0.01, material=vec),
        utils.sphere((0, 0, 0.029), 0.01, material=vec),
        utils.wall(0, axis=2, sense=1, material=vec),
    ]
)
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
    InteractionLoop(
        [Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
        [Ip2_ViscElCapMat_ViscElCapMat_ViscElCapPhys()],
        [Law2_ScGeom_ViscElCapPhys_Basic()],
    ),
    NewtonIntegrator(gravity=(0, 0, -9.81)),
]
O.dt = 1e-6
O.run(20, True)
save("viscelcap-000020.yade.gz")
print(
    "simulations viscelcap: %d bodies, %d real interactions at iteration %d"
    % (len(O.bodies), O.interactions.countReal(), O.iter)
)
