# YADE's own JCFpm example, examples/jointedCohesiveFrictionalPM/gravityBis.py as Debian installs it (a rock
# cube cut by a smooth joint, loaded by gravity, the joint's cohesion removed once the block is still), run
# as it is but trimmed to run fast: DEMSPLIT_SPHERES spheres instead of 3000, DEMSPLIT_ITER iterations
# instead of 10000, a seeded packing (DEMSPLIT_SEED) instead of a random one, no GUI, and the indicator
# sphere the example looks for taken as the highest sphere when a small packing has none where the example
# expects it. The state is then saved the usual way (O.save after O.run), with YADE's own numbers of that
# instant beside it (<state>.json, as saved_instants.py writes them). Run headless
# (tests/test_yade_instants.py):
#   DEMSPLIT_OUT=<dir> yade -n -j1 -x jcfpm_example.py
import json
import os
import re

EXAMPLE = "/usr/share/doc/yade/examples/jointedCohesiveFrictionalPM/"
out = os.environ.get("DEMSPLIT_OUT", ".")
source = open(EXAMPLE + "gravityBis.py").read()
trims = [
    ("nSpheres = 3000.0", "nSpheres = float(os.environ.get('DEMSPLIT_SPHERES', '500'))"),
    (
        "memoizeDb='/tmp/gts-triax-packings.sqlite', returnSpherePack=True)",
        "returnSpherePack=True, seed=int(os.environ.get('DEMSPLIT_SEED', '4')))",
    ),
    ("O.saveTmp()", ""),
    (
        "if refPoint:",
        "if refPoint is None:\n\trefPoint = max((b for b in O.bodies if isinstance(b.shape, Sphere)),"
        " key=lambda b: b.state.pos[2]).id\nif refPoint:",
    ),
    ("O.run(10000)", "O.run(int(os.environ.get('DEMSPLIT_ITER', '1500')), True)"),
    ("plot.plot()", ""),
]
for old, new in trims:
    assert old in source, old
    source = source.replace(old, new)
source = re.sub(r"^yade\.qt\..*$", "", source, flags=re.M)


def execfile(name):  # the example runs identifBis.py from its own directory
    exec(open(EXAMPLE + name).read(), globals())


exec(source.replace("from past.builtins import execfile", ""), globals())

sums = {"u_n": 0.0, "u_t": 0.0}
deep = 0
for i in O.interactions:
    p = i.phys
    sums["u_n"] += 0.5 * p.normalForce.squaredNorm() / p.kn if p.kn > 0 else 0.0
    sums["u_t"] += 0.5 * p.shearForce.squaredNorm() / p.ks if p.ks > 0 else 0.0
    deep += i.geom.penetrationDepth > min(i.geom.refR1, i.geom.refR2) and i.phys.isOnJoint
name = os.path.join(out, "jcfpm_example.yade.gz")
with open(name + ".json", "w") as f:
    json.dump(
        {
            "scene": "jcfpm_example",
            "tag": "run",
            "iter": O.iter,
            "time": O.time,
            "dt": O.dt,
            "count_real": O.interactions.countReal(),
            "law_energies": {},
            "sums": sums,
            "energy": {k: float(v) for k, v in O.energy.items()},
            "joint_deeper_than_a_radius": deep,
            "on_joint": sum(1 for i in O.interactions if i.phys.isOnJoint),
        },
        f,
        indent=1,
    )
O.save(name)
print(
    "jcfpm_example: %d bodies, %d real interactions (%d on the joint, %d of them deeper than a radius) at "
    "iteration %d"
    % (len(O.bodies), O.interactions.countReal(), sum(1 for i in O.interactions if i.phys.isOnJoint), deep, O.iter)
)
