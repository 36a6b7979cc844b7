#!/usr/bin/env python3
"""Draws shape.png from a softhd optimise output directory: the final deformed body
(body_final.ply) against the target cloud (target.ply): a side view on the two axes of\nlargest extent, and a 3D view."""
import os
import struct
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: E402
except ImportError:
    sys.exit(3)  # softhd optimise reports "needs python3-matplotlib" for exit status 3


def read_ply(path):
    """Reads the vertex x, y, z of a PLY written by softhd (ascii or binary double)."""
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline().decode("ascii").strip()
            header.append(line)
            if line == "end_header":
                break
        fmt = [h.split()[1] for h in header if h.startswith("format")][0]
        n = int([h.split()[2] for h in header if h.startswith("element vertex")][0])
        props = [h.split()[2] for h in header if h.startswith("property")]
        if fmt == "ascii":
            rows = [list(map(float, f.readline().split())) for _ in range(n)]
        else:
            rows = list(struct.iter_unpack("<" + "d" * len(props), f.read(8 * len(props) * n)))
    ix = props.index("x"), props.index("y"), props.index("z") if "z" in props else None
    return [[r[ix[0]] for r in rows], [r[ix[1]] for r in rows],
            [r[ix[2]] for r in rows] if ix[2] is not None else [0.0] * n]


def side_axes(body, target):
    """The two coordinate axes of the largest extent of body and target together: the
    view that shows the most of the shape (x1-x3 for a plate bending up, x1-x2 in 2D)."""
    extent = []
    for k in range(3):
        values = body[k] + target[k]
        extent.append(max(values) - min(values))
    first, second = sorted(sorted(range(3), key=lambda k: -extent[k])[:2])
    return first, second


def main(directory):
    body = read_ply(os.path.join(directory, "body_final.ply"))
    target = read_ply(os.path.join(directory, "target.ply"))
    h, v = side_axes(body, target)
    fig = plt.figure(figsize=(12, 5.4))
    side = fig.add_subplot(1, 2, 1)
    side.scatter(target[h], target[v], s=1, c="0.7", label="target cloud")
    side.scatter(body[h], body[v], s=2, c="C0", label="optimised body (nodes)")
    side.set_aspect("equal")
    side.set_xlabel("x%d" % (h + 1))
    side.set_ylabel("x%d" % (v + 1))
    side.set_title("side view")
    view = fig.add_subplot(1, 2, 2, projection="3d")
    view.scatter(target[0], target[1], target[2], s=0.5, c="0.7")
    view.scatter(body[0], body[1], body[2], s=1, c="C0")
    view.set_xlabel("x1")
    view.set_ylabel("x2")
    view.set_zlabel("x3")
    view.set_title("3D view")
    # The legend below the pictures, never on the data.
    fig.legend(*side.get_legend_handles_labels(), loc="lower center", ncol=2, markerscale=5)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    fig.savefig(os.path.join(directory, "shape.png"), dpi=110)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: plot_shape.py OUTPUT_DIR")
    main(sys.argv[1])
