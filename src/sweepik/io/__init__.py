"""Reading and writing: robot files (TOML, ``robot_file``) and the bundled robots (``robots/``), URDF (``urdf``), and
the on-disk solution store (``store``)."""
