"""Plots of the driving evaluation (docs/driving.md): the cumulative
histogram of the deviation from the ideal path in the paper's 5 cm bins,
and each run's trajectory over its route's ideal path on the 2D map.
Needs matplotlib (python3-matplotlib)."""

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402



def histogram(report: dict, path: str, title: str = "") -> None:
    """Fraction of time within each distance of the ideal path, overall and per surroundings."""
    edges = [100.0 * e for e in report["histogram_edges_m"]]
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for key, fractions in sorted(report["histogram"].items()):
        ax.step(edges, fractions, where="post", label=key)
    ax.set_xlabel("distance to the ideal path (cm)")
    ax.set_ylabel("fraction of time within")
    ax.set_ylim(0, 1.02)
    ax.set_xlim(0, edges[-1])
    ax.grid(alpha=0.3)
    ax.legend()
    ax.set_title(title or "cumulative histogram, 5 cm bins (%s policy)" % report["settings"]["policy"])
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def trajectories(runs: dict, folder: str) -> None:
    """One PNG per map: the ideal path (grey) and the car's trajectory
    (coloured by deviation) and any obstacles (red). runs: {(map, route):
    (ideal path (driving_obstacles.ShiftedPath), route, rows)}."""
    os.makedirs(folder, exist_ok=True)
    by_map = {}
    for (name, route), entry in runs.items():
        by_map.setdefault(name, []).append(entry)
    for name, entries in by_map.items():
        fig, ax = plt.subplots(figsize=(6.0, 6.0))
        for path, route, rows in entries:
            ideal = [path.point(0.5 * i)[:2] for i in range(int(path.length / 0.5) + 1)]
            for ox, oy, _ in path.obstacle_poses():
                ax.plot([ox], [oy], "s", color="red", ms=5, zorder=4)
            ax.plot([p[0] for p in ideal], [p[1] for p in ideal], color="0.7", lw=3, label="ideal path (%s)" % route)
            sc = ax.scatter([r[1] for r in rows], [r[2] for r in rows], c=[abs(r[5]) * 100 for r in rows], s=2,
                            cmap="viridis", vmin=0, vmax=100, zorder=3)
        fig.colorbar(sc, ax=ax, label="deviation (cm)", shrink=0.8)
        ax.set_aspect("equal")
        ax.set_title(name)
        ax.legend(loc="upper right", fontsize=7)
        fig.tight_layout()
        fig.savefig(os.path.join(folder, name + ".png"), dpi=90)
        plt.close(fig)
