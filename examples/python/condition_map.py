#!/usr/bin/env python3
"""A parameter sweep of the mass matrix's condition number, drawn as a map (Fig. 4.7 widened).

    python3 examples/python/condition_map.py [OUT_DIR]

Two squash modes on the table: the vertical squash and one at angle φ (Fig. 4.7). The map
sweeps the distance δ = 90° − φ (log scale) against the squash's expansion ratio (the
sideways bulge per unit of compression) and colours log10 cond(M): as δ → 0 the two modes
become one and cond grows as 1/δ² (ten times closer, a hundred times worse). At δ = 90°
(φ = 0) with ratio 1 the two squashes are each other's negative, so M is singular there too
(the white corner). Writes
OUT_DIR/condition_map.png.
"""
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import wobble  # noqa: E402

DATA = pathlib.Path(__file__).resolve().parents[2] / "data"


def main(out_dir):
    delta_deg = np.logspace(-3, np.log10(90), 160)
    phis = np.radians(90 - delta_deg)
    expands = np.linspace(0.0, 1.0, 41)
    cond = np.array([wobble.angle_sweep(str(DATA / "table.obj"), phis, expand=e)[0] for e in expands])

    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=120)
    image = ax.pcolormesh(delta_deg, expands, np.log10(cond), shading="auto", cmap="viridis")
    fig.colorbar(image, ax=ax, label="log10 cond(M)")
    ax.set_xscale("log")
    ax.set_xlabel("δ = 90° − φ: how far the second squash is from the vertical one (degrees)")
    ax.set_ylabel("expansion ratio of the squash")
    ax.set_title("Condition number of the table's mass matrix (at rest)")
    fig.tight_layout()
    out = pathlib.Path(out_dir) / "condition_map.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    print(f"cond(M) from {cond.min():.3g} to {cond.max():.3g} over {cond.size} samples")
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "out/examples")
