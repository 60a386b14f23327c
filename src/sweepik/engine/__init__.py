"""The solving engine: the compiled sweep search (``search``), certification by forward kinematics (``certify``),
one pose in one compiled call (``one_pose``), the Newton polish (``polish``), deduplication and multiplicity
(``dedupe``), self-motion families (``families``, ``continuation``, ``crossings``, ``rough_continua``), close roots at
folds (``partners``), thread parallelism (``parallel``), a reduction without a compiled kernel called back from the
search (``callback``). It runs the pieces a reduction (``sweepik.reductions``) supplies; the NumPy references the
tests hold it against live in ``tests/oracles``."""
