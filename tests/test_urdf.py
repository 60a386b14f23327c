"""URDF reader and writer: malformed and malicious files refused fast, FK against yourdfpy (an independent parser,
lxml-based) on example-robot-data's UR3/UR5/UR10 and Panda and on random hand-made chains, and writer -> reader
(and writer -> yourdfpy) round trips of every bundled robot."""

from __future__ import annotations

import dataclasses
import io
import math
import sysconfig
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import yourdfpy

import sweepik
from sweepik.errors import RobotDefinitionError, SweepikError, UnknownOptionError, UrdfError
from sweepik.io.urdf import (
    MAX_URDF_BYTES,
    MAX_URDF_DEPTH,
    MAX_URDF_JOINTS,
    MAX_URDF_TAGS,
    read_urdf,
    robot_from_urdf,
    urdf_text,
)
from sweepik.model.pose import pose_from_xyz_zyz
from sweepik.model.units import mm_per_unit

ROBOTS_DIR = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
UR_URDF = {name: ROBOTS_DIR / "ur_description" / "urdf" / f"{name}_robot.urdf" for name in ("ur3", "ur5", "ur10")}
PANDA_URDF = ROBOTS_DIR / "panda_description" / "urdf" / "panda.urdf"
#: Refusals must come at once: the slowest here (1001 joints, parsed up to the 1001st) takes about 0.02 s.
FAST_S = 1.0
#: FK agreement with yourdfpy (metres; rotation entries): both compose the same float64 transforms.
FK_TOL = 1e-12
SOURCE = "case.urdf"


# ---------------------------------------------------------------------------------------------- helpers


def _limit(lo: float = -2.0, hi: float = 2.0) -> str:
    return f'<limit lower="{lo}" upper="{hi}" effort="1" velocity="1"/>'


def _joint(name: str, parent: str, child: str, jtype: str = "revolute", inner: str | None = None) -> str:
    body = f'<origin xyz="0.1 0 0.2" rpy="0 0.3 0"/><axis xyz="0 0 1"/>{_limit()}' if inner is None else inner
    return f'<joint name="{name}" type="{jtype}"><parent link="{parent}"/><child link="{child}"/>{body}</joint>'


def _doc(*parts: str, links: tuple[str, ...] = ("a", "b", "c")) -> str:
    return '<robot name="t">' + "".join(f'<link name="{k}"/>' for k in links) + "".join(parts) + "</robot>"


def _two_joints(inner2: str | None = None, jtype2: str = "revolute") -> str:
    """Links a -> b -> c; the second joint's type and body can be replaced."""
    return _doc(_joint("j1", "a", "b"), _joint("j2", "b", "c", jtype2, inner2))


def _chain_text(n: int, joints_first: bool = False) -> str:
    links = [f'<link name="l{i}"/>' for i in range(n + 1)]
    joints = [_joint(f"j{i}", f"l{i - 1}", f"l{i}") for i in range(1, n + 1)]
    parts = joints + links if joints_first else [x for pair in zip(links[1:], joints, strict=True) for x in pair]
    return '<robot name="long">' + (links[0] if not joints_first else "") + "".join(parts) + "</robot>"


def _refused(call: Callable[[], object], match: str) -> str:
    """``call()`` raises UrdfError matching ``match``, within ``FAST_S``; the message is returned."""
    t0 = time.perf_counter()
    with pytest.raises(UrdfError, match=match) as info:
        call()
    elapsed = time.perf_counter() - t0
    assert elapsed < FAST_S, f"refusal took {elapsed:.3f} s"
    assert isinstance(info.value, SweepikError)
    return str(info.value)


BILLION_LAUGHS = (
    '<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY l0 "lol">'
    + "".join(f'<!ENTITY l{i} "{f"&l{i - 1};" * 10}">' for i in range(1, 10))
    + ']><robot name="&l9;"><link name="a"/></robot>'
)
EXTERNAL_ENTITY = (
    '<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY x SYSTEM "file:///etc/passwd">]>'
    '<robot name="&x;"><link name="a"/></robot>'
)

