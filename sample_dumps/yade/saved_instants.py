# Scenes in motion, one per YADE contact law of demsplit (and a periodic cell, clumps, walls, facets, a box
# and inline materials), each saving its state with O.save the ways users do: after O.run(N, True), and from
# a PyRunner before the InteractionLoop, between it and the NewtonIntegrator, and at the end of O.engines.
# The script never imports demsplit. Beside every state it writes <state>.json with YADE's own numbers of
# that instant, computed by YADE at the moment of the save: the law's energy functions, O.energy, sums over
# the real interactions' i.phys and i.geom (the energy of each mode as the law defines it) and
# O.interactions.countReal(), the spheres' positions at the InteractionLoop that computed the saved forces
# (the instant YADE's energy functions report), and how much the scene moves (the real interactions made in
# the last 100 iterations, the largest speed). Run headless (tests/test_yade_instants.py):
#   DEMSPLIT_OUT=<dir> [DEMSPLIT_SCENES=mindlin,cundall,...] yade -n -j1 -x saved_instants.py
import json
import math
import os
import random

from yade import geom, pack, utils

out = os.environ.get("DEMSPLIT_OUT", ".")
START = int(os.environ.get("DEMSPLIT_START", "1800"))
"""Iterations before the first save: the spheres are falling and colliding, contacts form and break
(the clumps, which bounce longer, get 900 more)."""


def law_energies(kind):
    """The law functor's own energy functions that exist for this law (J)."""
    names = {
        "mindlin": ("normElastEnergy",),
        "adhesion": ("normElastEnergy",),
        "cundall": ("elasticEnergy",),
        "viscofrict": ("elasticEnergy",),
        "cohfrict": ("normElastEnergy", "shearElastEnergy", "bendingElastEnergy", "twistElastEnergy"),
    }
    return {n: float(getattr(law, n)()) for n in names.get(kind, ())}


def sq(v):
    return float(v.squaredNorm())


def spring(force2, k):
    return 0.5 * force2 / k if k > 0 else 0.0


def phys_sums(kind):
    """Energy of each mode as the law defines it, summed over the real interactions (J)."""
    u = {"u_n": 0.0, "u_t": 0.0}
    if kind == "cohfrict":
        u.update(u_r=0.0, u_tw=0.0)
    if kind == "adhesion":
        u["u_adh"] = 0.0
    for i in O.interactions:
        g, p = i.geom, i.phys
        d = float(g.penetrationDepth)
        if kind in ("mindlin", "adhesion", "hertz_linear", "deresiewitz"):
            u["u_n"] += 0.4 * float(p.kno) * max(d, 0.0) ** 2.5
            if kind == "hertz_linear":  # nonLin=1: the law's shear stiffness is kso sqrt(delta), not stored
                u["u_t"] += spring(sq(p.shearForce), float(p.kso) * math.sqrt(max(d, 0.0)))
            elif kind != "deresiewitz":
                u["u_t"] += spring(sq(p.shearElastic), float(p.ks))
            if kind == "adhesion":
                u["u_adh"] -= float(p.adhesionForce) * d
        elif kind == "viscel":
            u["u_n"] += 0.5 * float(p.kn) * d * d
            u["u_t"] += spring(sq(p.shearForce), float(p.ks))
        else:  # springs whose forces YADE stores: CundallStrack, ViscoFrict, CohFrict, JCFpm
            u["u_n"] += spring(sq(p.normalForce), float(p.kn))
            u["u_t"] += spring(sq(p.shearForce), float(p.ks))
            if kind == "cohfrict":
                u["u_r"] += spring(sq(p.moment_bending), float(p.kr))
                u["u_tw"] += spring(sq(p.moment_twist), float(p.ktw))
    if kind == "deresiewitz":
        del u["u_t"]
    return u


held = {}
"""Sphere id -> position (wrapped into a periodic cell) at the InteractionLoop of the iterations around the
saves, by iteration."""


def hold():
    if start <= O.iter <= start + 4:
        held[O.iter] = {
            b.id: list(O.cell.wrap(b.state.pos) if O.periodic else b.state.pos)
            for b in O.bodies
            if isinstance(b.shape, Sphere)
        }


