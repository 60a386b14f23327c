"""The arm as data: robots and joints (``robot``), the chain of axes and points with its forward kinematics and
Jacobian (``chain``, ``kinematics``), the structure of its axes (``structure``), poses and their errors (``pose``),
length units (``units``), the origin + axis form and held (locked) joints (``origin_axis``), and the checks of
user input (``validate``). Imports nothing of sweepik above it."""
