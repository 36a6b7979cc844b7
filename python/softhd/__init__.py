"""softhd: the regularised Hausdorff distance between point clouds, and shape-tracking optimal
control of soft bodies with it (docs/formulation.md). NumPy arrays in and out.

Arrays
------
Points are (N, d) arrays (d = 2 or 3), volumes (N,) arrays (None: all 1). An input that is
already a C-contiguous ``float64`` NumPy array (or anything exposing one, e.g. a contiguous
float64 CPU tensor through ``numpy.asarray``) is passed to the library **without a copy**: the
library reads the caller's memory in place. Any other input whose values are real numbers
(integer or floating arrays of another precision, non-contiguous arrays, nested lists) is
converted once with ``numpy.ascontiguousarray(x, dtype=numpy.float64)``; ``float128`` rounds to
double. Boolean, complex, object and string data raise ``TypeError``.

Errors
------
Every error of the library is a ``softhd.Error``: ``softhd.InvalidArgument`` (also a
``ValueError``) for arguments outside their range, ``softhd.FileError`` (also an ``OSError``)
for files, ``softhd.ResourceError`` and ``softhd.NumericalError``. The message is the C++ one.

Threads
-------
Computations release the GIL. ``threads=0`` uses OpenMP's default (OMP_NUM_THREADS, else all
cores; note that ``import torch`` may lower it for the whole process); a positive count applies
to that call only. At most 1024 threads: a larger ``threads`` raises InvalidArgument, a larger
OMP_NUM_THREADS is clamped to 1024.

Ctrl-C
------
A SIGINT during a long call raises ``KeyboardInterrupt`` (or what the SIGINT handler raises)
within a fraction of a second: softhd checks for signals between the passes of a distance and
its blocks of pairs, between Newton iterations and between the evaluations of ``optimise``.
"""

import os as _os
import warnings as _warnings

import numpy as _np

from . import _core
from ._core import (DistanceResult, Error, FileError, ForwardResult, InvalidArgument, Iteration,
                    Mesh, NumericalError, OptimiseResult, ResourceError, Scene)

__all__ = ["distance", "align", "hausdorff_nearest", "Target", "read_cloud", "write_cloud", "read_mesh",
           "crop_to_box", "remove_statistical_outliers", "remove_dominant_plane",
           "find_dominant_plane", "area_weights",
           "visible_points",
           "Scene", "Mesh", "optimise", "optimise_defaults", "DistanceResult", "ForwardResult",
           "OptimiseResult",
           "Iteration", "Error", "InvalidArgument", "FileError", "ResourceError", "NumericalError"]


def _plane4(p, name):
    """None, or a plane n.x = d as the 4 numbers (n1, n2, n3, d), from a dict with ``normal``
    and ``offset`` (find_dominant_plane's), a pair (normal, offset) or 4 numbers."""
    if p is None:
        return None
    if isinstance(p, dict):
        p = (p["normal"], p["offset"])
    if len(p) == 2:
        p = _np.concatenate([_np.ravel(_np.asarray(p[0], dtype=float)), [float(p[1])]])
    return _as_float64(_np.ravel(p), name)


def _as_float64(a, name):
    """`a` itself if it is a C-contiguous float64 ndarray, else a converted copy (module rule)."""
    if isinstance(a, _np.ndarray) and a.dtype == _np.float64 and a.flags.c_contiguous:
        return a
    arr = _np.asarray(a)
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must hold real numbers, got dtype {arr.dtype}")
    return _np.ascontiguousarray(arr, dtype=_np.float64)


def _volumes(v, name):
    return None if v is None else _as_float64(v, name)


def _mask(v, name):
    """A C-contiguous bool array of `v`: booleans, or numbers that are all 0 or 1."""
    arr = _np.asarray(v)
    if arr.dtype == bool:
        return _np.ascontiguousarray(arr)
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must hold booleans (or 0/1), got dtype {arr.dtype}")
    bad = _np.flatnonzero((arr != 0) & (arr != 1))
    if bad.size:
        raise InvalidArgument(f"{name} must hold booleans (or 0/1), got {arr.flat[bad[0]]!r} at "
                              f"index {bad[0]}")
    return _np.ascontiguousarray(arr, dtype=bool)


