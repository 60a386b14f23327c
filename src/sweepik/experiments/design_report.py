"""Display of a design comparison (:func:`sweepik.experiments.design.compare_designs`): the console table, the figures
(PNG, matplotlib: ``pip install 'sweepik[plot]'``) and the Markdown report that states which design wins on what.
"""

from __future__ import annotations

from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from sweepik.experiments.design import EFFORT_NOISE, Candidate, DesignComparison, jacobian_singular_values
from sweepik.experiments.plot import _legend_below, _pyplot

__all__ = ["format_table", "save_design_figures", "write_design_report"]

#: Projections of the workspace maps: (x axis, y axis) indices into (x, y, z).
_PLANES = ((0, 1), (0, 2), (1, 2))
_AXIS = "xyz"


def _num(v: float | None, fmt: str = ".4g", scale: float = 1.0, unit: str = "") -> str:
    if v is None:
        return "—"
    return f"{v * scale:{fmt}}{(' ' + unit) if unit else ''}"


def _rows(cmp: DesignComparison) -> list[tuple[str, list[str]]]:
    """The side-by-side table: (metric, one cell per candidate)."""
    cs = cmp.candidates

    def row(label: str, cell: Any) -> tuple[str, list[str]]:
        return label, [cell(c) for c in cs]

    def decomposition(c: Candidate) -> str:
        d = c.decomposition
        if d["kind"] == "closed form":
            return f"closed form ({d['branches']} branches)"
        return f"1-D sweep over joint {d['free_joint_number']} ({d['free_joint']}), {d['branches']} branches"

    rows = [
        row("structure", lambda c: c.decomposition["structure"]),
        row("decomposition", decomposition),
        row("reduction", lambda c: c.decomposition["reduction"]),
        row("IK time per pose", lambda c: _num(c.ik["seconds_per_pose"], ".1f", 1e6, "µs")),
        row("task poses reached", lambda c: _num(c.ik["reached_share"], ".1f", 100, "%")),
        row(
            "solutions per reached pose (mean / max)",
            lambda c: f"{_num(c.ik['mean_solutions'], '.2f')} / {c.ik['max_solutions']}",
        ),
        row("poses with a multiple root", lambda c: _num(c.ik["multiple_root_share"], ".2f", 100, "%")),
        row("poses with a self-motion family", lambda c: _num(c.ik["self_motion_share"], ".2f", 100, "%")),
        row("solutions within joint limits", lambda c: _num(c.ik["within_limits_share"], ".1f", 100, "%")),
        row(
            "reachable volume",
            lambda c: f"{c.workspace['volume_m3']:.4g} ± {c.workspace['uncertainty_m3']:.2g} m³",
        ),
        row("Yoshikawa w (median)", lambda c: _num(c.manipulability["yoshikawa"]["p50"])),
        row(
            "smallest singular value (median / 5th pct)",
            lambda c: f"{_num(c.manipulability['sigma_min']['p50'])} / {_num(c.manipulability['sigma_min']['p5'])}",
        ),
        row("largest holding torque, revolute joints", lambda c: _num(c.effort["largest"]["max"], ".2f", unit="N·m")),
    ]
    n = max(c.robot.n_joints for c in cs)
    for i in range(n):

        def cell(c: Candidate, i: int = i) -> str:
            if i >= c.robot.n_joints:
                return "—"
            s = c.effort["per_joint"][i]
            unit = c.effort["units"][i]
            return f"{c.robot.joint_names[i]}: {_num(s['max'], '.2f')} / {_num(s['p95'], '.2f')} {unit}"

        rows.append(row(f"joint {i + 1} effort (max / 95th pct)", cell))
    return rows


