"""Seed 001's experiment: joints 2 and 4 of the 4-DOF arm move 0 → ±1.6 rad in 2 s.

Plans the motion as a rest-to-rest cubic (the seed's method, formulas corrected) and as a quintic,
tabulates position, speed and acceleration at 0.5, 1, 1.5 and 2 s beside the paper's Tables 1–3,
and explains why the tables cannot all be matched. Writes into the output folder:

- ``seed001_motion.png``: q, q̇, q̈ of joint 2 (and the mirrored joint 4) for both polynomials, with
  the paper's table entries as markers;
- ``seed001_table.md`` and ``seed001_table.csv``: the comparison table;
- ``summary.json``: every computed value, the paper's values and the consistency checks.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .. import traj  # noqa: E402

TIMES = (0.5, 1.0, 1.5, 2.0)
DURATION = 2.0
TARGET = 1.6  # rad, joint 2; joint 4 goes to −1.6 rad

# Seed 001, Tables 1–3, joint 2 (joint 4 is the mirror image; joints 1 and 3 stay at 0).
PAPER = {
    "position": (0.2, 0.7, 1.4, 1.6),
    "velocity": (1.5, 3.0, 1.5, 0.0),
    "acceleration": (8.0, 0.0, -8.0, 0.0),
}
UNITS = {"position": "rad", "velocity": "rad/s", "acceleration": "rad/s²"}

WHY = (
    "The paper's Tables 1–3 cannot all be matched by a cubic, a quintic or even consistently with each "
    "other: its speeds (0, 1.5, 3.0, 1.5, 0 rad/s at 0, 0.5, 1, 1.5, 2 s) integrate to 3.0 rad (trapezoidal "
    "and Simpson rules alike), nearly twice the 1.6 rad its Table 1 reaches; Table 1 is not symmetric "
    "about 1 s (0.7 rad instead of 0.8 rad at half time) although Tables 2–3 are; and its "
    "accelerations 8, 0, −8, 0 rad/s² are not on a line, as a cubic's must be (the corrected cubic "
    "gives 1.2, 0, −1.2, −2.4 rad/s²), while "
    "the quintic that does end at zero acceleration peaks at 15·1.6/(8·2) = 1.5 rad/s, half the table's "
    "3.0 rad/s. We therefore show the corrected cubic and a quintic and do not fit to the tables."
)


def _evaluate(kind: str) -> dict[str, list[float]]:
    q0, q1 = np.zeros(2), np.array([TARGET, -TARGET])
    t = traj.cubic(q0, q1, DURATION) if kind == "cubic" else traj.quintic(q0, q1, DURATION)
    q, qd, qdd = t.sample(np.array(TIMES))
    return {
        "position": q[:, 0].tolist(),
        "velocity": qd[:, 0].tolist(),
        "acceleration": qdd[:, 0].tolist(),
        "joint4_mirrors_joint2": bool(np.allclose(q[:, 1], -q[:, 0]) and np.allclose(qd[:, 1], -qd[:, 0])),
    }


def _figure(path: Path) -> None:
    q0, q1 = np.zeros(2), np.array([TARGET, -TARGET])
    curves = {"cubic": traj.cubic(q0, q1, DURATION), "quintic": traj.quintic(q0, q1, DURATION)}
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2), constrained_layout=True)
    for name, style in (("cubic", "-"), ("quintic", "--")):
        t, q, qd, qdd = curves[name].sample_rate(200.0)
        for ax, y in zip(axes, (q, qd, qdd), strict=False):
            ax.plot(t, y[:, 0], style, color="tab:blue", label=f"joint 2, {name}")
            ax.plot(t, y[:, 1], style, color="tab:orange", label=f"joint 4, {name}")
    for ax, key in zip(axes, ("position", "velocity", "acceleration"), strict=False):
        paper = np.array(PAPER[key])
        ax.plot(TIMES, paper, "o", color="tab:blue", mfc="none", ms=8, label="paper, joint 2")
        ax.plot(TIMES, -paper, "s", color="tab:orange", mfc="none", ms=8, label="paper, joint 4")
        ax.set_xlabel("t [s]")
        ax.set_ylabel(f"{key} [{UNITS[key]}]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(
        "Seed 001: joints 2 and 4, 0 → ±1.6 rad in 2 s (lines: ttmanip; markers: paper's Tables 1–3)"
    )
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _integral_of_paper_speeds() -> dict[str, float]:
    v = np.array([0.0, *PAPER["velocity"]])
    h = 0.5
    trapezoid = float(h * (v[0] / 2 + v[1:-1].sum() + v[-1] / 2))
    simpson = float(h / 3 * (v[0] + 4 * v[1] + 2 * v[2] + 4 * v[3] + v[4]))
    return {"trapezoid_rad": trapezoid, "simpson_rad": simpson}


def run(out_dir: Path) -> dict:
    """Runs the experiment, writes figures, tables and summary.json into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    results = {kind: _evaluate(kind) for kind in ("cubic", "quintic")}

    rows = []
    for key in ("position", "velocity", "acceleration"):
        for i, t in enumerate(TIMES):
            rows.append((key, t, PAPER[key][i], results["cubic"][key][i], results["quintic"][key][i]))
    with open(out / "seed001_table.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["quantity", "t_s", "paper", "cubic", "quintic"])
        w.writerows(rows)
    lines = [
        "# Seed 001: joint 2 (0 → 1.6 rad in 2 s; joint 4 is its mirror image)",
        "",
        "| quantity | t [s] | paper (Tables 1–3) | cubic (corrected) | quintic |",
        "|---|---|---|---|---|",
    ]
    for key, t, p, c, q in rows:
        lines.append(f"| {key} [{UNITS[key]}] | {t:g} | {p:g} | {c:.4f} | {q:.4f} |")
    lines += ["", WHY, ""]
    (out / "seed001_table.md").write_text("\n".join(lines))
    _figure(out / "seed001_motion.png")

    expected_cubic = {
        "position": [0.25, 0.8, 1.35, 1.6],
        "velocity": [0.9, 1.2, 0.9, 0.0],
        "acceleration": [1.2, 0.0, -1.2, -2.4],
    }
    cubic_ok = all(np.allclose(results["cubic"][k], v, atol=1e-12) for k, v in expected_cubic.items())
    summary = {
        "times_s": list(TIMES),
        "cubic": results["cubic"],
        "quintic": results["quintic"],
        "paper_joint2": {k: list(v) for k, v in PAPER.items()},
        "cubic_matches_readme_values": bool(cubic_ok),
        "paper_speed_integral": _integral_of_paper_speeds(),
        "paper_final_position_rad": PAPER["position"][-1],
        "why_tables_cannot_all_be_matched": WHY,
        "figures": ["seed001_motion.png"],
        "tables": ["seed001_table.md", "seed001_table.csv"],
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=2, ensure_ascii=False))
    return {
        "out": str(out),
        "cubic_matches_readme_values": cubic_ok,
        "paper_speed_integral_rad": round(summary["paper_speed_integral"]["trapezoid_rad"], 3),
        "figures": ", ".join(summary["figures"]),
    }
