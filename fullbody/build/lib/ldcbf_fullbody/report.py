"""What a run writes: ``summary.json``, ``steps.csv`` (one row per landed
footstep) and ``run.png`` (top view: the map, the footprints, the CoM's and
some links' paths)."""

import csv
import dataclasses
import json
import math
import pathlib
from typing import Any, Dict

import numpy as np


def write(result: Dict[str, Any], out: pathlib.Path, config: Dict[str, Any]) -> None:
    """Writes the three files into ``out`` (created if missing)."""
    out.mkdir(parents=True, exist_ok=True)
    summary = dict(result["summary"])
    summary["config"] = config
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    with open(out / "steps.csv", "w", newline="") as f:
        fields = [fl.name for fl in dataclasses.fields(result["steps"][0])] if result["steps"] else ["index"]
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for s in result["steps"]:
            w.writerow(dataclasses.asdict(s))
    picture(result, out / "run.png", config)


def picture(result: Dict[str, Any], path: pathlib.Path, config: Dict[str, Any]) -> None:
    """The top view (matplotlib, Agg)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon, Rectangle

    fig, ax = plt.subplots(figsize=(7, 7))
    for poly in result["obstacles"]:
        ax.add_patch(Polygon(poly, closed=True, color="0.55", alpha=0.8))
    L, W = config["foot_length"], config["foot_width"]
    for s in result["steps"]:
        c, sn = math.cos(s.landed_yaw), math.sin(s.landed_yaw)
        corner = np.array([s.landed_x, s.landed_y]) - np.array([c * L / 2 - sn * W / 2, sn * L / 2 + c * W / 2])
        color = "tab:blue" if s.side == "left" else "tab:red"
        ax.add_patch(Rectangle(corner, L, W, angle=math.degrees(s.landed_yaw), fill=False, color=color, lw=0.8))
        ax.plot([s.planned_x], [s.planned_y], "k.", ms=2)
    samples = result["samples"]
    if samples["com"]:
        com = np.array(samples["com"])
        ax.plot(com[:, 0], com[:, 1], "k-", lw=1.2, label="CoM")
        links = np.array(samples["links"])
        for i, name in enumerate(result["tracked"]):
            if "wrist" in name or "knee" in name:
                ax.plot(links[:, i, 0], links[:, i, 1], lw=0.6, alpha=0.7, label=name)
    ax.plot(*result["start"], "go", label="start")
    ax.plot(*result["goal"], "g*", ms=12, label="goal")
    s = result["summary"]
    ax.set_title(
        f"{s['scenario']}: G1 in MuJoCo, reached={s['reached_goal']}, falls={s['falls']}, "
        f"link contacts={s['link_contacts']}",
        fontsize=9,
    )
    ax.set_aspect("equal")
    ax.legend(fontsize=7, loc="best")
    ax.grid(alpha=0.3)
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)

