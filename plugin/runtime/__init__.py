"""How the process runs, apart from what it computes.

Nothing here knows a file format, a table or a contact law:

``command``
    the ``demsplit`` command's own process settings (imported first by the package, applied only when the
    process is the command, never in a program that imports demsplit);
``threads``
    the process's one pool of worker threads for work that releases the GIL, and ``map_ranges``;
``jit``
    the numba decorators and the few LLVM intrinsics the dump parser uses;
``prefault``
    the first frame's memory mapped on idle cores while a run opens;
``writeback``
    a file's pages sent to disk on idle cores while it grows;
``hashing``
    input files hashed (BLAKE3) on idle cores, with a hand-over to whoever needs a digest first.

Why each exists and what it gains: docs/performance.md, "Standing decisions".
"""