def _retired_visible(visible):
    """The keyword `visible` (the camera mask's old name) is refused naming the new one."""
    if visible is not None:
        raise TypeError("the keyword visible is now camera_mask (the mask of the moving points "
                        "a camera sees)")


class Target:
    """A target cloud Y (volumes VY) prepared for many evaluations: its k-d trees are built once.

    Options are those of :func:`distance`. The target keeps its own copy of the cloud.
    """

    def __init__(self, Y, VY=None, *, alpha=4.0, beta=4.0, gamma=2.0, eps=1e-3, method="exact",
                 tol=1e-6, threads=0):
        self._target = _core.Target(_as_float64(Y, "Y"), _volumes(VY, "VY"), alpha=alpha,
                                    beta=beta, gamma=gamma, eps=eps, method=method, tol=tol,
                                    threads=threads)
        self.method = method

    @property
    def size(self):
        """M, the number of target points."""
        return self._target.size

    @property
    def dim(self):
        """d, the dimension of the target cloud."""
        return self._target.dim

    def evaluate(self, X, VX=None, *, fields=False, gradient=False, gradient_volumes=False,
                 gradient_target=False, distance="symmetric", cap=0.0, cap_q=4.0, camera_mask=None,
                 visible=None, hessian=False):
        """rho_H(X, Y) and what is asked for, as a :class:`DistanceResult`.

        fields: d~ at every point (``field_moving`` (N,), ``field_target`` (M,); the raw
        values, before any cap); gradient: d rho / d x_i (``gradient`` (N, d));
        gradient_volumes: d rho / d V_i (N,); gradient_target: d rho / d y_j (M, d).
        Unrequested members are None. The form (docs/formulation.md §8): distance
        "symmetric", "scan_to_body" (rho = A, Y -> X only; B reported 0) or "visible" (B over
        the moving points where ``camera_mask`` (N,) is true: the points a camera sees,
        weights renormalised); cap: the soft
        cap c of psi_c(d) = (d^-q + c^-q)^(-1/q) on every field value (0: none), cap_q: q.
        hessian: keep what :meth:`hessian_product` needs at X (the gradient's passes are made).
        X (and VX) follow the module's array rule (no copy of C-contiguous float64).
        """
        _retired_visible(visible)
        if camera_mask is not None:
            camera_mask = _mask(camera_mask, "camera_mask")
        return self._target.evaluate(_as_float64(X, "X"), _volumes(VX, "VX"), fields=fields,
                                     gradient=gradient, gradient_volumes=gradient_volumes,
                                     gradient_target=gradient_target, distance=distance,
                                     cap=cap, cap_q=cap_q, camera_mask=camera_mask, hessian=hessian)

    def hessian_product(self, result, V, *, part="full"):
        """H V, the Hessian of rho w.r.t. the moving points (volumes fixed) applied to the
        direction V (N, d), at the X of ``result`` (an :meth:`evaluate` result of this target
        with hessian=True, whose form it keeps). part "gauss_newton": its positive
        semi-definite part instead (docs/formulation.md §2.7). Returns a new (N, d) array.
        """
        return self._target.hessian_product(result, _as_float64(V, "V"), part=part)


def distance(X, Y, VX=None, VY=None, *, alpha=4.0, beta=4.0, gamma=2.0, eps=1e-3,
             method="exact", tol=1e-6, fields=False, gradient=False, gradient_volumes=False,
             gradient_target=False, threads=0, distance="symmetric", cap=0.0, cap_q=4.0,
             camera_mask=None, visible=None):
    """The regularised Hausdorff distance rho_H between X (N, d) and Y (M, d).

    method: "exact" (all pairs), "tree" (relative error of every kernel sum <= tol) or
    "nearest" (the unregularised Hausdorff distance; no gradients). distance, cap, cap_q,
    camera_mask: the form of docs/formulation.md §8 (see :meth:`Target.evaluate`). Returns a
    :class:`DistanceResult` with ``rho``, ``A``, ``B`` and the requested arrays.
    Equivalent to ``Target(Y, VY, ...).evaluate(X, VX, ...)``.
    """
    _retired_visible(visible)
    target = Target(Y, VY, alpha=alpha, beta=beta, gamma=gamma, eps=eps, method=method, tol=tol,
                    threads=threads)
    return target.evaluate(X, VX, fields=fields, gradient=gradient,
                           gradient_volumes=gradient_volumes, gradient_target=gradient_target,
                           distance=distance, cap=cap, cap_q=cap_q, camera_mask=camera_mask)


