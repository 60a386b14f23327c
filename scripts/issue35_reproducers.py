"""The configurations issue 35 lists (points 4 and 5), each solved twice: the warm time, the solutions and families,
whether the configuration comes back (``tests/singular.recovered``) and how many of the families' members (9 along
each) miss the pose by more than 1e-9 of the arm's size.

    python scripts/issue35_reproducers.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from singular import recovered  # noqa: E402

import sweepik  # noqa: E402
from sweepik.model.pose import pose_error_geodesic  # noqa: E402
from sweepik.model.units import orientation_weight  # noqa: E402

PI = np.pi
#: (arm, configuration, limits, locked joints)
CASES = [
    ("ur5", [0.86056, 5.46006, -2.88415, -3.03775, PI, 2.59342], False, None),
    ("kuka_iiwa14", [-0.9736838840790869, 1.299252090037636, 0, 0, -2.3882056011399437, 0, 2.6599278402617434], False,
     {2: 0.0}),
    ("kuka_kr6_r900", [-0.449947703404042, -0.6365112470698561, -2.038806599570209, -1.6754080220239238, 0.0,
                       -2.6548778051440474], True, None),
    ("abb_irb140", [-2.633936123427877, -1.1638693734790628, 0.3487714784042786, -2.47670646646433, 0.0,
                    -3.027679808844194], False, None),
    ("kuka_kr6_r900", [-0.7869117403395842, -2.411759344263184, -3.0584514217013523, PI, 1.1669765685068096,
                       0.7964699331412812], False, None),
    ("puma560", [2.3568597051599407, 0.6302471995232901, 1.6177742441429797, 2.3660966733039746, 0.0,
                 -0.6885664195971763], True, None),
    ("carm", [1342.3161008277336, PI, 0.0, -1.5707963257948965, -1.6798806157027852, -0.9186248018997638], False,
     None),
    ("ur5", [2.2042858345559706, -0.9782962654771837, -0.9648341437830452, -2.7538323619714946, PI,
             -2.660267771237715], True, None),
]  # fmt: skip


def main() -> None:
    for name, q, limits, locked in CASES:
        robot = sweepik.load_robot(name)
        q_ = np.array(q)
        T = robot.fk(q_)
        kw = {"limits": limits} if locked is None else {"limits": limits, "locked": locked}
        sweepik.solve(robot, T, **kw)
        t0 = time.perf_counter()
        s = sweepik.solve(robot, T, **kw)
        dt = time.perf_counter() - t0
        w = orientation_weight(robot.length_unit)
        bad = 0
        for f in s.families:
            m = f.at(np.linspace(f.interval[0], f.interval[1], 9))
            err = pose_error_geodesic(robot.fk(m), np.broadcast_to(T, (len(m), 4, 4)), w)
            bad += int((err > 1e-9 * robot.length_scale).sum())
        print(
            f"{name:14s} limits={limits!s:5s} warm {dt:7.3f} s  solutions {len(s)}  families {len(s.families)}  "
            f"bad members {bad}  recovered {recovered(robot, s, q_)}",
            flush=True,
        )


if __name__ == "__main__":
    main()
