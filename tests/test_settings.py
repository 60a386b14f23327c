"""The engine's tolerances (:mod:`sweepik.engine.settings`): every one documented where it is set, and the orderings
the engine's steps rely on (a candidate's path from search to answer crosses them in turn)."""

from __future__ import annotations

import re
from pathlib import Path

import sweepik.engine.settings as S

SOURCE = Path(S.__file__).read_text()


def test_every_setting_is_documented_where_it_is_set() -> None:
    """Each module-level constant has a ``#:`` comment above it, or above the group of constants it opens."""
    lines = SOURCE.splitlines()
    constant = re.compile(r"^([A-Z][A-Z0-9_]*) = ")
    undocumented = []
    for i, line in enumerate(lines):
        m = constant.match(line)
        if not m:
            continue
        j = i - 1
        while j >= 0 and constant.match(lines[j]):
            j -= 1
        if not lines[j].startswith("#"):
            undocumented.append(m.group(1))
    assert not undocumented


def test_the_polish_band_lies_between_rounding_and_a_miss() -> None:
    """A candidate at rounding level is accepted without a polish; one the polish could certify lies above the
    acceptance tolerance and below the polish's reach; a multiple root's reach is wider than a simple one's."""
    assert S.MEET_ROUNDING_REL <= S.POLISH_ABOVE_REL < S.ACCEPT_TOL_REL
    assert S.POLISH_ABOVE_REL <= S.POLISH_PAPER_ABOVE_REL
    assert S.ACCEPT_TOL_REL < S.POLISH_BELOW_REL < S.POLISH_MULTIPLE_REL < 1e-2


def test_close_solutions_are_compared_from_duplicates_outwards() -> None:
    """Duplicates (equal to rounding) lie well inside the reach at which two solutions may be one root, whose
    nearer part asks the stricter test; the arc's points lie strictly between the pair; the partners' probes end at
    that reach."""
    assert S.DEDUPE_ANGLE < S.MEET_NEAR < S.MEET_REL <= 1e-3
    assert 0.0 < S.MEET_STAY < 0.5 and S.MEET_PASSES >= 1
    assert all(0.0 < t < 1.0 for t in S.MEET_ARC) and list(S.MEET_ARC) == sorted(S.MEET_ARC)
    assert list(S.PARTNER_STEPS) == sorted(S.PARTNER_STEPS) and max(S.PARTNER_STEPS) <= S.MEET_REL