# (id, text, pattern the message must match, words it must name besides the file)
MALFORMED: list[tuple[str, str, str, tuple[str, ...]]] = [
    ("empty", "", "not well-formed XML", ()),
    ("not-xml", '<robot name="t"><link name="a"></robot>', "not well-formed XML", ()),
    ("not-robot", "<model><link name='a'/></model>", "root element must be <robot>", ("model",)),
    ("billion-laughs", BILLION_LAUGHS, "DOCTYPE.*refused", ()),
    ("external-entity", EXTERNAL_ENTITY, "DOCTYPE.*refused", ()),
    ("undefined-entity", '<robot name="&x;"><link name="a"/></robot>', "undefined entity", ()),
    ("no-links", '<robot name="t"/>', "no <link>", ()),
    ("missing-parent", _doc(_joint("j1", "zz", "b")), "missing parent link 'zz'", ("j1",)),
    ("missing-child", _doc(_joint("j1", "a", "zz")), "missing child link 'zz'", ("j1",)),
    ("no-parent-element", _doc(_joint("j1", "a", "b").replace('<parent link="a"/>', "")), "missing <parent", ("j1",)),
    ("two-parents", _doc(_joint("j1", "a", "c"), _joint("j2", "b", "c")), "two parent joints", ("'c'", "j1", "j2")),
    ("cycle", _doc(_joint("j1", "b", "c"), _joint("j2", "c", "b")), "form a cycle", ("j1", "j2")),
    ("self-loop", _doc(_joint("j1", "b", "b")), "form a cycle", ("j1",)),
    ("two-roots", _doc(_joint("j1", "a", "b")), "2 root links", ("'a'", "'c'")),
    ("duplicate-link", _doc(links=("a", "a")), "link 'a' is defined twice", ()),
    ("duplicate-joint", _doc(_joint("j", "a", "b"), _joint("j", "b", "c")), "joint 'j' is defined twice", ()),
    (
        "joint-without-name",
        _doc('<joint type="fixed"><parent link="a"/><child link="b"/></joint>'),
        "#1: missing attribute 'name'",
        (),
    ),
    ("unknown-type", _two_joints(jtype2="spherical"), "unknown joint type 'spherical'", ("j2", "continuous")),
    ("no-type", _doc('<joint name="j1"><parent link="a"/><child link="b"/></joint>'), "unknown joint type", ()),
    ("nan-xyz", _two_joints(f'<origin xyz="0 nan 0"/>{_limit()}'), "origin xyz", ("j2", "nan")),
    ("inf-rpy", _two_joints(f'<origin rpy="0 0 inf"/>{_limit()}'), "origin rpy", ("j2",)),
    ("overflow-xyz", _two_joints(f'<origin xyz="0 1e999 0"/>{_limit()}'), "finite", ("j2",)),
    ("text-xyz", _two_joints(f'<origin xyz="a b c"/>{_limit()}'), "origin xyz must be 3 numbers", ("j2",)),
    ("two-numbers", _two_joints(f'<origin xyz="1 2"/>{_limit()}'), "origin xyz must be 3 numbers", ("j2",)),
    ("underscore", _two_joints(f'<origin xyz="1_0 0 0"/>{_limit()}'), "origin xyz must be 3 numbers", ("j2",)),
    ("nan-axis", _two_joints(f'<axis xyz="1 nan 0"/>{_limit()}'), "axis xyz", ("j2",)),
    ("zero-axis", _two_joints(f'<axis xyz="0 0 0"/>{_limit()}'), "axis xyz is zero", ("j2",)),
    ("nan-limit", _two_joints('<limit lower="nan" upper="1" effort="1" velocity="1"/>'), "limit lower", ("j2",)),
    ("text-limit", _two_joints('<limit lower="-1" upper="big" effort="1" velocity="1"/>'), "limit upper", ("j2",)),
    ("lower-above-upper", _two_joints(_limit(1.0, -1.0)), "lower 1 is above upper -1", ("j2",)),
    ("revolute-without-limit", _two_joints('<axis xyz="0 0 1"/>'), "needs <limit", ("j2", "revolute")),
    ("prismatic-without-limit", _two_joints('<axis xyz="0 0 1"/>', "prismatic"), "needs <limit", ("j2",)),
    ("continuous-half-limit", _two_joints('<limit lower="-1"/>', "continuous"), "both lower and upper", ("j2",)),
    ("two-origins", _two_joints(f'<origin xyz="0 0 1"/><origin xyz="0 0 2"/>{_limit()}'), "two <origin>", ("j2",)),
    ("mimic-on-chain", _two_joints(f'<mimic joint="j1"/>{_limit()}'), "mimics another joint", ("j2",)),
    ("floating-on-chain", _two_joints("", "floating"), "is floating", ("j2",)),
    ("planar-on-chain", _two_joints('<axis xyz="0 0 1"/>', "planar"), "is planar", ("j2",)),
    ("only-fixed", _doc(_joint("j1", "a", "b", "fixed", ""), _joint("j2", "b", "c", "fixed", "")), "no moving", ()),
    ("too-deep", _doc("<g>" * (MAX_URDF_DEPTH + 5) + "</g>" * (MAX_URDF_DEPTH + 5)), "nested more than", ()),
    ("too-many-tags", _doc("<g/>" * (MAX_URDF_TAGS + 1)), "markup characters", ()),
    ("too-many-joints", _chain_text(MAX_URDF_JOINTS + 1, joints_first=True), "more than 1000 joints", ()),
    ("too-many-links", _doc(links=tuple(f"k{i}" for i in range(MAX_URDF_JOINTS + 2))), "more than 1001 links", ()),
]


