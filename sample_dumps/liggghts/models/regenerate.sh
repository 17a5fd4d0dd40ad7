#!/bin/sh
# Rerun every per-model sample with Debian's liggghts (3.8.0) into ./runs/ (not committed: about
# 1 MB per model; tests/test_liggghts_laws_vs_liggghts.py makes the same runs in a temporary directory).
set -eu
here=$(cd "$(dirname "$0")" && pwd)
python3 "$here/make_run.py" "$here/runs" "$@"
