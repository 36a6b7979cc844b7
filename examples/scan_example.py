#!/usr/bin/env python3
"""A worked example (docs/guide.md, "Worked example: your own scan"): one synthetic depth view
of the bent finger, taken through clean-up, the pose from the fixture and a camera-frame
`optimise` to the recovered shape, with pictures.

    PYTHONPATH=build/python /usr/bin/python3 examples/scan_example.py [--out DIR]
        [--bend B] [--seed S] [--view full|half] [--noise F] [--outliers F]
        [--pose fixture|calibrated|align] [--calibration DEG FRAC] [--max-iter N] [--stages K]
        [--cap-factor F] [--clean-rms R] [--exact-rms R] [--figures DIR]

(`make example-scan` builds softhd and runs it with the defaults.)

1. The truth. The finger of data/scenes/finger.json bent by the control m*(X) = -B X3, solved
   on the 2x finer mesh of data/targets/finger_fine.json by `softhd forward` (for B = 1.5, the
   default, the repository's data/targets/finger_target.ply is that solve already).
2. The scan. softhd.synthetic views the deformed fine nodes from a random camera (seed
   S): only the visible points, Gaussian noise F L (L the body's size), outliers, a table
   plane under the finger; DIR/scan.ply is in the camera's frame, DIR/pose_true.txt the pose
   the example must recover (camera -> body).
3. Clean-up, in the camera's frame: the table (softhd.remove_dominant_plane, points within
   --plane x L of the dominant plane, default 0.03 = 6 times the noise's standard deviation:
   at 0.01 about 5 % of the table stays and pulls align off) and stray points
   (softhd.remove_statistical_outliers, k = 20, ratio 2): DIR/scan_clean.ply.
4. The pose's start. --pose fixture (the default): `softhd.align` against the body at rest
   with the fixture, the table under the finger known in the body's frame (where the
   synthetic view put it) and found in the scan by the clean-up, and the side of the image the
   clamped end is seen on (a user's "the clamp is on the left"): DIR/pose_fixture.txt, and the
   run keeps its tilt and height above the table. --pose calibrated: what a calibrated camera
   gives, here the true pose rotated by DEG degrees about a random axis through the body's
   centre and moved by FRAC L (--calibration, default 1 and 0.01): DIR/pose_calibrated.txt,
   given to the run with its uncertainty (DEG + 0.5 degrees, FRAC + 0.005 L). --pose align:
   `softhd align data/scenes/finger.json DIR/scan_clean.ply --distance scan_to_body` against
   the body at rest alone (on most views of a smooth body it lands far off). --align-only
   stops there and prints the start's error. The points the start pose puts outside the
   body's box inflated by --crop-margin (0.4) of its diagonal are dropped: DIR/scan_crop.ply,
   in the camera's frame.
5. The control, the pose refined by projection: DIR/scene.json is the finger's scene with the
   target
       {"kind": "cloud", "file": "scan_crop.ply", "frame": "camera", "pose": POSE,
        "pose_uncertainty": {...}, "distance": "visible", "surface": true,
        "weights": "delaunay", "cap": {"quantile": 0.9, "factor": F}}
   and softhd.optimise(..., pose_method="projection") runs it K times (stages) of N iterations,
   each stage from the last stage's control and pose, its cap re-made as F x the 90 % quantile
   of the scan's distances to that body.
6. The references, with the same budget: the run given the exact pose (the cropped scan moved
   into the body's frame by the true pose, the camera's position there; skipped with
   --exact-rms R) and the run against the clean, complete target in the body's frame (the fine
   solve's nodes; skipped with --clean-rms R); the node errors of all three against the true
   positions of the finger's nodes.
7. Pictures (matplotlib, Agg) in --figures (default DIR): scan_example_scan.png (the raw scan,
   camera frame), scan_example_aligned.png (the cleaned scan moved by the start pose, on the
   body at rest), scan_example_shape.png (the recovered body and the truth, coloured by the
   node error), scan_example_convergence.png (rho per iteration, pose error and node error
   per stage).

Prints the pose error (rotation in degrees, and the distance by which the pose misplaces the
scan's centroid) at the start and after every stage, and the node errors (max, rms, ratios to
the two references' rms). The numbers of the defaults are in docs/guide.md.
"""


