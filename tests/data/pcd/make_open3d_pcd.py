#!/usr/bin/python3
"""Writes the Open3D PCD files the reader tests read back (run once; the files are committed).

open3d_{ascii,binary,compressed}.pcd: 40 points with colours and normals as Open3D writes
them; open3d_points.txt: their x y z as the exact doubles of the float32 values in the files.
"""
import pathlib

import numpy as np
import open3d as o3d

here = pathlib.Path(__file__).resolve().parent
rng = np.random.default_rng(32)
points = rng.uniform(-2.0, 3.0, size=(40, 3))
cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
cloud.colors = o3d.utility.Vector3dVector(rng.uniform(0.0, 1.0, size=(40, 3)))
cloud.normals = o3d.utility.Vector3dVector(rng.normal(size=(40, 3)))
for name, ascii, compressed in [("ascii", True, False), ("binary", False, False),
                                ("compressed", False, True)]:
    o3d.io.write_point_cloud(str(here / f"open3d_{name}.pcd"), cloud, write_ascii=ascii,
                             compressed=compressed)
# Open3D stores x y z as float32 (F 4): the expected values are those floats, exactly.
stored = points.astype(np.float32).astype(np.float64)
with open(here / "open3d_points.txt", "w") as f:
    f.write("# x y z of open3d_*.pcd (float32 values written exactly)\n")
    for p in stored:
        f.write(" ".join(repr(float(v)) for v in p) + "\n")