@pytest.mark.parametrize(("text", "pattern", "names"), [c[1:] for c in MALFORMED], ids=[c[0] for c in MALFORMED])
def test_malformed_and_malicious_urdf_refused_fast(text: str, pattern: str, names: tuple[str, ...]) -> None:
    for doc in (text, text.encode("utf-8")):
        msg = _refused(lambda doc=doc: robot_from_urdf(doc, SOURCE), pattern)
        assert msg.startswith(SOURCE + ":")
        for word in names:
            assert word in msg


@pytest.mark.parametrize(
    ("kwargs", "pattern"),
    [
        ({"base_link": "nowhere"}, "base_link 'nowhere' is not a link"),
        ({"tip_link": "nowhere"}, "tip_link 'nowhere' is not a link"),
        ({"base_link": "c", "tip_link": "a"}, "tip_link 'a' is not below base_link 'c'"),
        ({"base_link": "b", "tip_link": "b"}, "no moving joint between 'b' and 'b'"),
        ({"tip_link": 3}, "tip_link must be a link name"),
    ],
)
def test_bad_base_or_tip(kwargs: dict[str, object], pattern: str) -> None:
    text = _two_joints()
    _refused(lambda: robot_from_urdf(text, SOURCE, **kwargs), pattern)  # type: ignore[arg-type]


def test_non_text_and_lone_surrogate_refused() -> None:
    _refused(lambda: robot_from_urdf(12, SOURCE), "must be str or bytes")  # type: ignore[arg-type]
    _refused(lambda: robot_from_urdf(_two_joints().replace('name="t"', 'name="\ud800"'), SOURCE), "surrogate")


def test_hundred_thousand_link_chain_refused_fast(tmp_path: Path) -> None:
    text = _chain_text(100_000)
    assert len(text) > MAX_URDF_BYTES
    _refused(lambda: robot_from_urdf(text, SOURCE), "more than the 4194304 bytes")
    path = tmp_path / "long.urdf"
    path.write_text(text)
    _refused(lambda: read_urdf(path), "larger than the 4194304 bytes")


