#!/usr/bin/env python3
"""Fit the table's pose to points clicked on a picture of a deformed table.

    python3 examples/python/fit_clicked_points.py [OUT_DIR] [--click]

The picture is the table drawn at a pose the example makes up (a crouch: bent, squashed,
tilted). With --click (and a display) you click the 5 top points and the 2 feet, left to
right, on it; without, the clicks are the true points with a few pixels of hand jitter. The
fit (wobble.fit_pose, Ceres) then recovers the pose; OUT_DIR/fit_clicked_points.png shows the
picture, the clicks and the fitted outline.
"""
import pathlib
import sys

import matplotlib
import numpy as np

CLICK = "--click" in sys.argv
if not CLICK:
    matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import wobble  # noqa: E402

DATA = pathlib.Path(__file__).resolve().parents[2] / "data"
# the mass points to click: the top's five, then the left and the right foot (data/table.obj)
CLICKED = [0, 1, 2, 3, 4, 5, 8]


def main(out_dir):
    table = wobble.load_body(str(DATA / "table.obj"), [str(DATA / "table_modes.def")])
    truth = np.array([20.0, 5.0, np.radians(6), 0.35, -0.1, 0.3, 0.15])  # bend, shear, vsquash, hsquash
    world = wobble.World()
    world.add_body(table)
    world.set_state(0, truth)
    true_points = world.point_positions(0)[CLICKED]

    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=120)
    for line in table.outline(truth):
        ax.plot(line[:, 0], line[:, 1], color="0.6", linewidth=6, solid_capstyle="round")
    ax.set_aspect("equal")
    drawn = np.vstack(table.outline(truth))
    ax.set_xlim(drawn[:, 0].min() - 40, drawn[:, 0].max() + 40)
    ax.set_ylim(drawn[:, 1].min() - 40, drawn[:, 1].max() + 60)
    if CLICK:
        ax.set_title("click the 5 top points, then the left foot and the right foot")
        clicks = np.array(plt.ginput(len(CLICKED), timeout=0))
    else:
        clicks = true_points + np.random.default_rng(4).normal(0, 1.5, true_points.shape)

    fit = wobble.fit_pose(table, clicks, mass_points=CLICKED)
    for i, line in enumerate(table.outline(fit.q)):
        ax.plot(line[:, 0], line[:, 1], color="tab:blue", linewidth=1.5, label="fitted" if i == 0 else None)
    ax.plot(clicks[:, 0], clicks[:, 1], "x", color="tab:red", markersize=8, label="clicks")
    ax.set_title(f"fitted pose: rms residual {fit.rms_residual:.2f}")
    ax.legend(loc="upper right")
    fig.tight_layout()
    out = pathlib.Path(out_dir) / "fit_clicked_points.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)

    names = ["tx", "ty", "theta"] + table.mode_names
    for name, got, want in zip(names, fit.q, truth):
        print(f"{name:>8}: fitted {got:9.4f}   drawn {want:9.4f}")
    print(f"{fit.report.termination} after {fit.report.iterations} iterations; "
          f"undetermined modes: {fit.conditioning.undetermined or 'none'}")
    print(f"wrote {out}")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    main(args[0] if args else "out/examples")
