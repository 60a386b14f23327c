"""Display of verification results: the console table and the Markdown report with figures
(``sweepik verify``). The experiments themselves are in :mod:`sweepik.experiments.verify`."""

from __future__ import annotations

import math
from collections.abc import Sequence
from os import PathLike
from pathlib import Path
from typing import Any

from sweepik.experiments.verify import PAPER_TABLES, POINTS_PER_EDGE, RECALL_TOL, RECALL_TOL_LOOSE


def _by_strategy(result: dict[str, Any]) -> dict[str, dict[str, Any] | None]:
    if "grid" not in result:
        return {"paper": result.get("paper"), "precise": result.get("precise")}
    strat = result.get("strategy", "precise")
    return {"paper": result if strat == "paper" else None, "precise": result if strat == "precise" else None}


def _fmt(v: Any, kind: str) -> str:
    if v is None:
        return "-"
    if kind == "int":
        return f"{int(v):,}"
    if kind == "pct":
        return f"{100 * float(v):.2f} %"
    if kind == "time":
        v = float(v)
        return f"{v * 1e3:.3g} ms" if v < 1 else f"{v:.3g} s"
    if kind == "step":
        ang, length, unit = v.get("angle_deg"), v.get("length"), v.get("length_unit", "mm")
        parts = []
        if ang is not None:
            parts.append(f"{ang:.2f} deg")
        if length is not None:
            parts.append(f"{length:.1f} {unit}")
        return ", ".join(parts) or "-"
    return f"{float(v):.3g}"


_SECTIONS = (
    ("grid", "Grid, 15,900 nonsingular points (Table 3)", "grid"),
    ("grid_all", "Grid, all 16,500 points (singular ones included)", None),
    ("offgrid", "Off-grid random configurations", None),
    ("trajectory", "Trajectory (Table 4)", "trajectory"),
)
_METRICS = (
    ("points", "points", "int"),
    ("recall", "recall (within 1e-6)", "pct"),
    ("recall_loose", "recall (within 1e-4)", "pct"),
    ("J_max", "J_max (mm)", "num"),
    ("J_mean", "J_mean (mm)", "num"),
    ("J_99_6", "J_99.6% (mm)", "num"),
    ("seconds_per_point", "time per point", "time"),
    ("max_joint_step_detail", "max joint step", "step"),
    ("branch_switches", "branch switches", "int"),
)


def _table_rows(result: dict[str, Any]) -> list[tuple[str, list[list[str]]]]:
    strat = _by_strategy(result)
    ref = result.get("paper_reference", PAPER_TABLES)
    out = []
    for key, title, ref_key in _SECTIONS:
        rows = []
        for mkey, label, kind in _METRICS:
            cells = []
            for s in ("paper", "precise"):
                r = strat[s]
                sec = r.get(key) if r else None
                cells.append(_fmt(sec.get(mkey), kind) if sec and mkey in sec else None)
            if all(c is None for c in cells):
                continue
            pv = ref.get(ref_key, {}).get(mkey) if ref_key else None
            paper_cell = _fmt(pv, kind) if pv is not None else "-"
            if mkey == "seconds_per_point" and pv is not None:
                paper_cell += " (Matlab)"
            rows.append([label, paper_cell] + [c or "-" for c in cells])
        out.append((title, rows))
    return out


def format_table(result: dict[str, Any]) -> str:
    """A console table of a :func:`run_verify` result: metric by metric, the paper | sweepik with the
    paper's strategy | sweepik precise ('-' where a column was not run or the paper gives no number)."""
    header = ["metric", "paper", "sweepik paper-strategy", "sweepik precise"]
    sections = _table_rows(result)
    all_rows = [header] + [r for _, rows in sections for r in rows]
    widths = [max(len(r[i]) for r in all_rows) for i in range(4)]

    def line(r: list[str]) -> str:
        return "  ".join([r[0].ljust(widths[0])] + [c.rjust(w) for c, w in zip(r[1:], widths[1:], strict=True)])

    out = [line(header), "-" * (sum(widths) + 6)]
    for title, rows in sections:
        out.append(title)
        out.extend(line(r) for r in rows)
    return "\n".join(out)


