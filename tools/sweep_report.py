"""Turns a novaphy_sweep CSV into a markdown table and a Pareto plot (simulated robot-seconds per second
against error).

    /usr/bin/python3 tools/sweep_report.py sweep_quadruped.csv [--error error_1s] [--out PREFIX]

Writes PREFIX.md (default: the CSV's name) and PREFIX.png. The Pareto front holds the settings that no other
setting beats on both throughput and error; diverged settings are drawn apart and never on the front.
"""

import argparse
import csv
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the headless backend is chosen)


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise ValueError(f"{path}: no rows")
    return rows


def number(text):
    return float(text) if text not in ("", None) else math.nan


def pareto(rows, error):
    """Indices of the rows on the front: most robot-seconds per second for their error, none diverged."""
    candidates = [i for i, r in enumerate(rows) if r["setting"] != "reference" and number(r["diverged_steps"]) == 0]
    front = []
    for i in candidates:
        speed, err = number(rows[i]["robot_seconds_per_s"]), number(rows[i][error])
        beaten = any(
            number(rows[j]["robot_seconds_per_s"]) >= speed and number(rows[j][error]) <= err
            and (number(rows[j]["robot_seconds_per_s"]) > speed or number(rows[j][error]) < err)
            for j in candidates
        )
        if not beaten:
            front.append(i)
    return sorted(front, key=lambda i: number(rows[i]["robot_seconds_per_s"]))


def markdown(rows, error, front):
    errors = [k for k in rows[0] if k.startswith("error_")]
    mujoco = [k for k in rows[0] if k.startswith("mujoco_rk4_error_") and rows[0][k] != ""]
    columns = ["setting", "robot_steps_per_s", "robot_seconds_per_s"] + errors + mujoco + [
        "energy_error_j_per_kg", "max_penetration_m", "max_limit_overshoot", "diverged_steps"]
    lines = ["| " + " | ".join(c.replace("_", " ") for c in columns) + " | Pareto |",
             "|" + "---|" * (len(columns) + 1)]
    for i, r in enumerate(rows):
        cells = []
        for c in columns:
            if c == "setting":
                cells.append(r[c])
            elif c in ("robot_steps_per_s", "robot_seconds_per_s"):
                cells.append(f"{number(r[c]):,.0f}")
            elif c == "diverged_steps":
                cells.append(r[c])
            else:
                cells.append(f"{number(r[c]):.2e}")
        lines.append("| " + " | ".join(cells) + " | " + ("✓" if i in front else "") + " |")
    return "\n".join(lines) + "\n"


def plot(rows, error, front, path, title):
    fig, ax = plt.subplots(figsize=(8, 5), dpi=100)
    for i, r in enumerate(rows):
        if r["setting"] == "reference":
            continue
        speed, err = number(r["robot_seconds_per_s"]), max(number(r[error]), 1e-16)
        diverged = number(r["diverged_steps"]) > 0
        ax.scatter(speed, err, marker="x" if diverged else "o", color="tab:red" if diverged else (
            "tab:blue" if i in front else "tab:gray"), zorder=3)
        ax.annotate(r["setting"], (speed, err), fontsize=6, xytext=(3, 3), textcoords="offset points")
    if front:
        ax.plot([number(rows[i]["robot_seconds_per_s"]) for i in front],
                [max(number(rows[i][error]), 1e-16) for i in front], color="tab:blue", label="Pareto front")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("simulated robot-seconds per wall-clock second")
    ax.set_ylabel(f"{error.replace('_', ' ')} (max |q - q_ref|)")
    ax.set_title(title + " (x: diverged)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("csv")
    parser.add_argument("--error", default=None, help="the error column of the front (default: the first)")
    parser.add_argument("--out", default=None, help="PREFIX of PREFIX.md and PREFIX.png")
    args = parser.parse_args()
    rows = read(args.csv)
    error = args.error or next(k for k in rows[0] if k.startswith("error_"))
    if error not in rows[0]:
        raise SystemExit(f"sweep_report: no column '{error}' in {args.csv}")
    prefix = args.out or os.path.splitext(args.csv)[0]
    front = pareto(rows, error)
    with open(prefix + ".md", "w") as f:
        f.write(markdown(rows, error, front))
    plot(rows, error, front, prefix + ".png", f"{rows[0]['scene']}: speed against {error.replace('_', ' ')}")
    print(f"sweep_report: {len(rows)} rows, {len(front)} on the Pareto front of {error} -> {prefix}.md, {prefix}.png")


if __name__ == "__main__":
    main()
