#!/usr/bin/python3
"""Open3D's global registration as its documentation's tutorial sets it up (issue 32's peer):
voxel downsampling (voxel size v), normals (radius 2v, 30 neighbours), FPFH features
(radius 5v, 100 neighbours), RANSAC on feature matches (distance 1.5v, mutual filter off,
point-to-point estimation with 3 points, edge-length 0.9 and distance checkers, 100 000
iterations, confidence 0.999), then point-to-plane ICP (distance 0.4v) on the full clouds.

Module use: align(body, scan, voxel, seed) -> (4x4 pose taking the scan onto the body,
seconds). Command line: open3d_align.py BODY SCAN VOXEL OUT_POSE.txt (clouds as text or PLY).
"""
import sys
import time

import numpy as np


def _cloud(o3d, points):
    pc = o3d.geometry.PointCloud()
    pc.points = o3d.utility.Vector3dVector(np.asarray(points, dtype=np.float64))
    return pc


def _prepare(o3d, pc, voxel):
    down = pc.voxel_down_sample(voxel)
    down.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * voxel, max_nn=30))
    fpfh = o3d.pipelines.registration.compute_fpfh_feature(
        down, o3d.geometry.KDTreeSearchParamHybrid(radius=5 * voxel, max_nn=100))
    return down, fpfh


def align(body, scan, voxel, seed=0):
    import open3d as o3d
    reg = o3d.pipelines.registration
    o3d.utility.random.seed(seed)
    t0 = time.perf_counter()
    target, source = _cloud(o3d, body), _cloud(o3d, scan)
    tgt_down, tgt_f = _prepare(o3d, target, voxel)
    src_down, src_f = _prepare(o3d, source, voxel)
    dist = 1.5 * voxel
    ransac = reg.registration_ransac_based_on_feature_matching(
        src_down, tgt_down, src_f, tgt_f, False, dist,
        reg.TransformationEstimationPointToPoint(False), 3,
        [reg.CorrespondenceCheckerBasedOnEdgeLength(0.9),
         reg.CorrespondenceCheckerBasedOnDistance(dist)],
        reg.RANSACConvergenceCriteria(100000, 0.999))
    target.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * voxel, max_nn=30))
    icp = reg.registration_icp(source, target, 0.4 * voxel, ransac.transformation,
                               reg.TransformationEstimationPointToPlane())
    return np.asarray(icp.transformation), time.perf_counter() - t0


def main():
    if len(sys.argv) != 5:
        sys.exit("usage: open3d_align.py BODY SCAN VOXEL OUT_POSE.txt")
    sys.path.insert(0, "build/python")
    import softhd
    body, _ = softhd.read_cloud(sys.argv[1])
    scan, _ = softhd.read_cloud(sys.argv[2])
    pose, seconds = align(body, scan, float(sys.argv[3]))
    np.savetxt(sys.argv[4], pose, fmt="%.17g")
    print(f"open3d: {seconds:.3f} s")


if __name__ == "__main__":
    main()