def _markdown_table(result: dict[str, Any]) -> str:
    out = []
    for title, rows in _table_rows(result):
        out.append(f"**{title}**\n")
        out.append("| metric | paper | sweepik paper-strategy | sweepik precise |")
        out.append("|---|---:|---:|---:|")
        out.extend("| " + " | ".join(r) + " |" for r in rows)
        out.append("")
    return "\n".join(out)


def _deg_config(q: Sequence[float]) -> str:
    return "(" + ", ".join([f"{q[0]:g} mm"] + [f"{math.degrees(v):g}°" for v in q[1:]]) + ")"


def _classes_text(by_class: dict[str, int]) -> str:
    return ", ".join(f"{n} {k}" for k, n in sorted(by_class.items(), key=lambda kv: -kv[1])) or "none"


def _max_solutions(summary: dict[str, Any]) -> int:
    return max((int(k) for k in summary.get("solutions_histogram", {})), default=0)


def _explanations(result: dict[str, Any]) -> list[str]:
    """Paragraphs explaining each difference from the paper's tables, filled from the measured numbers."""
    runs = {k: v for k, v in _by_strategy(result).items() if v is not None}
    out = (
        _paper_strategy_text(runs) + _precise_strategy_text(runs) + _figure4_text(runs) + _singular_and_time_text(runs)
    )
    return out + _trajectory_text(runs)


def _paper_strategy_text(runs: dict[str, Any]) -> list[str]:
    """The paper's strategy on and off the grid."""
    ref = PAPER_TABLES
    e = "{:.3g}".format
    out: list[str] = []
    if "paper" in runs:
        g, o = runs["paper"]["grid"], runs["paper"]["offgrid"]
        out.append(
            f"**Grid-exact d1 flatters the paper's strategy.** The Table-2 d1 values (500, 1000, 1500 mm) lie "
            f"exactly on its 10 mm sweep grid, so the sweep samples the exact d1 of every generating "
            f"configuration and J sits at rounding level: J_max = {_fmt(g['J_max'], 'num')} mm and "
            f"J_mean = {_fmt(g['J_mean'], 'num')} mm on the 15,900 points (paper: {e(ref['grid']['J_max'])} and "
            f"{e(ref['grid']['J_mean'])} mm). The paper's J_max, three orders of magnitude above its own 99.6 % "
            f"threshold, suggests a few poses where its Matlab implementation stopped short of the exact grid "
            f"point; ours evaluates the same grid points exactly."
        )
        if g["missed_total"]:
            by_class = g.get("missed_by_class", {})
            text = (
                f"**Misses of the paper's strategy on the grid.** {g['missed_total']} generating configurations "
                f"are not found (recall {_fmt(g['recall'], 'pct')}); by set: {_classes_text(by_class)}."
            )
            if by_class.get("self-motion"):
                text += (
                    " At a self-motion pose (θ2 = ±90°, θ5 = 0) every d1 of an interval solves the pose; the "
                    "strategy has no notion of a continuum, reports the local minima of rounding noise along it "
                    f"as isolated solutions (up to {_max_solutions(g)} per pose) and the generating configuration "
                    "is rarely among them."
                )
            out.append(text)
        if o.get("points"):
            out.append(
                f"**Off the grid the paper's strategy loses most solutions.** With continuous d1 "
                f"({o['points']:,} random in-limit configurations, seed {o.get('seed')}) its final d1 is only "
                f"within 0.0005 mm of the root (the last refinement step is 0.001 mm). The remaining pose error "
                f"often exceeds its acceptance threshold J < 1e-5 mm, and the solution is dropped: "
                f"{o['no_solution']:,} of the {o['points']:,} poses get no solution at all. The solutions it "
                f"keeps have J up to {_fmt(o['J_max'], 'num')} mm (J_mean {_fmt(o['J_mean'], 'num')} mm) and "
                f"joint values only near the generating ones: recall {_fmt(o['recall'], 'pct')} within 1e-6, "
                f"{_fmt(o['recall_loose'], 'pct')} within 1e-4 (grid: {_fmt(g['recall'], 'pct')})."
            )
    return out