def test_joint_bound_is_inclusive() -> None:
    """A chain of exactly MAX_URDF_JOINTS joints is read (in about 0.3 s), one more is refused (above)."""
    r = robot_from_urdf(_chain_text(MAX_URDF_JOINTS))
    assert r.n_joints == MAX_URDF_JOINTS
    assert np.isfinite(r.fk(np.zeros(MAX_URDF_JOINTS))).all()


def test_read_urdf_file_errors(tmp_path: Path) -> None:
    msg = _refused(lambda: read_urdf(tmp_path / "missing.urdf"), "no such file")
    assert "missing.urdf" in msg
    _refused(lambda: read_urdf(tmp_path), "is a directory")
    big = tmp_path / "big.urdf"
    with big.open("wb") as fh:  # sparse: refused by its size, never read
        fh.truncate(MAX_URDF_BYTES + 1)
    _refused(lambda: read_urdf(big), "larger than")
    _refused(lambda: read_urdf(3.5), "path must be a str")  # type: ignore[arg-type]
    bad = tmp_path / "bad.urdf"
    bad.write_text(EXTERNAL_ENTITY)
    assert str(bad) in _refused(lambda: read_urdf(bad), "DOCTYPE")


# ---------------------------------------------------------------------------------------------- against yourdfpy


def _yourdfpy(source: Path | str) -> yourdfpy.URDF:
    kwargs = {"load_meshes": False, "build_scene_graph": True, "build_collision_scene_graph": False}
    if isinstance(source, Path):
        return yourdfpy.URDF.load(str(source), **kwargs)
    return yourdfpy.URDF.load(io.BytesIO(source.encode("utf-8")), **kwargs)


def _yourdfpy_fk(model: yourdfpy.URDF, names: list[str], q: np.ndarray, base: str, tip: str) -> np.ndarray:
    out = []
    for row in q:
        model.update_cfg(dict(zip(names, row, strict=True)))
        out.append(model.get_transform(frame_to=tip, frame_from=base))
    return np.array(out)


def _in_limits(robot: sweepik.Robot, rng: np.random.Generator, n: int, cap: float = 2 * math.pi) -> np.ndarray:
    return rng.uniform(np.maximum(robot.lower, -cap), np.minimum(robot.upper, cap), (n, robot.n_joints))


def _check_against_yourdfpy(
    robot: sweepik.Robot, model: yourdfpy.URDF, base: str, tip: str, rng: np.random.Generator, n: int = 200
) -> None:
    q = _in_limits(robot, rng, n)
    expected = _yourdfpy_fk(model, robot.joint_names, q, base, tip)
    np.testing.assert_allclose(robot.fk(q), expected, rtol=0, atol=FK_TOL)


@pytest.mark.parametrize("name", sorted(UR_URDF))
def test_ur_urdf_fk_matches_yourdfpy(name: str, rng: np.random.Generator) -> None:
    path = UR_URDF[name]
    model = _yourdfpy(path)
    robot = read_urdf(path)  # default: base = the root ('world'), tip = the last moving joint's child
    assert robot.name == name and robot.length_unit == "m" and robot.dh_convention == "none"
    assert robot.joint_names == model.actuated_joint_names
    urdf_limits = [[model.joint_map[j].limit.lower, model.joint_map[j].limit.upper] for j in robot.joint_names]
    np.testing.assert_array_equal(robot.limits, urdf_limits)
    assert robot.base_is_identity
    _check_against_yourdfpy(robot, model, "world", "wrist_3_link", rng)
    # a fixed frame after the last moving joint, named as tip: it becomes the tool transform
    with_tool = read_urdf(path, base_link="base_link", tip_link="tool0")
    assert not with_tool.tool_is_identity
    _check_against_yourdfpy(with_tool, model, "base_link", "tool0", rng)