def format_table(cmp: DesignComparison) -> str:
    """The side-by-side table as aligned text (console)."""
    head = ["", *[c.name for c in cmp.candidates]]
    body = [[label, *cells] for label, cells in _rows(cmp)]
    widths = [max(len(r[k]) for r in [head, *body]) for k in range(len(head))]
    lines = ["  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True)).rstrip() for r in [head, *body]]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def _verdict_line(v: dict[str, Any]) -> str:
    values = ", ".join(f"{k} {val if val is not None else '—'}" for k, val in v["values"].items())
    if v["winner"] is None:
        return f"- **{v['criterion']}** ({v['better']} is better): no clear winner ({values})."
    return f"- **{v['criterion']}**: **{v['winner']}** ({v['why']}; {values})."


# --------------------------------------------------------------------------------------------------
# Figures
# --------------------------------------------------------------------------------------------------


def _save(fig: Any, path: Path) -> Path:
    plt = _pyplot()
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path


def _solutions_figure(cmp: DesignComparison, path: Path) -> Path:
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.0, 4.2))
    top = max(int(c.solutions_per_pose.max(initial=0)) for c in cmp.candidates)
    k = np.arange(top + 1)
    width = 0.8 / len(cmp.candidates)
    for j, c in enumerate(cmp.candidates):
        counts = np.bincount(c.solutions_per_pose, minlength=top + 1)
        share = 100.0 * counts / max(len(c.solutions_per_pose), 1)
        ax.bar(k + (j - (len(cmp.candidates) - 1) / 2) * width, share, width, label=c.name)
    ax.set_xticks(k)
    ax.set_xlabel("solutions within the joint limits")
    ax.set_ylabel("share of task poses (%)")
    ax.set_title(f"Solutions per pose ({cmp.task['n_poses']:,} task poses)", fontsize=10)
    ax.grid(True, axis="y", alpha=0.3)
    _legend_below(ax)
    fig.tight_layout()
    return _save(fig, path)


def _workspace_figure(cmp: DesignComparison, c: Candidate, path: Path) -> Path:
    """Three projections of the task positions, each coloured by this candidate's number of solutions."""
    plt = _pyplot()
    from matplotlib.colors import BoundaryNorm, ListedColormap

    P = cmp.positions
    counts = c.solutions_per_pose
    top = max(int(x.solutions_per_pose.max(initial=0)) for x in cmp.candidates)
    base = plt.get_cmap("viridis", max(top, 1))
    colours = ["0.8", *[base(i) for i in range(max(top, 1))]]
    cmap = ListedColormap(colours[: top + 1] if top else colours[:2])
    norm = BoundaryNorm(np.arange(-0.5, max(top, 1) + 1.0), cmap.N)
    order = np.argsort(counts, kind="stable")  # poses with more solutions drawn last, on top
    unit = cmp.task["length_unit"]
    fig, axes = plt.subplots(1, 3, figsize=(13.0, 4.4))
    lo, hi = P.min(axis=0), P.max(axis=0)
    pad = max(0.05 * float(np.max(hi - lo)) if P.size else 1.0, 1e-3 * (1.0 + float(np.max(np.abs(P), initial=0.0))))
    sc = None
    for ax, (a, b) in zip(axes, _PLANES, strict=True):
        sc = ax.scatter(P[order, a], P[order, b], c=counts[order], cmap=cmap, norm=norm, s=6, linewidths=0)
        ax.set_xlabel(f"{_AXIS[a]} ({unit})")
        ax.set_ylabel(f"{_AXIS[b]} ({unit})")
        ax.set_xlim(lo[a] - pad, hi[a] + pad)
        ax.set_ylim(lo[b] - pad, hi[b] + pad)
        ax.set_aspect("equal", adjustable="box")
        ax.set_title(f"{_AXIS[a]}-{_AXIS[b]} projection", fontsize=9)
        ax.grid(True, alpha=0.3)
    bar = fig.colorbar(sc, ax=list(axes), shrink=0.85, ticks=np.arange(0, max(top, 1) + 1))
    bar.set_label("solutions within the joint limits (grey: none)")
    fig.suptitle(
        f"{c.name}: task poses by number of IK solutions "
        f"(reachable volume {c.workspace['volume_m3']:.3g} ± {c.workspace['uncertainty_m3']:.2g} m³)",
        fontsize=10,
    )
    return _save(fig, path)


