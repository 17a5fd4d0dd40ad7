"""Store size, assembly (close) and read time per HDF5 compression filter.

Synthetic frames from tests/result_frames.py: 20 frames x (20 000 particles,
52 000 contacts, 2 walls); energies, overlaps and points are random floats, so
the floating-point columns barely compress (a worst case for the filters).

Run: python benchmarks/store_compression.py
"""
import os
import shutil
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from result_frames import PROVENANCE, WALLS_META, synthetic_frame  # noqa: E402

import demsplit.store as S  # noqa: E402

frames = [synthetic_frame(s, n_particles=20000, n_pairs=50000, n_wall_contacts=2000) for s in range(0, 20000, 1000)]
for comp, level in [("gzip", 1), ("gzip", 4), ("gzip", 6), ("lzf", None), (None, None)]:
    S.COMPRESSION_OPTS["gzip"] = level
    d = tempfile.mkdtemp()
    p = os.path.join(d, "out.h5")
    w = S.ResultWriter(p, PROVENANCE, walls_meta=WALLS_META, compression=comp)
    for f in frames:
        w.append(f)
    t1 = time.perf_counter()
    w.close()
    t2 = time.perf_counter()
    S.read_store(p)
    t3 = time.perf_counter()
    print(f"{comp}{level or ''}: {os.path.getsize(p) / 2**20:6.1f} MiB, close {t2 - t1:5.2f} s, read {t3 - t2:5.2f} s")
    shutil.rmtree(d)