def hausdorff_nearest(X, Y, *, fields=False, threads=0):
    """The exact (unregularised) Hausdorff distance: ``rho`` = max(A, B), ``A`` = max_j
    dist(y_j, X), ``B`` = max_i dist(x_i, Y) (nearest-neighbour queries)."""
    return distance(X, Y, method="nearest", fields=fields, threads=threads)


def align(body, scan, body_volumes=None, *, similarity=False, scale_min=0.5, scale_max=2.0,
          distance="symmetric", cap=0.0, eps=None, alpha=4.0, beta=4.0, gamma=2.0,
          global_start=True, initial=None, rotations=48, refine_points=1000, inlier=0.01,
          threads=0, score="coverage", keep=4, fixture=None, table=None, clamp=None,
          body_triangles=None):
    """The pose that takes ``scan`` (M, 3), in the camera's frame, onto ``body`` (N, 3)
    (docs/formulation.md section 8, as ``softhd align``): y -> s R y + t minimising rho over a
    twist, after a global start over ``rotations`` grid rotations (unless ``global_start`` is
    False: then from ``initial``, a (4, 4) matrix, default the identity). With the global start,
    ``initial`` is one more candidate, refined and compared with the global start's. A rigid
    alignment needs a rigid ``initial`` (scale 1).

    similarity: also a scale s in [scale_min, scale_max] (the bounds must include 1).
    distance: "symmetric" or "scan_to_body" (rho = A, for partial views); cap: the soft cap
    (a length, 0: none). eps: the final refinement's epsilon (None: L/1000, L the diagonal of
    the body's bounding box). refine_points: points of each cloud in the refinement (0: all).
    inlier: the overlap's threshold as a fraction of L, in (0, 1). score: how the global start's poses
    are ranked and its ``keep`` refined candidates compared: "coverage" (the coverage score
    of docs/formulation.md section 8.5: the camera at the scan frame's origin, the scan must
    cover the body's side it shows and lie on the body) or "rho" (rho itself, for a scan not
    in its camera's frame). The retired spelling "visible" raises InvalidArgument naming
    "coverage".

    fixture: the table the body sits on, in the body's frame, as 4 numbers (n1, n2, n3, d),
    a pair (normal, d) or a dict with "normal" and "offset": the plane n.x = d, n pointing
    towards the body (docs/formulation.md section 8.12); with it, ``table`` (the same table
    found in the scan, e.g. ``find_dominant_plane(scan, ...)``'s ``normal`` and ``offset``
    before the table is removed; its sign is free) is required, and
    every pose tried keeps the table's tilt and height: only the rotation about the table's
    normal (``rotations`` angles in the global start) and the shift along it are searched.
    clamp: with ``fixture``, the clamp's side as a pair (direction in the body's frame from its
    centre to its clamped end, the direction that end is seen in the scan's frame): poses that
    turn the one more than 90 degrees from the other (on the table) are not tried.

    body_triangles: the body's surface, (T, 3) integer ids into ``body``'s rows, outward and
    closed (e.g. ``Mesh.boundary_triangles`` with ``body`` the mesh's nodes in the body's
    configuration): every nearest-point fit then pairs a scan point with its closest point of
    the surface, and the finish fits the pose point-to-plane to convergence, so a scan sampled
    anywhere on that surface and rigidly moved is recovered to rounding (not only a copy of the
    body's points); ``residuals``, ``overlap`` and ``rmse`` are then distances to the surface.

    Returns a dict: ``matrix`` (4, 4), ``twist`` (7,: omega, v, sigma with R = exp([omega]x),
    t = v, s = e^sigma), ``scale``, ``rho``, ``overlap`` (fraction of scan points within the
    inlier distance of the body), ``inlier_distance``, ``rmse`` (of those points' true
    nearest distances), ``residuals`` (M,: every moved scan point's true nearest distance to
    the body), ``status``, ``iterations``, ``seconds``, ``starts`` (the global start's
    starting poses: rotations + 4, 0 without it), ``candidates`` (the candidates refined and
    compared: at most ``keep``, plus ``initial``), ``refine_points`` (the refinement's points
    of the body and of the scan). Raises InvalidArgument for bounds
    that exclude 1, a wrong ``initial``, non-3D or non-finite clouds, and a body or scan whose
    points do not span a plane (a single point, coincident or collinear points fix no pose).
    """
    init = None if initial is None else _as_float64(initial, "initial")
    d = _core.align(_as_float64(body, "body"), _volumes(body_volumes, "body_volumes"),
                    _as_float64(scan, "scan"), similarity=bool(similarity),
                    scale_min=float(scale_min), scale_max=float(scale_max),
                    distance=str(distance), cap=float(cap),
                    eps=None if eps is None else float(eps), alpha=float(alpha),
                    beta=float(beta), gamma=float(gamma), global_start=bool(global_start),
                    initial=init, rotations=int(rotations),
                    refine_points=int(refine_points), inlier=float(inlier),
                    threads=int(threads), score=str(score), keep=int(keep),
                    fixture=_plane4(fixture, "fixture"), table=_plane4(table, "table"),
                    clamp=None if clamp is None else _as_float64(
                        _np.concatenate([_np.ravel(clamp[0]), _np.ravel(clamp[1])]), "clamp"),
                    body_triangles=None if body_triangles is None else _triangles(
                        body_triangles, "body_triangles"))
    d["twist"] = d["twist"].reshape(7)
    d["residuals"] = d["residuals"].reshape(-1)
    return d