def _effort_figure(cmp: DesignComparison, path: Path) -> Path:
    plt = _pyplot()
    n = max(c.robot.n_joints for c in cmp.candidates)
    cols = min(n, 4)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.3 * cols, 3.0 * rows + 0.6), squeeze=False)
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    x = np.arange(len(cmp.candidates))
    overall = max((s["max"] or 0.0) for c in cmp.candidates for s in c.effort["per_joint"])
    for i in range(rows * cols):
        ax = axes[i // cols][i % cols]
        if i >= n:
            ax.set_visible(False)
            continue
        have = [(j, c) for j, c in enumerate(cmp.candidates) if i < c.robot.n_joints and c.effort["per_joint"][i]["n"]]
        if not have:
            ax.text(0.5, 0.5, "no pose reached", transform=ax.transAxes, ha="center", va="center", fontsize=9)
            ax.set_title(f"joint {i + 1}", fontsize=9)
            continue
        mx = [c.effort["per_joint"][i]["max"] or 0.0 for _, c in have]
        p95 = [c.effort["per_joint"][i]["p95"] or 0.0 for _, c in have]
        med = [c.effort["per_joint"][i]["p50"] or 0.0 for _, c in have]
        pos = x[[j for j, _ in have]]
        ax.bar(pos, mx, 0.6, color=[f"C{j}" for j, _ in have], alpha=0.85)
        ax.plot(pos, p95, "k_", markersize=22, markeredgewidth=2)
        ax.plot(pos, med, "kx", markersize=7)
        units = sorted({c.effort["units"][i] for _, c in have})
        names = " / ".join(sorted({c.robot.joint_names[i] for _, c in have}))
        ax.set_title(f"joint {i + 1} ({names})", fontsize=9)
        ax.set_ylabel(f"|holding effort| ({', '.join(units)})", fontsize=8)
        if max(mx) <= EFFORT_NOISE * overall:  # rounding noise only: show a zero effort as zero
            ax.set_ylim(0.0, 1.0)
            ax.text(0.5, 0.5, "no load (0)", transform=ax.transAxes, ha="center", va="center", fontsize=9)
        else:
            ax.set_ylim(0.0, 1.08 * max(mx))
        ax.set_xticks(x)
        ax.set_xticklabels([c.name for c in cmp.candidates], fontsize=8, rotation=15)
        ax.grid(True, axis="y", alpha=0.3)
        for j in sorted(set(range(len(cmp.candidates))) - {j for j, _ in have}):
            ax.text(x[j], 0.5, "not reached", transform=ax.get_xaxis_transform(), ha="center", va="center",
                    rotation=90, fontsize=8)  # fmt: skip
    load = cmp.payload
    masses = _any_masses(cmp)
    fig.suptitle(
        f"Static holding effort over all in-limit solutions of the task: payload {load['mass_kg']:g} kg"
        + (" and link masses" if load["links"] and masses else ", no link masses"),
        fontsize=10,
    )
    handles = [
        Patch(color="0.5", alpha=0.85, label="max"),
        Line2D([], [], color="k", marker="_", linestyle="", markersize=14, markeredgewidth=2, label="95th percentile"),
        Line2D([], [], color="k", marker="x", linestyle="", markersize=7, label="median"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0.0, 0.06, 1.0, 0.95))
    return _save(fig, path)


def _manipulability_figure(cmp: DesignComparison, path: Path) -> Path:
    """Histograms of the smallest singular value and of Yoshikawa's w over the in-limit solutions."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0))
    for j, c in enumerate(cmp.candidates):
        s = jacobian_singular_values(c.robot, c.solutions_q)
        if s.shape[0] == 0:
            continue
        for ax, v in zip(axes, (s[:, -1], np.prod(s, axis=-1)), strict=True):
            ax.hist(v, bins=50, histtype="step", linewidth=1.5, color=f"C{j}", label=c.name, density=True)
    axes[0].set_xlabel("smallest singular value of J (SI units)")
    axes[1].set_xlabel("Yoshikawa manipulability w = √det(J Jᵀ)")
    for ax in axes:
        ax.set_ylabel("density")
        ax.grid(True, alpha=0.3)
        _legend_below(ax)
    fig.suptitle("Distance to singularity over all in-limit solutions of the task", fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def _any_masses(cmp: DesignComparison) -> bool:
    return any(j.mass > 0 for c in cmp.candidates for j in c.robot.joints)


def save_design_figures(cmp: DesignComparison, directory: str | PathLike[str]) -> dict[str, Path]:
    """Write the comparison's PNG figures into ``directory`` (created if needed); returns ``{name: path}``."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    figs = {
        "solutions_per_pose": _solutions_figure(cmp, out / "solutions_per_pose.png"),
        "effort": _effort_figure(cmp, out / "effort.png"),
        "manipulability": _manipulability_figure(cmp, out / "manipulability.png"),
    }
    for k, c in enumerate(cmp.candidates):
        figs[f"workspace_{k + 1}"] = _workspace_figure(cmp, c, out / f"workspace_{k + 1}_{_safe(c.name)}.png")
    return figs


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in name)[:60] or "robot"