def test_ur_urdf_equals_ur_dh_table_up_to_the_base_turn(rng: np.random.Generator) -> None:
    """UR's URDF (base_link -> tool0) is UR's DH table turned by pi about z at the base; it agrees only to 2e-11
    because the URDF writes pi/2 as 1.57079632679."""
    dh = sweepik.load_robot("ur5")
    urdf = read_urdf(UR_URDF["ur5"], base_link="base_link", tip_link="tool0")
    q = rng.uniform(-math.pi, math.pi, (100, 6))
    turn = np.diag([-1.0, -1.0, 1.0, 1.0])
    np.testing.assert_allclose(urdf.fk(q), turn @ dh.fk(q), rtol=0, atol=1e-10)


@pytest.mark.parametrize("tip", ["panda_link8", "panda_hand", "panda_hand_tcp"])
def test_panda_urdf_fk_matches_yourdfpy(tip: str, rng: np.random.Generator) -> None:
    model = _yourdfpy(PANDA_URDF)
    robot = read_urdf(PANDA_URDF, tip_link=tip)  # the fingers (one a mimic joint) are off this chain: ignored
    assert robot.joint_names == [f"panda_joint{i}" for i in range(1, 8)]
    assert robot.limits[3].tolist() == [-3.0718, -0.0698]
    _check_against_yourdfpy(robot, model, "panda_link0", tip, rng)


def test_panda_without_tip_is_not_a_chain() -> None:
    msg = _refused(lambda: read_urdf(PANDA_URDF), "not a chain")
    for leaf in ("panda_hand_tcp", "panda_leftfinger", "panda_rightfinger"):
        assert leaf in msg
    _refused(lambda: read_urdf(PANDA_URDF, tip_link="panda_rightfinger"), "panda_finger_joint2.*mimics")
    # the left finger is a plain prismatic joint: the chain to it has 8 joints
    assert read_urdf(PANDA_URDF, tip_link="panda_leftfinger").joints[-1].type == "prismatic"


def test_humanoid_candidate_tips_are_cut() -> None:
    path = ROBOTS_DIR / "romeo_description" / "urdf" / "romeo.urdf"
    msg = _refused(lambda: read_urdf(path), "not a chain")
    assert "in all)" in msg and msg.count("', '") == 9  # ten names listed, then the count


def _random_chain(rng: np.random.Generator, n: int) -> tuple[str, list[str]]:
    """A URDF chain of ``n`` joints of random types (fixed ones anywhere, also first and last), origins and axes."""
    parts, names = [], []
    for i in range(n):
        jtype = rng.choice(["revolute", "continuous", "prismatic", "fixed", "fixed"])
        xyz = " ".join(repr(float(v)) for v in rng.uniform(-0.5, 0.5, 3))
        rpy = " ".join(repr(float(v)) for v in rng.uniform(-math.pi, math.pi, 3))
        inner = f'<origin xyz="{xyz}" rpy="{rpy}"/>'
        if jtype != "fixed":
            axis = rng.normal(size=3)
            if jtype == "prismatic":  # yourdfpy slides along the axis as written: give it unit length
                axis /= np.linalg.norm(axis)
            inner += f'<axis xyz="{" ".join(repr(float(v)) for v in axis)}"/>'
            names.append(f"j{i}")
        if jtype in ("revolute", "prismatic"):
            inner += _limit(-1.5, 1.5)
        parts.append(_joint(f"j{i}", f"l{i}", f"l{i + 1}", str(jtype), inner))
    return _doc(*parts, links=tuple(f"l{i}" for i in range(n + 1))), names


