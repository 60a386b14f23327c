"""What is built on the solver: the paper's verification (``verify``, ``verify_report``), design comparison
(``design``, ``design_report``), workspace volume (``workspace``), statics (``statics``), benchmarks (``bench``), peer
solvers (``peers``) and figures (``plot``)."""