def read_cloud(path, dim=0):
    """(points, volumes) of a text, PLY or PCD cloud file (by its extension: .ply, .pcd, else
    text): a C-contiguous (N, d) float64 array and an (N,) one. dim: 0 (from the file), 2 or 3.
    Raises FileError naming the file and line. What the reader skipped (colours, normals, a
    PCD's invalid points) is reported as one UserWarning per note."""
    points, volumes, notes = _core.read_cloud(_os.fspath(path), dim)
    for note in notes:
        _warnings.warn(note, stacklevel=2)
    return points, volumes


def crop_to_box(points, lower, upper, margin=0.0):
    """Indices (int64, increasing) of the points inside [lower - m, upper + m], m = margin times
    the box's diagonal |upper - lower| (docs/formulation.md section 8.8)."""
    return _core.crop_to_box(_as_float64(points, "points"), _as_float64(lower, "lower"),
                             _as_float64(upper, "upper"), float(margin))


def remove_statistical_outliers(points, k=20, ratio=2.0):
    """Indices of the points kept by statistical outlier removal: m_i the mean distance to the
    k nearest other points, kept if m_i <= mean(m) + ratio * std(m) (sample std, N - 1)."""
    return _core.remove_statistical_outliers(_as_float64(points, "points"), int(k), float(ratio))


def remove_dominant_plane(points, distance, iterations=1000, min_fraction=0.1, seed=1):
    """Indices of the points off the dominant plane (RANSAC with `iterations` samples from a
    fixed seed, refit by least squares on its inliers): |n.x - d| > distance. Nothing is
    removed if the plane holds fewer than min_fraction of the points."""
    return _core.remove_dominant_plane(_as_float64(points, "points"), float(distance),
                                       int(iterations), float(min_fraction), int(seed))


def find_dominant_plane(points, distance, iterations=1000, min_fraction=0.1, seed=1):
    """The dominant plane of (M, 3) points (as remove_dominant_plane finds it): a dict with
    ``normal`` (unit; its largest component positive), ``offset`` (n.x = offset on the plane)
    and ``inliers`` (the points within ``distance`` of it)."""
    return _core.find_dominant_plane(_as_float64(points, "points"), float(distance),
                                     int(iterations), float(min_fraction), int(seed))


def area_weights(points, method="knn", neighbours=12):
    """(N,) estimated surface areas of a 3D scan (lengths of a 2D curve): "knn" (pi r_k^2 / k)
    or "delaunay" (the tangent-plane Voronoi cell); docs/formulation.md section 8.9."""
    return _core.area_weights(_as_float64(points, "points"), str(method), int(neighbours))


def _triangles(triangles, name):
    tri = _np.asarray(triangles)
    if tri.size and tri.dtype.kind not in "iu":
        raise TypeError(f"{name} must hold integers, got dtype {tri.dtype}")
    return _np.ascontiguousarray(tri, dtype=_np.int64).reshape(-1, 3)