import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
try:
    import softhd
    from softhd import synthetic
except ImportError:
    sys.exit("scan_example: cannot import softhd; run with PYTHONPATH=build/python "
             "(make example-scan builds it)")

FINGER = os.path.join(ROOT, "data/scenes/finger.json")
FINE = os.path.join(ROOT, "data/targets/finger_fine.json")
REPO_TARGET = os.path.join(ROOT, "data/targets/finger_target.ply")  # m* = -1.5 X3 on FINE


def log(text):
    print(text, flush=True)


def run(cmd):
    """A softhd command; its stderr (progress) is kept in the log, a failure ends the example."""
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"scan_example: {' '.join(cmd)} failed ({r.returncode}): {r.stderr.strip()}")
    return r.stdout


def true_deformation(softhd_bin, bend, out):
    """The fine mesh's deformed nodes (and deformed volumes) for m*(X) = -bend X3."""
    if bend == 1.5:
        return REPO_TARGET
    nodes_file, control_file = os.path.join(out, "fine_nodes.txt"), os.path.join(out, "m_star.txt")
    target = os.path.join(out, f"truth_{bend:g}.ply")
    if os.path.exists(target):  # made by an earlier run in the same --out
        return target
    run([softhd_bin, "forward", FINE, "--write-control-nodes", nodes_file])
    with open(nodes_file) as f, open(control_file, "w") as g:
        for line in f:  # x y z m: m* = -bend X3 (linear, so P1 controls hold it exactly)
            if line.startswith("#") or not line.split():
                continue
            x, y, z = line.split()[:3]
            g.write(f"{x} {y} {z} {-bend * float(z):.17g}\n")
    run([softhd_bin, "forward", FINE, "--control", control_file, "--out",
         os.path.join(out, "truth_run"), "--write-cloud", target])
    return target


def node_errors(nodes, displacements, truth):
    """Per-node |x + u - x_true|, with its max and rms."""
    e = np.linalg.norm(nodes + displacements - truth, axis=1)
    return e, float(e.max()), float(np.sqrt((e ** 2).mean()))


def pose_error(P, P_true, centre):
    """(rotation error in degrees, |P(c) - P_true(c)|): the angle of R R_trueᵀ, and how far P
    puts the camera-frame point c (the scan's centroid) from where the true pose puts it."""
    R, Rt = P[:3, :3], P_true[:3, :3]
    c = (np.trace(R @ Rt.T) - 1) / 2
    shift = np.linalg.norm(R @ centre + P[:3, 3] - Rt @ centre - P_true[:3, 3])
    return float(np.degrees(np.arccos(np.clip(c, -1, 1)))), float(shift)


def moved(P, points):
    return points @ P[:3, :3].T + P[:3, 3]


def finger_scene(path, description, target):
    with open(FINGER) as f:
        j = json.load(f)
    j["name"] = "finger_scan_example"
    j["description"] = description
    j["mesh"]["file"] = os.path.relpath(os.path.join(ROOT, "data/meshes/finger.msh"),
                                        os.path.dirname(path))
    j["target"] = target
    with open(path, "w") as f:
        json.dump(j, f, indent=1)
        f.write("\n")


def write_scene(path, scan_file, pose_file, uncertainty, fixture, cap):
    target = {"kind": "cloud", "file": os.path.basename(scan_file), "frame": "camera",
              "pose": os.path.relpath(pose_file, os.path.dirname(path)), "distance": "visible",
              "surface": True, "weights": "delaunay", "cap": cap}
    if uncertainty:
        target["pose_uncertainty"] = uncertainty
    if fixture:  # the projection keeps the start's tilt and height above the table
        target["fixture"] = {"normal": [float(x) for x in fixture[0]], "offset": float(fixture[1])}
    finger_scene(path, "examples/scan_example.py: the finger against one depth view in the "
                 "camera's frame, the pose refined by projection", target)