def save(tag):
    name = os.path.join(out, "%s-%s.%s" % (scene, tag, "xml.bz2" if tag == "between" else "yade.gz"))
    forces_at = O.iter - 1 if tag in ("before", "run") else O.iter  # the iteration whose InteractionLoop ran last
    ref = {
        "scene": scene,
        "tag": tag,
        "iter": O.iter,
        "time": O.time,
        "dt": O.dt,
        "count_real": O.interactions.countReal(),
        "law_energies": law_energies(kind),
        "energy": {k: float(v) for k, v in O.energy.items()},
        "sums": phys_sums(kind),
        "positions": held[forces_at],
        "made_in_last_100": sum(1 for i in O.interactions if i.iterMadeReal > O.iter - 100),
        "max_speed": max(b.state.vel.norm() for b in O.bodies if isinstance(b.shape, Sphere)),
    }
    with open(name + ".json", "w") as f:
        json.dump(ref, f, indent=1)
    O.save(name)


def save_at(tag, when):
    if O.iter == when:
        save(tag)


def two(cls, **kw):
    """Two materials in O.materials: soft and stiff."""
    soft = O.materials.append(cls(young=2e7, poisson=0.3, density=2500, frictionAngle=0.4, label="soft", **kw))
    stiff = O.materials.append(cls(young=1e8, poisson=0.2, density=2500, frictionAngle=0.4, label="stiff", **kw))
    return soft, stiff


def cloud(lo, hi, soft, stiff, seed, r=0.003, speed=0.2):
    """Spheres of both materials in a loose hexagonal packing, radii 0.9-0.99 r (gaps at the
    start), with random velocities."""
    rnd = random.Random(seed)
    for k, b in enumerate(pack.regularHexa(pack.inAlignedBox(lo, hi), radius=r, gap=0)):
        s = utils.sphere(b.state.pos, r * rnd.uniform(0.9, 0.99), material=soft if k % 2 else stiff)
        s.state.vel = Vector3(*(rnd.uniform(-speed, speed) for _ in range(3)))
        O.bodies.append(s)


def engines(shapes, ip2, law2, newton):
    bo1 = {
        "Sphere": Bo1_Sphere_Aabb(aabbEnlargeFactor=bonds),
        "Facet": Bo1_Facet_Aabb(),
        "Wall": Bo1_Wall_Aabb(),
        "Box": Bo1_Box_Aabb(),
    }
    six = kind == "cohfrict"
    ig2 = {
        "Sphere": Ig2_Sphere_Sphere_ScGeom6D() if six else Ig2_Sphere_Sphere_ScGeom(interactionDetectionFactor=bonds),
        "Facet": Ig2_Facet_Sphere_ScGeom6D() if six else Ig2_Facet_Sphere_ScGeom(),
        "Wall": Ig2_Wall_Sphere_ScGeom(),
        "Box": Ig2_Box_Sphere_ScGeom(),
    }
    at = {"before": start + 1, "between": start + 2, "end": start + 3}  # where the PyRunner sits: when it saves
    O.engines = [
        ForceResetter(),
        InsertionSortCollider([bo1[s] for s in shapes]),
        PyRunner(command="save_at('before', %d)" % at["before"], iterPeriod=1),
        InteractionLoop([ig2[s] for s in shapes], [ip2], [law2]),
        PyRunner(command="hold()", iterPeriod=1),
        PyRunner(command="save_at('between', %d)" % at["between"], iterPeriod=1),
        newton,
        PyRunner(command="save_at('end', %d)" % at["end"], iterPeriod=1),
    ]


def box_scene(seed, mat=FrictMat, **kw):
    soft, stiff = two(mat, **kw)
    L = 0.03
    cloud((0.001, 0.001, 0.001), (L - 0.001, L - 0.001, 0.03), soft, stiff, seed)
    O.bodies.append(geom.facetBox((L / 2, L / 2, 0.03), (L / 2, L / 2, 0.03), wallMask=31, material=stiff))
    return soft, stiff