def visible_points(points, triangles, camera, tolerance=1e-6):
    """(N,) bool: the points of a closed, outward triangle surface that a camera at `camera`
    sees (docs/formulation.md section 8.7): facing (an incident triangle's outward normal n has
    n.(camera - x) > 0) and the segment from the camera meets no triangle before x (up to
    `tolerance` times the bounding-box diagonal). points (N, 3); triangles (T, 3) ids into
    them (e.g. Mesh.boundary_triangles over Mesh.nodes + displacements); a point on no
    triangle (an interior node) is not seen."""
    tri = _np.asarray(triangles)
    if tri.size and tri.dtype.kind not in "iu":
        raise TypeError(f"triangles must hold integers, got dtype {tri.dtype}")
    return _core.visible_points(_as_float64(points, "points"),
                                _np.ascontiguousarray(tri, dtype=_np.int64).reshape(-1, 3),
                                _as_float64(camera, "camera"), float(tolerance))


def write_cloud(path, points, volumes=None):
    """Writes a cloud: binary PLY if the name ends in .ply, text otherwise (both round-trip
    bit-exactly). volumes None: all 1."""
    _core.write_cloud(_os.fspath(path), _as_float64(points, "points"), _volumes(volumes, "volumes"))


def read_mesh(path, order=None, scale=1.0):
    """The :class:`Mesh` of a Gmsh file (MSH 4.1 ASCII or binary, MSH 2.2 ASCII), read as a
    scene's ``"mesh": {"type": "gmsh", ...}`` reads it (docs/guide.md, "A body from Gmsh").

    order: None (the file's), 1 (the elements' vertices only: P1/Q1 on a second-order file)
    or 2 (second order; straight-sided midside nodes added to a first-order file, a
    second-order file kept isoparametric). scale: multiplies the coordinates (1e-3 for a file
    in mm and a body in m).

    The result has ``nodes`` (N, dim) float64, ``elements`` (E, nodes per element) int64 in
    softhd's local node order, ``cell_type`` ("tet4", "tet10", "hex8", "hex27", "tri3",
    "tri6", "quad4", "quad9"), ``region_names`` (the physical volumes; physical surfaces in
    2D) with ``element_region`` (E,) indices into them, ``boundary`` (a dict: physical group
    one dimension below the body's -> sorted node ids), ``vertex_nodes``,
    ``element_vertices`` and ``volume`` (softhd's quadrature). Nodes no element uses are
    dropped; the others keep the file's order.

    Raises FileError naming the file (and line or block) for a file that cannot be read or
    solved on (malformed, unknown element type, mixed orders, no volume elements, inverted
    elements), InvalidArgument for an order other than None, 1, 2 or a scale <= 0.
    """
    if order is None:
        order = 0
    elif order not in (1, 2) or isinstance(order, bool):
        raise InvalidArgument(f"read_mesh: order must be None, 1 or 2, got {order!r}")
    return _core.read_mesh(_os.fspath(path), order, float(scale))