def test_random_chains_with_fixed_joints_match_yourdfpy(rng: np.random.Generator) -> None:
    """Fixed joints before, between and after moving ones fold into the next origin or the tool; with the last
    link as tip every fixed joint counts, and by default too (the trailing fixed joints do not branch)."""
    checked = 0
    while checked < 30:
        n = int(rng.integers(1, 9))
        text, names = _random_chain(rng, n)
        if not names:
            continue
        model = _yourdfpy(text)
        robot = robot_from_urdf(text, SOURCE, tip_link=f"l{n}")
        assert robot.joint_names == names and robot.base_is_identity
        _check_against_yourdfpy(robot, model, "l0", f"l{n}", rng, n=20)
        default = robot_from_urdf(text, SOURCE)
        assert default.joint_names == names
        _check_against_yourdfpy(default, model, "l0", f"l{n}", rng, n=20)
        checked += 1


def test_fixed_joints_fold_into_neighbours() -> None:
    text = _doc(
        _joint("f0", "a", "b", "fixed", '<origin xyz="0 0 1"/>'),
        _joint("j1", "b", "c", "continuous", '<origin xyz="1 0 0"/><axis xyz="0 0 1"/>'),
        _joint("f2", "c", "d", "fixed", '<origin rpy="0 0 1.5707963267948966"/>'),
        _joint("j3", "d", "e", "continuous", '<origin xyz="0 0 2"/><axis xyz="0 0 1"/>'),
        _joint("f4", "e", "f", "fixed", '<origin xyz="0 0 3"/>'),
        links=tuple("abcdef"),
    )
    r = robot_from_urdf(text, tip_link="f")
    np.testing.assert_allclose(np.array(r.joints[0].origin)[:3, 3], [1, 0, 1])  # f0 folded into j1
    np.testing.assert_allclose(np.array(r.joints[1].origin)[:2, :2], [[0, -1], [1, 0]], atol=1e-15)  # f2 into j3
    np.testing.assert_allclose(r.T_flange_tool[:3, 3], [0, 0, 3])  # f4 is the tool
    np.testing.assert_allclose(r.fk([0.0, 0.0])[:3, 3], [1, 0, 6])


def test_continuous_limits() -> None:
    def read(limit: str) -> np.ndarray:
        text = _two_joints(f'<axis xyz="0 0 1"/>{limit}', "continuous")
        return robot_from_urdf(text, SOURCE).limits[1]

    np.testing.assert_array_equal(read(""), [-math.pi, math.pi])
    np.testing.assert_array_equal(read('<limit effort="1" velocity="1"/>'), [-math.pi, math.pi])
    np.testing.assert_array_equal(read('<limit lower="-10" upper="0.5"/>'), [-10.0, 0.5])


def test_revolute_limit_attributes_default_to_zero() -> None:
    """URDF: lower and upper default to 0 (a limit with only effort and velocity holds the joint at 0)."""
    r = robot_from_urdf(_two_joints('<axis xyz="0 0 1"/><limit effort="1" velocity="1"/>'), SOURCE)
    np.testing.assert_array_equal(r.limits[1], [0.0, 0.0])