def staged_runs(a, scene_of, crop, P_start, rest, truth, log, label):
    """--stages optimise runs of --max-iter iterations, each from the last one's control (and
    pose), the cap re-made from the last state's distances; scene_of(k, cap, P) writes stage k's
    scene and returns its path and whether its target is in the camera's frame."""
    cap, control, P = {"quantile": 0.9, "factor": a.cap_factor}, None, P_start
    rhos, poses, rms = [], [], []
    for k in range(1, a.stages + 1):
        path, camera_frame = scene_of(k, cap, P)
        extra = {"pose_method": "projection"} if camera_frame else {}
        r = softhd.optimise(softhd.Scene.load(path), max_iter=a.max_iter, initial=control, **extra)
        control = r.control
        if camera_frame:
            P = r.pose
        _, e_max, e_rms = node_errors(rest, r.displacements, truth)
        rhos.append([h.rho for h in r.history])
        poses.append(P)
        rms.append(e_rms)
        log(f"{label} stage {k}: {r.iterations} iterations, {r.seconds:.1f} s, {r.termination}; "
            f"rho {r.rho_start:.4g} -> {r.rho_final:.4g}; node error max {e_max:.4g}, "
            f"rms {e_rms:.4g} mm")
        d = softhd.distance(rest + r.displacements, moved(P, crop), distance="scan_to_body",
                            fields=True)
        cap = a.cap_factor * float(np.quantile(d.field_target, 0.9))
    return r, rhos, poses, rms