def optimise(scene, target=None, *, max_iter=None, max_seconds=None, rel_tol=None,
             algorithm=None, hessian=None, move_limit=None, particles=None, volumes=None, alpha=None,
             beta=None, gamma=None, eps=None, method=None, tol=None, tikhonov_mass=None,
             tikhonov_grad=None, coarse_levels=None, levels=None, refined_move_limit=None,
             coarse_iterations=None, switch_decrease=None, coarse_tol=None,
             distance=None, cap=None, cap_q=None, initial=None, pose_move=None, pose_method=None,
             quadrature=None, callback=None, threads=0):
    """Finds the fiber tension m within the scene's bounds whose equilibrium best matches the
    target: the run ``softhd optimise`` makes (the library's TrackingRun), with its options and
    its defaults for every option left None (:func:`optimise_defaults` lists them, e.g. method
    "tree" with tol 1e-2, move_limit 0.1, beta 0: automatic, 4 for the symmetric distance and
    2 for scan_to_body and visible, as ``--beta``; coarse_levels "auto" (0: none;
    ``--coarse-levels``):
    the state solves' coarse start, two-level starts on the coarse level (a box with half the
    cells, a mesh file of order 2 as P1/Q1 on its vertices), levels 0:
    automatic, where the target has a known map (an arc, a manufactured state) 1 + every coarser
    level of at least 32 elements (a box halved along its even axes, else every axis of at least 4
    cells to (n + 1) / 2; bending: 3), else 1 (the user's mesh alone; a scan-like cloud runs on one
    level); levels N > 1 solves first on the N - 1 coarser levels, as ``--levels N``,
    each level after the coarsest with the move limit refined_move_limit, 0.02, as
    ``--refined-move-limit``; each coarse level at most coarse_iterations, 30, iterations, ending
    earlier once rho decreased by less than switch_decrease, 0.01, relative twice in a row, with
    the tree tolerance max(tol, coarse_tol), 5e-2, as ``--coarse-iterations``,
    ``--switch-decrease``, ``--coarse-tol``). Returns an :class:`OptimiseResult`.

    target: None (the scene's own "target"), a cloud file path, an (M, d) array, or a tuple
    (points, volumes). distance ("symmetric" or "scan_to_body"), cap (a length), cap_q: the
    distance's form (docs/formulation.md §8); None: the scene target's "distance", "cap",
    "cap_q" (symmetric without a cap for a file or an array); any of them given replaces the
    target's form as a whole. callback(record): called after every accepted iteration with an
    :class:`Iteration` (J, rho, A, B, ..., control); **returning False ends the run** after
    that iteration (termination "stopped by the caller"; on a coarse level, after the first
    iteration on the user's mesh, whose result it returns); any other return value continues;
    an exception raised by the callback ends the run and propagates. initial: the starting
    control (one value per control, e.g. an earlier result's ``control``; levels 1 only); None:
    the scene's control.initial; values outside the control bounds, and an empty array, raise
    InvalidArgument. pose_method, pose_move: a scene target in the camera's frame only
    (InvalidArgument for a target in the body's frame): pose_method "joint" (default: the pose's
    six variables join the optimiser's) or "projection" (every evaluation fits the rigid pose to
    the scan on its state, from the last evaluation's pose, and the optimiser moves the control
    alone; the result's ``pose`` is the final fit); pose_move, the joint pose's move limit as a
    fraction of the control's, in (0, 1] (default 1). algorithm "newton" (trust-region Newton-CG) uses the exact Hessian-vector
    product of J, or with hessian "gauss_newton" its positive semi-definite part (``--hessian``).
    quadrature: "collocation" or "cells" (``--quadrature``; None: the scene target's
    "quadrature", else collocation): cells integrates the distance over the body's cells and the
    target's (an arc, or a cloud with "solved_on"; with the distance "scan_to_body", a cloud's
    points as a surface with their weights; any other target without cells falls back to
    collocation, as its description says), on one level, not with algorithm "newton"; a cloud in
    the camera's frame with it needs pose_method "projection".
    """
    points = vols = file = None
    if isinstance(target, (str, bytes, _os.PathLike)):
        file = _os.fsdecode(target)
    elif isinstance(target, tuple):
        points, vols = _as_float64(target[0], "target"), _volumes(target[1], "target volumes")
    elif target is not None:
        points = _as_float64(target, "target")
    return _core.optimise(scene, points, vols, file, max_iter=max_iter, max_seconds=max_seconds,
                          rel_tol=rel_tol, algorithm=algorithm, hessian=hessian,
                          move_limit=move_limit,
                          particles=particles, volumes_kind=volumes, alpha=alpha, beta=beta,
                          gamma=gamma, eps=eps, method=method, tol=tol,
                          tikhonov_mass=tikhonov_mass, tikhonov_grad=tikhonov_grad,
                          coarse_levels=None if coarse_levels is None else str(coarse_levels),
                          levels=levels,
                          refined_move_limit=refined_move_limit,
                          coarse_iterations=coarse_iterations, switch_decrease=switch_decrease,
                          coarse_tol=coarse_tol, distance=distance,
                          cap=cap, cap_q=cap_q,
                          initial=None if initial is None else _as_float64(initial, "initial"),
                          pose_move=pose_move, pose_method=pose_method, quadrature=quadrature,
                          callback=callback,
                          threads=threads)


def optimise_defaults():
    """The defaults of :func:`optimise`'s options as a dict (name: value): those of
    ``softhd optimise``, written once in the library (TrackingRunOptions)."""
    return _core.optimise_defaults()
