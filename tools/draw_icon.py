"""Draws the FMU's icon: the quarter car with its annular absorber and the
delayed feedback u = g x_t(t - tau).

    python tools/draw_icon.py [OUT.png]     (default fmu-build/assets/icon.png)

The body m_s rests on the annular absorber m_h through k_s and c_s, the
absorber on the wheel m_t through k_h and c_h, the wheel on the road x_g
through the tire spring k_t. The actuator between absorber and wheel applies
u = g x_t(t - tau): the wheel displacement x_t, delayed by tau and
multiplied by g.

fmu-build packs the committed picture as `model.png` (FMI 2.0),
`terminalsAndIcons/icon.png` (FMI 3.0) and `documentation/diagram.png` of
both FMUs. The output is deterministic for a given matplotlib (no time
stamp, no software tag): run it again after changing the drawing and commit
the picture.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import FancyArrowPatch, Rectangle  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_OUT = ROOT / "fmu-build" / "assets" / "icon.png"
SIZE_PX = 320
DPI = 100
INK = "#1b1b1b"
BODY = "#9ec5e8"
ABSORBER = "#f2c57c"
WHEEL = "#8f8f8f"
FEEDBACK = "#c0392b"
LINE = 1.2


def spring(ax, x, y0, y1, turns=4, width=0.32):
    """A zigzag spring from (x, y0) to (x, y1)."""
    lead = 0.18 * (y1 - y0)
    ys = [y0, y0 + lead]
    xs = [x, x]
    step = (y1 - y0 - 2 * lead) / (2 * turns)
    for i in range(2 * turns):
        ys.append(y0 + lead + (i + 0.5) * step)
        xs.append(x + (width if i % 2 == 0 else -width))
    ys += [y1 - lead, y1]
    xs += [x, x]
    ax.plot(xs, ys, color=INK, lw=LINE, solid_joinstyle="miter")


def damper(ax, x, y0, y1, width=0.3):
    """A dashpot from (x, y0) to (x, y1): a cylinder open at the top and a
    piston on a rod."""
    mid = (y0 + y1) / 2
    ax.plot([x, x], [y0, mid - 0.25], color=INK, lw=LINE)
    ax.plot([x - width, x - width, x + width, x + width],
            [mid + 0.3, mid - 0.25, mid - 0.25, mid + 0.3], color=INK, lw=LINE)
    ax.plot([x - width * 0.7, x + width * 0.7], [mid + 0.05, mid + 0.05], color=INK, lw=LINE * 1.6)
    ax.plot([x, x], [mid + 0.05, y1], color=INK, lw=LINE)


def actuator(ax, x, y0, y1, width=0.3):
    """The control force between two masses: a box with arrows both ways."""
    mid = (y0 + y1) / 2
    ax.plot([x, x], [y0, mid - 0.32], color=FEEDBACK, lw=LINE)
    ax.plot([x, x], [mid + 0.32, y1], color=FEEDBACK, lw=LINE)
    ax.add_patch(Rectangle((x - width, mid - 0.32), 2 * width, 0.64, facecolor="white",
                           edgecolor=FEEDBACK, lw=LINE))
    ax.text(x, mid, "$u$", ha="center", va="center", fontsize=9, color=FEEDBACK)


def mass(ax, x0, x1, y0, y1, color, label, hollow=False):
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor=color, edgecolor=INK, lw=LINE))
    if hollow:  # the annular absorber: a ring around the suspension
        inset = 0.22
        ax.add_patch(Rectangle((x0 + inset, y0 + inset), x1 - x0 - 2 * inset, y1 - y0 - 2 * inset,
                               facecolor="white", edgecolor=INK, lw=LINE * 0.8))
    ax.text((x0 + x1) / 2, (y0 + y1) / 2, label, ha="center", va="center", fontsize=10, color=INK)


def up_arrow(ax, x, y, label, color=INK):
    ax.add_patch(FancyArrowPatch((x, y - 0.45), (x, y + 0.45), arrowstyle="-|>", mutation_scale=8,
                                 color=color, lw=LINE))
    ax.text(x - 0.12, y, label, ha="right", va="center", fontsize=9, color=color)


def draw(out: Path) -> None:
    inches = SIZE_PX / DPI
    fig = plt.figure(figsize=(inches, inches), dpi=DPI)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_xlim(-0.3, 9.7)
    ax.set_ylim(0, 10)
    ax.set_aspect("equal")
    ax.axis("off")

    # The road and the ground under it.
    xs = [1.2 + 0.05 * i for i in range(101)]
    ys = [0.75 + 0.12 * math.sin(2 * math.pi * (x - 1.2) / 2.5) for x in xs]
    ax.fill_between(xs, [0.2] * len(xs), ys, color="#d9d9d9", lw=0)
    ax.plot(xs, ys, color=INK, lw=LINE)
    up_arrow(ax, 1.0, 1.0, "$x_g$")

    # Wheel on the tire spring.
    spring(ax, 3.5, 0.85, 2.0)
    ax.text(3.95, 1.42, "$k_t$", ha="left", va="center", fontsize=9)
    mass(ax, 2.1, 4.9, 2.0, 2.9, WHEEL, "$m_t$")
    up_arrow(ax, 1.75, 2.45, "$x_t$")

    # Absorber on the wheel: k_h, c_h and the actuator.
    spring(ax, 2.55, 2.9, 4.3, turns=3, width=0.25)
    ax.text(2.15, 3.6, "$k_h$", ha="right", va="center", fontsize=9)
    damper(ax, 3.4, 2.9, 4.3, width=0.25)
    ax.text(3.7, 3.6, "$c_h$", ha="left", va="center", fontsize=9)
    actuator(ax, 4.62, 2.9, 4.3, width=0.22)
    mass(ax, 1.7, 5.3, 4.3, 5.3, ABSORBER, "$m_h$", hollow=True)
    up_arrow(ax, 1.35, 4.8, "$x_h$")

    # Body on the absorber: k_s, c_s.
    spring(ax, 2.7, 5.3, 6.7, turns=3, width=0.25)
    ax.text(2.3, 6.0, "$k_s$", ha="right", va="center", fontsize=9)
    damper(ax, 4.3, 5.3, 6.7, width=0.25)
    ax.text(4.65, 6.0, "$c_s$", ha="left", va="center", fontsize=9)
    mass(ax, 1.4, 5.6, 6.7, 7.9, BODY, "$m_s$")
    up_arrow(ax, 1.05, 7.3, "$x_s$")

    # The delayed feedback: x_t -> delay tau, gain g -> actuator.
    ax.plot([4.9, 7.6, 7.6], [2.45, 2.45, 3.05], color=FEEDBACK, lw=LINE)
    ax.add_patch(Rectangle((6.55, 3.05), 2.1, 1.0, facecolor="white", edgecolor=FEEDBACK, lw=LINE))
    ax.text(7.6, 3.55, r"$g\,e^{-\tau s}$", ha="center", va="center", fontsize=10, color=FEEDBACK)
    ax.add_patch(FancyArrowPatch((6.55, 3.6), (4.84, 3.6), arrowstyle="-|>", mutation_scale=8, shrinkA=0,
                                 shrinkB=0, color=FEEDBACK, lw=LINE))
    ax.text(5.9, 2.2, "$x_t$", ha="center", va="top", fontsize=9, color=FEEDBACK)
    ax.text(5.3, 9.0, r"$u = g\,x_t(t-\tau)$", ha="center", va="center", fontsize=11, color=FEEDBACK)

    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=DPI, metadata={"Software": None})
    plt.close(fig)


def main(argv: list[str]) -> int:
    out = Path(argv[1]) if len(argv) > 1 else DEFAULT_OUT
    draw(out)
    print(f"wrote {out} ({out.stat().st_size} bytes, {SIZE_PX} x {SIZE_PX} px)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