def pictures(a, d):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rng = np.random.default_rng(0)

    def thin(n, k=2500):  # at most k of n points drawn, so that each PNG stays small
        return np.sort(rng.choice(n, min(n, k), replace=False))

    def axes3d(fig, pos, title):
        ax = fig.add_subplot(pos, projection="3d")
        ax.set_title(title, fontsize=9)
        ax.tick_params(labelsize=6)
        return ax

    def equal(ax, pts):
        lo, hi = pts.min(0), pts.max(0)
        mid, r = (lo + hi) / 2, (hi - lo).max() / 2
        ax.set_xlim(mid[0] - r, mid[0] + r)
        ax.set_ylim(mid[1] - r, mid[1] + r)
        ax.set_zlim(mid[2] - r, mid[2] + r)

    figs = {}
    # 1. The raw scan in the camera's frame, coloured by what the clean-up did with each point.
    fig = plt.figure(figsize=(5.2, 4.2), dpi=80)
    ax = axes3d(fig, 111, f"raw scan, camera frame ({len(d['scan'])} points)")
    for mask, colour, label in ((d["kept"], "tab:blue", "kept"),
                                (d["plane"], "tab:orange", "table plane removed"),
                                (d["stray"], "tab:red", "outlier filter removed"),
                                (d["cropped"], "tab:purple", "cropped with the start pose")):
        p = d["scan"][mask]
        if len(p):
            s = thin(len(p))
            ax.scatter(p[s, 0], p[s, 1], p[s, 2], s=1.5, c=colour, label=f"{label} ({len(p)})",
                       depthshade=False)
    ax.scatter([0], [0], [0], marker="^", c="k", s=30, label="camera")
    ax.view_init(elev=-60, azim=-90)
    ax.legend(fontsize=6, loc="upper left", markerscale=4)
    figs["scan"] = fig
    # 2. The cleaned, cropped scan moved by the start pose, on the body at rest.
    fig = plt.figure(figsize=(5.2, 4.2), dpi=80)
    ax = axes3d(fig, 111, f"scan at the start pose ({d['align_deg']:.1f}° off) on the body at rest")
    b, s = d["rest"], thin(len(d["rest"]), 1500)
    ax.scatter(b[s, 0], b[s, 1], b[s, 2], s=1, c="0.6", label="body at rest (nodes)",
               depthshade=False)
    p = d["aligned"]
    s = thin(len(p))
    ax.scatter(p[s, 0], p[s, 1], p[s, 2], s=1.5, c="tab:blue", label="scan, start pose",
               depthshade=False)
    p = moved(d["P_true"], d["crop"])
    ax.scatter(p[s, 0], p[s, 1], p[s, 2], s=1, c="tab:green", alpha=0.4,
               label="scan, true pose", depthshade=False)
    equal(ax, np.vstack([b, d["aligned"]]))
    ax.view_init(elev=15, azim=-70)
    ax.legend(fontsize=6, loc="upper left", markerscale=4)
    figs["aligned"] = fig
    # 3. The recovered body against the truth, coloured by the node error.
    fig = plt.figure(figsize=(5.2, 4.2), dpi=80)
    ax = axes3d(fig, 111, f"recovered body, node error rms {d['rms']:.3g} "
                          f"({d['rms'] / d['clean_rms']:.0f}x the clean run's)")
    t, r, e = d["truth"], d["recovered"], d["errors"]
    s = thin(len(t), 1500)
    ax.scatter(t[s, 0], t[s, 1], t[s, 2], s=1, c="0.7", label="true deformed body",
               depthshade=False)
    sc = ax.scatter(r[s, 0], r[s, 1], r[s, 2], s=2, c=e[s], cmap="viridis", vmin=0,
                    label="recovered body", depthshade=False)
    cb = fig.colorbar(sc, ax=ax, shrink=0.6, pad=0.1)
    cb.set_label("node error (mm)", fontsize=7)
    cb.ax.tick_params(labelsize=6)
    equal(ax, np.vstack([t, r, d["rest"]]))
    ax.view_init(elev=15, azim=-70)
    ax.legend(fontsize=6, loc="upper left", markerscale=4)
    figs["shape"] = fig
    # 4. Convergence: rho per iteration over the stages; pose and node errors per stage.
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(7.5, 3.0), dpi=80)
    start = 0
    for k, rho in enumerate(d["rho"]):
        it = np.arange(start, start + len(rho))
        a1.plot(it, rho, lw=1, label=f"stage {k + 1}" if len(d["rho"]) <= 8 else None)
        start += len(rho)
    a1.set_xlabel("iteration (all stages)", fontsize=8)
    a1.set_ylabel("rho (the stage's cap)", fontsize=8)
    a1.tick_params(labelsize=7)
    if len(d["rho"]) <= 8:
        a1.legend(fontsize=6)
    stages = np.arange(len(d["stage_deg"]))
    a2.plot(stages, d["stage_deg"], "o-", c="tab:red", label="pose error (degrees)")
    a2.set_xlabel("stage (0: the start pose)", fontsize=8)
    a2.set_xticks(stages)
    a2.set_ylabel("rotation error (degrees)", fontsize=8, color="tab:red")
    a2.tick_params(labelsize=7)
    a3 = a2.twinx()
    a3.plot(stages, np.array(d["stage_rms"]) / d["clean_rms"], "s-", c="tab:blue")
    a3.set_ylabel("node rms / clean run's", fontsize=8, color="tab:blue")
    a3.tick_params(labelsize=7)
    fig.tight_layout()
    figs["convergence"] = fig
    os.makedirs(a.figures, exist_ok=True)
    for name, fig in figs.items():
        path = os.path.join(a.figures, f"scan_example_{name}.png")
        fig.savefig(path, dpi=80)
        plt.close(fig)
        log(f"picture: {path} ({os.path.getsize(path) // 1024} KB)")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--out", default="results/scan_example", help="the run's files")
    ap.add_argument("--figures", default=None, help="where the PNGs go (default: --out)")
    ap.add_argument("--softhd", default=os.path.join(ROOT, "build/apps/softhd"),
                    help="the softhd tool (default build/apps/softhd)")
    ap.add_argument("--bend", type=float, default=1.5,
                    help="the true control m* = -B X3 (default 1.5, the finger scene's target)")
    ap.add_argument("--seed", type=int, default=1, help="the camera's seed (default 1)")
    ap.add_argument("--view", choices=["full", "half"], default="full")
    ap.add_argument("--noise", type=float, default=0.005, help="fraction of L (default 0.005)")
    ap.add_argument("--outliers", type=float, default=0.03,
                    help="outliers as a fraction of the visible points (default 0.03)")
    ap.add_argument("--plane", type=float, default=0.03,
                    help="clean-up: the table plane's distance as a fraction of L (default 0.03)")
    ap.add_argument("--pose", choices=["fixture", "calibrated", "align"], default="fixture",
                    help="the pose's start: align with the fixture (the table under the finger "
                         "and the clamp's side; default), a calibrated camera's (the true pose "
                         "off by --calibration) or align's against the body at rest alone")
    ap.add_argument("--calibration", type=float, nargs=2, default=[1.0, 0.01],
                    metavar=("DEG", "FRAC"),
                    help="--pose calibrated: the calibration's error, a rotation in degrees and "
                         "a shift as a fraction of L (default 1 0.01)")
    ap.add_argument("--crop-margin", type=float, default=0.4,
                    help="the crop with the start pose: the body's box inflated by this fraction "
                         "of its diagonal (default 0.4: it must cover the deformation; at 0.1 the "
                         "bent tip was cut off)")
    ap.add_argument("--align-only", action="store_true",
                    help="stop after the start pose (prints its error)")
    ap.add_argument("--max-iter", type=int, default=40, help="iterations per stage (default 40)")
    ap.add_argument("--stages", type=int, default=1,
                    help="optimise runs, each from the last one's control and pose, the cap "
                         "re-made (default 1)")
    ap.add_argument("--cap-factor", type=float, default=1.0,
                    help="the cap: this times the 90 %% quantile of the scan's distances to the "
                         "body (default 1)")
    ap.add_argument("--clean-rms", type=float, default=None,
                    help="the clean run's node error rms from an earlier run (skips that run)")
    ap.add_argument("--exact-rms", type=float, default=None,
                    help="the exact-pose run's node error rms from an earlier run (skips it)")
    ap.add_argument("--no-pictures", action="store_true")
    a = ap.parse_args()
    a.figures = a.figures or a.out
    if not os.access(a.softhd, os.X_OK):
        sys.exit(f"scan_example: no softhd tool at '{a.softhd}' (make example-scan builds it, "
                 "or give --softhd)")
    if a.stages < 1 or a.max_iter < 1 or not a.cap_factor > 0:
        sys.exit("scan_example: --stages and --max-iter must be >= 1, --cap-factor > 0")
    if not (a.calibration[0] >= 0 and a.calibration[1] >= 0):
        sys.exit("scan_example: --calibration DEG FRAC must be >= 0")
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    t0 = time.time()

    # 1. The truth.
    scene = softhd.Scene.load(FINGER)
    rest = scene.mesh.nodes
    truth_file = true_deformation(a.softhd, a.bend, out)
    fine_deformed, _ = softhd.read_cloud(truth_file)
    fine_mesh = softhd.read_mesh(os.path.join(ROOT, "data/meshes/finger_fine.msh"), order=2)
    fine_rest = fine_mesh.nodes
    truth = synthetic.matched_nodes(rest, fine_rest, fine_deformed)
    L = float(np.linalg.norm(rest.max(0) - rest.min(0)))  # what a user knows: the body at rest
    log(f"truth: m* = -{a.bend:g} X3 on the fine mesh ({truth_file}); the tip moves "
        f"{np.linalg.norm(truth - rest, axis=1).max():.3g} mm; L = {L:.4g} mm")

    # 2. The scan, in the camera's frame.
    scan, P_true, info = synthetic.view(fine_deformed, fine_mesh.boundary_triangles, a.seed,
                                        a.view, noise=a.noise, outliers=a.outliers, table=True)
    softhd.write_cloud(os.path.join(out, "scan.ply"), scan)
    np.savetxt(os.path.join(out, "pose_true.txt"), P_true, fmt="%.17g")
    log(f"scan: {len(scan)} points in the camera's frame ({info['kept'] - info['table']} on the "
        f"body, {info['table']} on the table, {info['outliers']} outliers): {out}/scan.ply")

    # 3. Clean-up in the camera's frame.
    table = softhd.find_dominant_plane(scan, distance=a.plane * L)  # for the fixture
    off_plane = softhd.remove_dominant_plane(scan, distance=a.plane * L)
    inliers = off_plane[softhd.remove_statistical_outliers(scan[off_plane], k=20, ratio=2.0)]
    clean = scan[inliers]
    clean_file = os.path.join(out, "scan_clean.ply")
    softhd.write_cloud(clean_file, clean)
    log(f"clean-up: the plane removed {len(scan) - len(off_plane)}, the outlier filter "
        f"{len(off_plane) - len(inliers)}; {len(clean)} left")

    # 4. The pose's start, then the crop with it.
    centre = clean.mean(0)
    uncertainty, fixture = None, None
    if a.pose == "fixture":
        # What the user knows of the bench: the table in the body's frame (here where the
        # synthetic view put it) and on which side of the image the clamped end is seen.
        fixture = synthetic.table_plane(fine_deformed)
        seen = P_true[:3, :3].T @ np.array([-1.0, 0.0, 0.0])  # the base (x = 0) from the centre
        k = int(np.argmax(np.abs(seen[:2])))
        hint = np.zeros(3)
        hint[k] = np.sign(seen[k])
        fit = softhd.align(rest, clean, distance="scan_to_body", fixture=fixture, table=table,
                           clamp=(np.array([-1.0, 0.0, 0.0]), hint))
        P0, start_label = np.array(fit["matrix"]), "fixture"
        pose_file = os.path.join(out, "pose_fixture.txt")
        np.savetxt(pose_file, P0, fmt="%.17g")
        log(f"align with the fixture (the table {fixture[0].tolist()}, offset {fixture[1]:.4g}; "
            f"the clamp seen towards {hint.tolist()}): {fit['status']}, overlap "
            f"{fit['overlap']:.3f}")
    elif a.pose == "calibrated":
        deg_c, frac_c = a.calibration
        P0 = synthetic.perturbed_pose(P_true, centre, L, a.seed, deg_c, frac_c)
        pose_file = os.path.join(out, "pose_calibrated.txt")
        np.savetxt(pose_file, P0, fmt="%.17g")
        uncertainty = {"degrees": deg_c + 0.5, "length": (frac_c + 0.005) * L}
        start_label = "calibrated"
        log(f"calibrated pose: the true one off by {deg_c:g} deg and {frac_c:g} L; the run's "
            f"uncertainty {uncertainty['degrees']:g} deg, {uncertainty['length']:.3g} mm")
    else:
        align_dir = os.path.join(out, "align")
        run([a.softhd, "align", FINGER, clean_file, "--distance", "scan_to_body", "--out",
             align_dir])
        with open(os.path.join(align_dir, "pose.json")) as f:
            aligned = json.load(f)
        P0, pose_file, start_label = np.array(aligned["matrix"]), os.path.join(align_dir,
                                                                               "pose.txt"), "align"
        log(f"align: {aligned['status']}, overlap {aligned['overlap']:.3f}, rmse "
            f"{aligned['rmse']:.3g}")
    deg0, shift0 = pose_error(P0, P_true, centre)
    log(f"start pose ({start_label}): {deg0:.2f} deg off, {shift0:.3g} mm at the scan's centroid "
        f"({shift0 / L:.3g} L)")
    if a.align_only:
        return
    inside = softhd.crop_to_box(moved(P0, clean), rest.min(0), rest.max(0), margin=a.crop_margin)
    crop = clean[inside]
    crop_file = os.path.join(out, "scan_crop.ply")
    softhd.write_cloud(crop_file, crop)
    log(f"crop (body's box + {a.crop_margin:g} of its diagonal, the start pose): kept "
        f"{len(crop)} of {len(clean)}")

    # 5. The control, the pose refined by projection, in stages.
    def camera_scene(k, cap, P):
        path = os.path.join(out, "scene.json" if k == 1 else f"stage_{k}.json")
        pose_k = pose_file
        if k > 1:  # the last stage's pose (the uncertainty's bound is then about it)
            pose_k = os.path.join(out, f"pose_{k - 1}.txt")
            np.savetxt(pose_k, P, fmt="%.17g")
        write_scene(path, crop_file, pose_k, uncertainty, fixture, cap)
        return path, True

    r, rho, poses, stage_rms = staged_runs(a, camera_scene, crop, P0, rest, truth, log, "scan")
    stage_deg = [deg0] + [pose_error(P, P_true, centre)[0] for P in poses]
    stage_rms = [node_errors(rest, 0 * rest, truth)[2]] + stage_rms
    P, u = poses[-1], r.displacements
    deg, shift = pose_error(P, P_true, centre)
    softhd.write_cloud(os.path.join(out, "body_recovered.ply"), rest + u)
    softhd.write_cloud(os.path.join(out, "scan_final_pose.ply"), moved(P, crop))

    # 6. The references: the exact pose (the data term alone), and the clean, complete target.
    if a.exact_rms is None:
        exact_file = os.path.join(out, "scan_body_frame.ply")
        softhd.write_cloud(exact_file, moved(P_true, crop))

        def exact_scene(k, cap, _P):
            path = os.path.join(out, f"exact_{k}.json")
            finger_scene(path, "examples/scan_example.py: the cropped scan moved by the true "
                         "pose, the camera's position in the body's frame",
                         {"kind": "cloud", "file": os.path.basename(exact_file),
                          "surface": True, "weights": "delaunay", "cap": cap,
                          "camera": [float(x) for x in P_true[:3, 3]]})
            return path, False

        x_rms = staged_runs(a, exact_scene, crop, P_true, rest, truth, log, "exact pose")[3][-1]
    else:
        x_rms = a.exact_rms
        log(f"exact-pose run: rms {x_rms:.4g} given (--exact-rms)")
    if a.clean_rms is None:
        c = softhd.optimise(scene, truth_file, max_iter=a.max_iter * a.stages)
        _, c_max, c_rms = node_errors(rest, c.displacements, truth)
        log(f"clean run (the fine solve's nodes, body frame): {c.iterations} iterations, "
            f"{c.seconds:.1f} s; node error max {c_max:.4g}, rms {c_rms:.4g} mm")
    else:
        c_rms = a.clean_rms
        log(f"clean run: rms {c_rms:.4g} given (--clean-rms)")
    errors, e_max, e_rms = node_errors(rest, u, truth)
    log("")
    log(f"pose error: start {deg0:.2f} deg, final {deg:.2f} deg, {shift:.3g} mm "
        f"({shift / L:.3g} L) at the scan's centroid")
    log(f"node error rms: at rest {stage_rms[0]:.4g}, recovered {e_rms:.4g} mm (max {e_max:.4g}; "
        f"{e_rms / L:.3%} of L); given the exact pose {x_rms:.4g} ({e_rms / x_rms:.2f}x); the "
        f"clean, complete target {c_rms:.4g} ({e_rms / c_rms:.1f}x)")
    log(f"total {time.time() - t0:.0f} s")

    if not a.no_pictures:
        pictures(a, dict(scan=scan, kept=_mask(len(scan), inliers[inside]),
                         plane=~_mask(len(scan), off_plane),
                         stray=_mask(len(scan), off_plane) & ~_mask(len(scan), inliers),
                         cropped=_mask(len(scan), np.delete(inliers, inside)),
                         rest=rest, aligned=moved(P0, crop), crop=crop, P_true=P_true,
                         align_deg=deg0, truth=truth, recovered=rest + u, errors=errors,
                         rms=e_rms, clean_rms=c_rms, rho=rho, stage_deg=stage_deg,
                         stage_rms=stage_rms))


def _mask(n, idx):
    m = np.zeros(n, bool)
    m[idx] = True
    return m


if __name__ == "__main__":
    main()