def _precise_strategy_text(runs: dict[str, Any]) -> list[str]:
    """The precise strategy, and its misses."""
    out: list[str] = []
    if "precise" in runs:
        g, o = runs["precise"]["grid"], runs["precise"]["offgrid"]
        text = (
            f"**The precise strategy** refines every root to full precision, on and off the grid: "
            f"J_max = {_fmt(g['J_max'], 'num')} mm on the 15,900 points and {_fmt(o.get('J_max'), 'num')} mm "
            f"on the off-grid set (recall {_fmt(o.get('recall'), 'pct')}); {g['family_poses']} grid poses are "
            f"reported with a self-motion family."
        )
        out.append(text)
        if g["missed_total"]:
            worst = max((m for m in g["missed_match"] if m is not None), default=None)
            listed = "; ".join(_deg_config(q) for q in g["missed"][:5])
            out.append(
                f"**Recall below 1 (precise strategy).** {g['missed_total']} of the {g['points']:,} "
                f"nonsingular generating configurations are not matched within {RECALL_TOL:g} (recall "
                f"{_fmt(g['recall'], 'pct')}; by set: {_classes_text(g.get('missed_by_class', {}))}); within "
                f"{RECALL_TOL_LOOSE:g} the recall is {_fmt(g['recall_loose'], 'pct')}. The closest solutions "
                f"differ by up to {_fmt(worst, 'num')} (d1 in mm) in the listed misses: the generating "
                f"configuration is a double root (two solution branches crossing), located only to about "
                f"sqrt(machine epsilon); J is at rounding level but d1 is not exact. First misses: {listed}."
            )
    return out


def _figure4_text(runs: dict[str, Any]) -> list[str]:
    """Figure 4, the two strategies side by side."""
    out: list[str] = []
    if all(k in runs and "figure4" in runs[k] for k in ("paper", "precise")):
        fp, fq = runs["paper"]["figure4"], runs["precise"]["figure4"]
        fewer = [
            f"{t:g}° ({a} vs {b})"
            for t, a, b in zip(fp["theta2_desired_deg"], fp["n_solutions"], fq["n_solutions"], strict=True)
            if a < b
        ]
        out.append(
            f"**Figure 4.** The desired θ2 is found at {sum(fp['desired_found'])} of the 11 points by the "
            f"paper's strategy and at {sum(fq['desired_found'])} by the precise one (the paper: always), and "
            f"the alternate solution 180° off is common, as in the paper. In total the paper's strategy reports "
            f"{sum(fp['n_solutions'])} solutions, the precise one {sum(fq['n_solutions'])}"
            + (
                f"; the paper's strategy misses some at desired θ2 = {', '.join(fewer)} (paper vs precise): it "
                f"keeps only the best branch per 10 mm sample, so a root on another branch, or two roots within "
                f"one sample step, are lost."
                if fewer
                else "."
            )
        )
    return out


def _singular_and_time_text(runs: dict[str, Any]) -> list[str]:
    """The singular poses the paper leaves out, and the time per point."""
    ref = PAPER_TABLES
    out: list[str] = []
    for name, run in runs.items():
        ga, g = run["grid_all"], run["grid"]
        out.append(
            f"**Singular poses ({name} strategy).** The paper leaves out the 600 configurations with "
            f"θ2 = ±90° and θ3 = 0 (double roots along d1; with θ5 = 0 a self-motion family). Including them "
            f"(16,500 points): recall {_fmt(ga['recall'], 'pct')} (15,900 points: {_fmt(g['recall'], 'pct')}), "
            f"J_max = {_fmt(ga['J_max'], 'num')} mm."
        )
    times = ", ".join(f"{_fmt(r['grid']['seconds_per_point'], 'time')} ({n} strategy)" for n, r in runs.items())
    out.append(
        f"**Time per point.** The paper reports {ref['grid']['seconds_per_point']} s per point in Matlab on "
        f"2008 hardware; sweepik (vectorised batches, the search compiled with Numba when installed) takes "
        f"{times} on the grid."
    )
    return out