def test_arbitrary_axis_and_prismatic_joint(rng: np.random.Generator) -> None:
    unit = np.array([1.0, 2.0, 3.0]) / math.sqrt(14.0)
    revolute = _doc(
        _joint("j1", "a", "b", inner=f'<origin xyz="0.1 0.2 0.3" rpy="0.4 -0.5 0.6"/><axis xyz="1 2 3"/>{_limit()}'),
        links=("a", "b"),
    )
    r = robot_from_urdf(revolute, SOURCE, tip_link="b")
    np.testing.assert_allclose(r.joints[0].axis, unit, rtol=0, atol=1e-16)
    _check_against_yourdfpy(r, _yourdfpy(revolute), "a", "b", rng)
    # the axis is a fixed direction of the moving frame: rotating about it leaves it in place
    q = rng.uniform(-2, 2, (50, 1))
    axis_world = np.array(r.joints[0].origin)[:3, :3] @ unit
    np.testing.assert_allclose(r.fk(q)[:, :3, :3] @ unit, np.broadcast_to(axis_world, (50, 3)), atol=1e-15)

    prismatic = _doc(
        _joint("s", "a", "b", "prismatic", f'<origin xyz="0.1 0 0"/><axis xyz="1 2 3"/>{_limit(0, 2)}'),
        links=("a", "b"),
    )
    p = robot_from_urdf(prismatic, SOURCE, tip_link="b")
    assert p.joints[0].type == "prismatic" and p.limits.tolist() == [[0.0, 2.0]]
    # URDF normalises the axis (yourdfpy does not for prismatic joints, so the formula is the oracle here)
    s = rng.uniform(0, 2, (50, 1))
    np.testing.assert_allclose(p.fk(s)[:, :3, 3], [0.1, 0, 0] + s * unit, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(p.fk(s)[:, :3, :3], np.broadcast_to(np.eye(3), (50, 3, 3)))


def test_missing_origin_and_axis_defaults() -> None:
    r = robot_from_urdf(_doc(_joint("j1", "a", "b", "continuous", ""), links=("a", "b")), SOURCE, tip_link="b")
    assert r.joints[0].axis == (1.0, 0.0, 0.0)
    np.testing.assert_array_equal(np.array(r.joints[0].origin), np.eye(4))


def test_off_chain_joints_are_ignored() -> None:
    """A floating joint, a mimic joint, an unrelated subtree and <transmission> joints off the chain do not matter;
    visuals with package:// meshes are never opened."""
    text = _doc(
        _joint("j1", "a", "b"),
        _joint("free", "a", "c", "floating", ""),
        _joint("m", "b", "d", inner=f'<mimic joint="j1"/><axis xyz="0 1 0"/>{_limit()}'),
        '<transmission name="t"><joint name="j1"/></transmission>',
        links=("a", "b", "c", "d"),
    ).replace(
        '<link name="b"/>',
        '<link name="b"><visual><geometry><mesh filename="package://x/y.stl"/></geometry></visual></link>',
    )
    r = robot_from_urdf(text, SOURCE, tip_link="b")
    assert r.joint_names == ["j1"]


def test_unknown_or_multibyte_encoding_declaration_refused() -> None:
    for enc in ("x-bogus", "utf-32"):
        doc = f'<?xml version="1.0" encoding="{enc}"?>' + _two_joints()
        _refused(lambda doc=doc: robot_from_urdf(doc.encode("latin-1"), SOURCE), "encoding")


def test_attribute_flood_refused_fast() -> None:
    """One element with 300,000 attributes (3.5 MiB, few '<'): refused before the parser hands them to Python."""
    attrs = " ".join(f"a{i:x}='1'" for i in range(300_000))
    doc = f'<robot name="t"><link name="a" {attrs}/></robot>'
    _refused(lambda: robot_from_urdf(doc, SOURCE), "'='")


def test_text_encoding_and_declarations() -> None:
    text = _two_joints().replace('name="t"', 'name="bräu"')
    declared = '<?xml version="1.0" encoding="ISO-8859-1"?>\n' + text
    assert robot_from_urdf(declared, SOURCE).name == "bräu"  # str: the declaration does not re-decode it
    assert robot_from_urdf(declared.encode("latin-1"), SOURCE).name == "bräu"  # bytes: decoded as declared
    assert robot_from_urdf(text.encode("utf-16"), SOURCE).name == "bräu"
    assert robot_from_urdf(text.replace('name="bräu"', ""), "dir/my_arm.urdf").name == "my_arm"


# ---------------------------------------------------------------------------------------------- writer


def _round_trip(robot: sweepik.Robot, rng: np.random.Generator) -> None:
    text = urdf_text(robot)
    back = robot_from_urdf(text, SOURCE)  # the default tip follows the single fixed tool joint
    assert np.array_equal(robot_from_urdf(text, SOURCE, tip_link="tool").T_flange_tool, back.T_flange_tool)
    m = mm_per_unit(robot.length_unit) / 1000.0
    assert back.length_unit == "m" and back.n_joints == robot.n_joints and back.name == robot.name
    assert [j.type for j in back.joints] == [j.type for j in robot.joints]
    assert back.joint_names == robot.joint_names
    scale = np.where(robot.is_revolute, 1.0, m)
    np.testing.assert_array_equal(back.lower, robot.lower * scale)
    np.testing.assert_array_equal(back.upper, robot.upper * scale)
    q = _in_limits(robot, rng, 100, cap=max(2 * math.pi, robot.length_scale))
    expected = robot.fk(q)
    expected[..., :3, 3] *= m
    got = back.fk(q * scale)
    tol = 1e-12 * max(1.0, robot.length_scale * m)
    np.testing.assert_allclose(got, expected, rtol=0, atol=tol)
    # an independent reader agrees on the written file
    model = _yourdfpy(text)
    np.testing.assert_allclose(
        _yourdfpy_fk(model, back.joint_names, q[:20] * scale, "world", "tool"), got[:20], rtol=0, atol=tol
    )


@pytest.mark.parametrize("name", sweepik.bundled_robots())
def test_round_trip_bundled_robots(name: str, rng: np.random.Generator) -> None:
    _round_trip(sweepik.load_robot(name), rng)


def test_round_trip_with_base_tool_and_origin_axis_form(rng: np.random.Generator) -> None:
    carm = sweepik.load_robot("carm")  # mm, a prismatic first joint, modified DH
    moved = dataclasses.replace(
        carm,
        T_world_base=pose_from_xyz_zyz([100.0, -20.0, 300.0], [0.3, 1.2, -0.7]),
        T_flange_tool=pose_from_xyz_zyz([0.0, 5.0, 120.0], [1.0, math.pi / 2, 0.2]),
    )
    _round_trip(moved, rng)
    ur5 = sweepik.load_robot("ur5")  # standard DH: the last row's fixed part goes into the tool joint
    _round_trip(dataclasses.replace(ur5, T_flange_tool=pose_from_xyz_zyz([0, 0, 0.1], [0.0, math.pi, 0.0])), rng)
    # origin + axis (a URDF read back) writes and reads again to the same FK
    panda = read_urdf(PANDA_URDF, tip_link="panda_hand")
    _round_trip(panda, rng)
    # gimbal-locked rotations (pitch exactly +-pi/2) in an origin
    _round_trip(dataclasses.replace(ur5, T_world_base=pose_from_xyz_zyz([0, 0, 0], [0.4, math.pi / 2, 0.0])), rng)


def test_writer_names() -> None:
    ur5 = sweepik.load_robot("ur5")
    joints = tuple(dataclasses.replace(j, name="tool_joint" if i == 0 else j.name) for i, j in enumerate(ur5.joints))
    named = dataclasses.replace(ur5, joints=joints, name='a <"quoted"> & odd name')
    back = robot_from_urdf(urdf_text(named), SOURCE, tip_link="tool")
    assert back.name == named.name
    assert back.joint_names[0] == "tool_joint"
    assert "tool_joint_2" in urdf_text(named)  # the fixed joint to the tool gives way (URDF joint names must differ)
    twins = tuple(dataclasses.replace(j, name="tool_joint" if i < 2 else j.name) for i, j in enumerate(ur5.joints))
    with pytest.raises(RobotDefinitionError, match="'tool_joint' used more than once"):
        dataclasses.replace(ur5, joints=twins)
    with pytest.raises(UrdfError, match="characters XML cannot write"):
        urdf_text(dataclasses.replace(ur5, name="bad\x01name"))
    with pytest.raises(UnknownOptionError, match="needs a Robot"):
        urdf_text("ur5")  # type: ignore[arg-type]
