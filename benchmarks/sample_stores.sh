#!/usr/bin/env bash
# Write the result store of every sample run (LIGGGHTS packing, periodic, analytic; the full-precision and
# the paper-rule variants of packing; both YADE scenes in both snapshot formats) into OUTDIR, with the
# given demsplit command. Run it with the code before and after a change, from the repository root, then
# compare the two directories with benchmarks/compare_stores.py:
#   bash benchmarks/sample_stores.sh "python -m demsplit.cli" /tmp/before
set -u
D=$1
O=$2
mkdir -p "$O"
for s in packing periodic analytic; do
    $D run "sample_dumps/liggghts/$s/in.$s" -o "$O/$s.h5" -q || echo "FAIL $s"
done
for y in cundall_periodic mindlin_box; do
    for ext in h5 npys; do
        $D run "sample_dumps/yade/$y.$ext" -o "$O/${y}_$ext.h5" -q || echo "FAIL $y $ext"
    done
done
P=sample_dumps/liggghts/packing
$D run $P/in.packing --atoms $P/atoms_full.txt.gz --contacts $P/pairs_full.txt.gz --walls $P/wall_full.txt.gz \
    -o "$O/packing_full.h5" -q || echo "FAIL packing_full"
$D run $P/in.packing --tangential-rule paper -o "$O/packing_paper.h5" -q || echo "FAIL packing_paper"