def build():
    """The scene named by the global ``scene``; sets ``kind`` (the law, for the sums), ``law`` (the Law2 functor)."""
    global kind, law, bonds
    kind, bonds = {"periodic": "mindlin", "clumps": "mindlin"}.get(scene, scene), 1.0
    newton = NewtonIntegrator(gravity=(0, 0, -200.0), damping=0.3)
    if scene == "mindlin":  # damped Hertz-Mindlin; facets and a box with inline materials
        soft, stiff = two(FrictMat)
        L = 0.03
        cloud((0.001, 0.001, 0.007), (L - 0.001, L - 0.001, 0.03), soft, stiff, 1)
        O.bodies.append(
            geom.facetBox(
                (L / 2, L / 2, 0.03),
                (L / 2, L / 2, 0.03),
                wallMask=31,
                material=FrictMat(young=1e9, poisson=0.3, density=2500, frictionAngle=0.4),
            )
        )
        O.bodies.append(
            utils.box(
                (L / 2, L / 2, 0.003),
                (0.006, 0.006, 0.003),
                fixed=True,
                material=FrictMat(young=5e8, poisson=0.25, density=2500, frictionAngle=0.4),
            )
        )
        law = Law2_ScGeom_MindlinPhys_Mindlin()
        engines(("Sphere", "Facet", "Box"), Ip2_FrictMat_FrictMat_MindlinPhys(en=0.6, es=0.6), law, newton)
    elif scene == "cundall":  # CundallStrack between Walls, O.energy tracked
        soft, stiff = two(FrictMat)
        L = 0.03
        cloud((0.001, 0.001, 0.001), (L - 0.001, L - 0.001, 0.03), soft, stiff, 2)
        O.bodies.append(
            [
                utils.wall(0, axis=2, sense=1, material=stiff),
                utils.wall(0, axis=0, sense=1, material=soft),
                utils.wall(L, axis=0, sense=-1, material=soft),
                utils.wall(0, axis=1, sense=1, material=stiff),
                utils.wall(L, axis=1, sense=-1, material=stiff),
            ]
        )
        O.trackEnergy = True
        law = Law2_ScGeom_FrictPhys_CundallStrack()
        engines(("Sphere", "Wall"), Ip2_FrictMat_FrictMat_FrictPhys(), law, newton)
    elif scene == "periodic":  # Hertz-Mindlin in a periodic cell under compression
        soft, stiff = two(FrictMat)
        O.periodic = True
        O.cell.setBox(0.03, 0.03, 0.03)
        sp = pack.SpherePack()
        sp.makeCloud((0, 0, 0), (0.03, 0.03, 0.03), rMean=0.002, rRelFuzz=0.25, periodic=True, seed=3, num=250)
        rnd = random.Random(3)
        for k, (c, r) in enumerate(sp):
            b = utils.sphere(c, r, material=soft if k % 2 else stiff)
            b.state.vel = Vector3(*(rnd.uniform(-0.5, 0.5) for _ in range(3)))
            O.bodies.append(b)
        O.cell.velGrad = Matrix3(-15, 2, 0, 0, -15, 0, 0, 0, -15)
        law = Law2_ScGeom_MindlinPhys_Mindlin()
        engines(("Sphere",), Ip2_FrictMat_FrictMat_MindlinPhys(), law, NewtonIntegrator(damping=0.1))
    elif scene == "clumps":  # rotating clumps and spheres on Walls of two inline materials
        soft, stiff = two(FrictMat)
        L = 0.04
        O.bodies.append(
            [
                utils.wall(0, axis=2, sense=1, material=FrictMat(young=3e8, poisson=0.3, density=2500)),
                utils.wall(0, axis=0, sense=1, material=FrictMat(young=6e8, poisson=0.2, density=2500)),
                utils.wall(L, axis=0, sense=-1, material=stiff),
                utils.wall(0, axis=1, sense=1, material=stiff),
                utils.wall(L, axis=1, sense=-1, material=soft),
            ]
        )
        rnd = random.Random(4)
        for k in range(27):  # three layers of 3 x 3 clumps
            c = Vector3(0.007 + 0.013 * (k % 3), 0.007 + 0.013 * (k // 3 % 3), 0.008 + 0.013 * (k // 9))
            a = Vector3(rnd.uniform(-1, 1), rnd.uniform(-1, 1), rnd.uniform(-1, 1)).normalized() * 0.003
            cid, members = O.bodies.appendClumped(
                [utils.sphere(c - a, 0.0035, material=soft), utils.sphere(c + a, 0.0025, material=stiff)]
            )
            O.bodies[cid].state.vel = Vector3(rnd.uniform(-0.5, 0.5), rnd.uniform(-0.5, 0.5), -1.5)
            O.bodies[cid].state.angVel = Vector3(rnd.uniform(-50, 50), rnd.uniform(-50, 50), rnd.uniform(-50, 50))
        cloud((0.001, 0.001, 0.046), (L - 0.001, L - 0.001, 0.052), soft, stiff, 4, speed=1.5)
        law = Law2_ScGeom_MindlinPhys_Mindlin()
        engines(("Sphere", "Wall"), Ip2_FrictMat_FrictMat_MindlinPhys(), law, newton)
    elif scene == "viscel":
        box_scene(5, ViscElMat, kn=2e4, ks=1e4, cn=0.5, cs=0.2)
        law = Law2_ScGeom_ViscElPhys_Basic()
        engines(("Sphere", "Facet"), Ip2_ViscElMat_ViscElMat_ViscElPhys(), law, newton)
    elif scene == "viscofrict":
        box_scene(6)
        law = Law2_ScGeom_ViscoFrictPhys_CundallStrack(shearCreep=True, viscosity=1e3)
        engines(("Sphere", "Facet"), Ip2_FrictMat_FrictMat_ViscoFrictPhys(), law, newton)
    elif scene == "hertz_linear":
        box_scene(7)
        law = Law2_ScGeom_MindlinPhys_HertzWithLinearShear(nonLin=1)  # ks = kso sqrt(delta)
        engines(("Sphere", "Facet"), Ip2_FrictMat_FrictMat_MindlinPhys(), law, newton)
    elif scene == "deresiewitz":
        box_scene(8)
        law = Law2_ScGeom_MindlinPhys_MindlinDeresiewitz()
        engines(("Sphere", "Facet"), Ip2_FrictMat_FrictMat_MindlinPhys(), law, newton)
    elif scene == "adhesion":
        box_scene(9)
        law = Law2_ScGeom_MindlinPhys_Mindlin(includeAdhesion=True)
        engines(("Sphere", "Facet"), Ip2_FrictMat_FrictMat_MindlinPhys(gamma=0.5), law, newton)
    elif scene == "cohfrict":
        box_scene(
            10,
            CohFrictMat,
            isCohesive=True,
            normalCohesion=1e5,
            shearCohesion=1e5,
            momentRotationLaw=True,
            alphaKr=2.0,
            alphaKtw=1.0,
        )
        law = Law2_ScGeom6D_CohFrictPhys_CohesionMoment(useIncrementalForm=True, always_use_moment_law=True)
        engines(
            ("Sphere", "Facet"), Ip2_CohFrictMat_CohFrictMat_CohFrictPhys(setCohesionOnNewContacts=True), law, newton
        )
    elif scene == "jcfpm":  # bonds made within 1.2 x the contact distance at the first iteration
        bonds = 1.2
        box_scene(11, JCFpmMat, tensileStrength=1e4, cohesion=1e4)
        law = Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM()
        engines(("Sphere", "Facet"), Ip2_JCFpmMat_JCFpmMat_JCFpmPhys(cohesiveTresholdIteration=1), law, newton)
    else:
        raise SystemExit("unknown scene %r" % scene)


ALL = (
    "mindlin",
    "cundall",
    "periodic",
    "clumps",
    "viscel",
    "viscofrict",
    "hertz_linear",
    "deresiewitz",
    "adhesion",
    "cohfrict",
    "jcfpm",
)
for scene in [s for s in os.environ.get("DEMSPLIT_SCENES", ",".join(ALL)).split(",") if s]:
    O.reset()
    held.clear()
    start = START + (900 if scene == "clumps" else 0)
    build()
    O.dt = 0.5 * utils.PWaveTimeStep()
    O.run(start + 3, True)  # through the PyRunner saves
    O.run(2, True)
    save("run")  # after O.run(N, True)
    print(
        "saved_instants %s: %d bodies, %d real interactions at iteration %d"
        % (scene, len(O.bodies), O.interactions.countReal(), O.iter)
    )
