#!/bin/sh
# Regenerate the YADE sample files of demsplit (run from anywhere):
#   sh sample_dumps/yade/regenerate.sh
# Needs Debian's yade (2023.02a) and demsplit installed in the dev Python
# (`python`); DEMSPLIT_SITE tells the YADE scripts where to find it.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
DEMSPLIT_SITE=$(python -c "import sysconfig; print(sysconfig.get_paths()['purelib'])")
export DEMSPLIT_SITE
export DEMSPLIT_OUT="$here"
cd "$here"
rm -f ./*.h5 ./*.npys ./*.vtk ./*.txt
for scene in mindlin_box cundall_periodic; do
    yade -n -j1 -x "$scene.py" 2>&1 | grep "^$scene:" | tee "$scene.log"
done
for law in viscel viscofrict hertz_linear deresiewitz cohfrict jcfpm adhesion capillary; do
    DEMSPLIT_LAW=$law yade -n -j1 -x laws_box.py 2>&1 | grep "^laws_box_$law:" | tee "laws_box_$law.log"
done
# saved states and YADE's own JCFpm example: their states are made by the tests (tests/test_yade_instants.py),
# not kept; the logs record YADE's counts
states=$(mktemp -d)
for script in saved_instants jcfpm_example; do
    DEMSPLIT_OUT="$states" yade -n -j1 -x "$script.py" 2>&1 | grep "^$script" | tee "$script.log"
done
rm -r "$states"
