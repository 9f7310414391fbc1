"""Benchmark rows -> success rates per pose, method and task (grasp / place / overall) and the mean
over tasks; written as Markdown (with the paper's overall figures beside ours), JSON and a PNG chart."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from app.bench.paper import paper_overall
from app.io_utils import atomic_path, write_json

KINDS = ("grasp", "place", "overall")


def summarise(rows: list[dict], tasks: list[str], poses: list[str], methods: list[str]) -> dict:
    """{pose: {method: {task|'mean': {grasp, place, overall, n}}}} - rates over the trials present; a row
    whose job ended in a bug of ours (`internal_error`) is no trial of the method: counted apart."""
    out: dict = {}
    for pose in poses:
        for method in methods:
            cells = {}
            for t in tasks:
                every = [r for r in rows if r["pose"] == pose and r["method"] == method and r["task"] == t]
                sel = [r for r in every if not r.get("internal_error")]
                if sel:
                    cells[t] = {k: round(float(np.mean([r[k] for r in sel])), 3) for k in KINDS} | {"n": len(sel)}
                    if len(sel) < len(every):
                        cells[t]["internal_errors"] = len(every) - len(sel)
                    if all("gripper_in_table" in r for r in sel):
                        cells[t]["in_table"] = round(float(np.mean([r["gripper_in_table"] for r in sel])), 3)
            if cells:
                cells["mean"] = {k: round(float(np.mean([c[k] for c in cells.values()])), 3) for k in KINDS}
                out.setdefault(pose, {})[method] = cells
    return out


def markdown(summary: dict, tasks: list[str], title: str) -> str:
    """One table per pose: per task grasp / place / overall, the mean, and the paper's mean overall."""
    lines = [f"## {title}", ""]
    for pose, by_method in summary.items():
        lines += [f"### {pose.capitalize()} pose", "",
                  "| method | " + " | ".join(f"{t} G / P / **O**" for t in tasks) + " | mean G / P / **O** | paper mean O |",
                  "|---" * (len(tasks) + 3) + "|"]
        for method, cells in by_method.items():
            row = [f"{c['grasp']:.2f} / {c['place']:.2f} / **{c['overall']:.2f}**" if (c := cells.get(t)) else "-"
                   for t in (*tasks, "mean")]
            paper = _paper_mean(pose, method, tasks)
            lines.append(f"| {method} | " + " | ".join(row) + f" | {'-' if paper is None else f'{paper:.2f}'} |")
        ns = [c["n"] for cells in by_method.values() for t, c in cells.items() if t != "mean"]
        n = str(max(ns)) if min(ns) == max(ns) else f"{min(ns)}-{max(ns)}"
        lines += ["", f"{n} trials per task; G grasp, P place, O overall success.", ""]
        lines += [f"Grasps that put the open gripper into the table (judged as the paper does, without it), {method}: "
                  + ", ".join(f"{t} {c['in_table']:.2f}" for t, c in cells.items() if "in_table" in c) + "."
                  for method, cells in by_method.items() if any("in_table" in c for c in cells.values())]
        lines += [""] if any("in_table" in c for cells in by_method.values() for c in cells.values()) else []
    return "\n".join(lines)


def _paper_mean(pose: str, method: str, tasks: list[str]) -> float | None:
    """The paper's overall success averaged over these tasks (None if it did not report one)."""
    values = [paper_overall(pose, method, t) for t in tasks]
    return None if any(v is None for v in values) else round(float(np.mean(values)), 2)


def chart(summary: dict, path: Path) -> None:
    """Grouped bars of the mean overall success per method, one group per pose (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    poses = list(summary)
    methods = list(dict.fromkeys(m for by in summary.values() for m in by))
    fig, ax = plt.subplots(figsize=(1.2 + 1.1 * len(methods), 3.2))
    width = 0.8 / max(len(poses), 1)
    x = np.arange(len(methods))
    for i, pose in enumerate(poses):
        values = [summary[pose].get(m, {}).get("mean", {}).get("overall", 0.0) for m in methods]
        ax.bar(x + i * width, values, width, label=pose)
    ax.set_xticks(x + width * (len(poses) - 1) / 2, methods, rotation=20)
    ax.set_ylim(0, 1)
    ax.set_ylabel("mean overall success")
    ax.legend()
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=100)
    plt.close(fig)


def write_report(rows: list[dict], tasks: list[str], poses: list[str], methods: list[str], out: Path,
                 title: str) -> dict:
    """Write table.md, summary.json and chart.png into out; return the summary."""
    summary = summarise(rows, tasks, poses, methods)
    with atomic_path(out / "table.md") as tmp:
        Path(tmp).write_text(markdown(summary, tasks, title))
    write_json(out / "summary.json", summary)
    if summary:
        chart(summary, out / "chart.png")
    return summary
