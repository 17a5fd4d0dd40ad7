#!/bin/sh
# Regenerate every LAMMPS sample from its input script with Debian's lmp
# (LAMMPS 29 Sep 2021 - Update 2). Run from anywhere: sh sample_dumps/lammps/regenerate.sh
# Each run takes a few seconds on one core.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
for folder in hertz_mindlin dmt jkr hooke_region periodic legacy; do
    cd "$here/$folder"
    rm -f ./*.txt ./*.txt.gz
    for script in in.*; do
        if ! lmp -in "$script" -log none -echo none > lmp.out 2>&1; then
            tail -20 lmp.out; exit 1
        fi
    done
    rm lmp.out
    # -n: no name or time stamp, so that the bytes are reproducible
    gzip -n -9 ./*.txt
done