# --------------------------------------------------------------------------------------------------
# The report
# --------------------------------------------------------------------------------------------------


def _md_cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def write_design_report(cmp: DesignComparison, directory: str | PathLike[str]) -> Path:
    """Write ``report.md`` (verdicts point by point, the side-by-side table, figures, definitions) and its
    figures into ``directory`` (created if needed); returns the report's path. Needs matplotlib."""
    out = Path(directory)
    figs = save_design_figures(cmp, out)
    names = [c.name for c in cmp.candidates]
    load = cmp.payload
    com = ", ".join(f"{v:g}" for v in load["com"])
    lines = [
        f"# sweepik design comparison: {' vs '.join(names)}",
        "",
        f"**Task**: {cmp.task['n_poses']:,} tool poses, {cmp.task['source']} (seed {cmp.task['seed']}). "
        f"**Payload**: {load['mass_kg']:g} kg at ({com}) {load['com_unit']} in the tool frame"
        + (
            "; link masses from the robot files"
            if load["links"] and _any_masses(cmp)
            else "; no link masses (none in the robot files)"
            if load["links"]
            else "; link masses ignored"
        )
        + ".",
        "",
        "Gravity: "
        + "; ".join(f"{c.name} along ({', '.join(f'{g:g}' for g in c.robot.gravity)})" for c in cmp.candidates)
        + " (world frame, from the robot files).",
        "",
        "## Which design wins on what",
        "",
        *[_verdict_line(v) for v in cmp.verdicts],
        "",
        "## Side by side",
        "",
        "| | " + " | ".join(_md_cell(n) for n in names) + " |",
        "|---|" + "---|" * len(names),
        *[
            "| " + _md_cell(label) + " | " + " | ".join(_md_cell(c) for c in cells) + " |"
            for label, cells in _rows(cmp)
        ],
        "",
        "## Figures",
        "",
        f"![solutions per pose]({figs['solutions_per_pose'].name})",
        "",
        f"![holding effort]({figs['effort'].name})",
        "",
        f"![manipulability]({figs['manipulability'].name})",
        "",
        *[f"![workspace of {c.name}]({figs[f'workspace_{k + 1}'].name})\n" for k, c in enumerate(cmp.candidates)],
        "## Definitions",
        "",
        "- *IK time per pose*: wall time of `solve_many` over the task divided by its size, after a warm-up "
        "(compilation excluded; its first call is in the JSON as `first_call_seconds`).",
        "- *Task poses reached*: poses with at least one solution inside the joint limits (or a self-motion "
        "family). *Solutions within joint limits*: solutions inside the limits over all solutions that reach the "
        "poses when the limits are ignored.",
        "- *Reachable volume*: volume of the tool point's positions over random in-limit configurations "
        f"({cmp.task['workspace_samples']:,} per candidate), from voxel occupancy, with its uncertainty "
        "(`sweepik.experiments.workspace`).",
        "- *Holding effort*: joint torque (N·m; N for a prismatic joint) that holds the arm still against "
        "gravity, at every in-limit solution of every task pose (`sweepik.experiments.statics`): the actuator each "
        "joint needs to hold the payload anywhere in the task.",
        "- *Manipulability*: Yoshikawa's w = √det(J Jᵀ) and the smallest singular value of the geometric "
        "Jacobian J at the tool point, lengths in metres, at the same configurations.",
        "",
    ]
    report = out / "report.md"
    report.write_text("\n".join(lines), encoding="utf-8")
    return report