def _trajectory_text(runs: dict[str, Any]) -> list[str]:
    """The rectangle trajectory of Table 4."""
    ref = PAPER_TABLES
    e = "{:.3g}".format
    out: list[str] = []
    tr_run = runs.get("precise") or runs.get("paper")
    if tr_run:
        tr = tr_run["trajectory"]
        corners = " → ".join("(" + ", ".join(f"{c:g}" for c in cc) + ")" for cc in tr["corners"])
        out.append(
            f"**Trajectory.** The paper does not give its rectangle's corners; ours are {corners} mm (chosen to "
            f"stay clear of joint limits and singularities, see docs/verification.md), {POINTS_PER_EDGE} points "
            f"per edge plus the closing point ({tr['points']} points). z changes in 40 mm steps, on the paper "
            f"strategy's 10 mm grid, so both strategies reach rounding-level J here, as in Table 4 "
            f"({e(ref['trajectory']['J_max'])} / {e(ref['trajectory']['J_mean'])} mm; ours: "
            f"{_fmt(tr['J_max'], 'num')} / {_fmt(tr['J_mean'], 'num')} mm — the difference is rounding). "
            f"Following the nearest solution gives {tr['branch_switches']} branch switch(es) and a largest step "
            f"of {_fmt(tr['max_joint_step_detail'], 'step')}."
        )
    return out


def write_report(result: dict[str, Any], directory: str | PathLike[str]) -> Path:
    """Write ``report.md`` with the comparison table, explanations of every difference from the paper, and
    PNG figures (Figure 4 per strategy, the Figure-5 path in 3D, joints along the path) into ``directory``
    (created if needed). Returns the report's path. Needs matplotlib (``sweepik[plot]``)."""
    from sweepik.experiments.plot import save_verification_figures

    out_dir = Path(directory)
    figures = save_verification_figures(result, out_dir)
    runs = {k: v for k, v in _by_strategy(result).items() if v is not None}
    robot = next(iter(runs.values())).get("robot", "carm") if runs else "carm"
    lines = [
        f"# sweepik verification report ({robot})",
        "",
        "Reproduction of section 6 of Friedman et al. (C-Arm inverse kinematics): Table 3 (grid of Table 2), "
        "Figure 4, Table 4 and Figure 5 (trajectory), plus an off-grid test. J is the paper's error (eq. 6) "
        "in mm, of the solution closest to the generating configuration. Recall: share of poses whose "
        f"generating configuration is among the solutions (every joint within {RECALL_TOL:g}, d1 in mm, "
        "angles in rad). See docs/verification.md for the definitions.",
        "",
        _markdown_table(result),
        "## Differences from the paper",
        "",
    ]
    for para in _explanations(result):
        lines += [para, ""]
    lines += ["## Figures", ""]
    captions = {
        "figure4": "Figure 4: θ2 of every solution (×) against the desired θ2 (○); (m) = multiplicity.",
        "trajectory_3d": "Figure 5: the rectangle (thin), the trajectory (thick) and the computed points (*).",
        "trajectory_joints": "Joint values along the trajectory (revolute in degrees, d1 in mm on the right axis).",
    }
    for name, path in figures.items():
        cap = next((c for k, c in captions.items() if name.startswith(k)), name)
        lines += [f"![{name}]({path.name})", "", f"*{cap}* ({name})", ""]
    report = out_dir / "report.md"
    report.write_text("\n".join(lines))
    return report
