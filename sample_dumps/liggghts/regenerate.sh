#!/bin/sh
# Regenerate every LIGGGHTS sample from its input script with Debian's liggghts
# (LIGGGHTS-PUBLIC 3.8.0). Run from anywhere: sh sample_dumps/liggghts/regenerate.sh
# Each run takes well under a minute on one core.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
for scene in packing periodic analytic gate; do
    cd "$here/$scene"
    rm -f ./*.txt ./*.txt.gz ./*.bin
    # stdbuf: LIGGGHTS loses error->one messages when stdout is a pipe.
    if ! stdbuf -o0 -e0 liggghts -in "in.$scene" -echo none -log none > liggghts.out 2>&1; then
        tail -20 liggghts.out; exit 1
    fi
    rm liggghts.out
    # The big full-precision dumps of packing/ and periodic/, and every dump of gate/, are stored
    # gzip-compressed (-n: no name/time stamp, so the bytes are reproducible); analytic/ stays plain text.
    case "$scene" in
        analytic) ;;
        gate) gzip -n -9 -f ./*.txt ;;
        *) gzip -n -9 -f ./*_full.txt ;;
    esac
done
# The wall-force scenes (walls/, see walls/make_scenes.py): each model with a primitive and with a mesh floor.
python3 "$here/walls/make_scenes.py" "$here/walls" > /dev/null
gzip -n -9 -f "$here"/walls/*/ds_*.txt
