#!/usr/bin/python3
"""Continuum reference values of the regularised Hausdorff distance between boxes.

rho~ of two bodies (formulation section 2, with the sums over the clouds replaced by integrals
over the bodies):

    J_X(y) = int_X (|y - x| + eps)^-4 dx,    dt_X(y) = (J_X(y)/|X|)^(-1/4) - eps,
    A = ((1/|Y|) int_Y dt_X(y)^4 dy)^(1/4),  B likewise,  rho~ = ((A^2 + B^2)/2)^(1/2)
    (alpha = beta = 4, gamma = 2, eps = 1e-3).

Inner integral, exact up to a one-dimensional quadrature of an analytic integrand:
with F(x) = (x - y) / (3 eps (|x - y| + eps)^3) one has div F = (r + eps)^-4 (because
d/dr [r^3 / (3 eps (r + eps)^3)] = r^2 (r + eps)^-4) and F bounded at x = y, so for any
polyhedron (y inside or outside)

    J_X(y) = (1/(3 eps)) sum_faces h_f int_face (r + eps)^-3 dA,   h_f = n_f . (x - y).

For a box split at y into 8 corner boxes (signed, by inclusion-exclusion when y is outside),
only the three far faces of a corner box [0,a]x[0,b]x[0,c] have h != 0, each a rectangle with
a corner at the foot of y: K(a,b,c) = (1/(3 eps)) (a G(a;b,c) + b G(b;a,c) + c G(c;a,b)),
G(h;p,q) = int_[0,p]x[0,q] (sqrt(s^2 + t^2 + h^2) + eps)^-3 ds dt. In polar coordinates about
the corner the radial integral is closed form,

    int_0^R s ds / (sqrt(s^2 + h^2) + eps)^3 = Psi(h) - Psi(T),  Psi(t) = 1/(t+eps) - eps/(2(t+eps)^2),
    T = sqrt(R^2 + h^2),

and the angle over each of the two triangles of the rectangle, after theta = gd(u)
(tan theta = sinh u), is int_0^asinh(q/p) Psi(sqrt(p^2 cosh^2 u + h^2)) / cosh u du, whose
integrand is analytic in the strip |Im u| < pi/2 whatever p, h, eps: one Gauss-Legendre rule
of n_u points converges geometrically (checked by doubling n_u). This is the same quantity as
the ray form int_S2 rho(w)^3 / (3 eps (rho + eps)^3) dw of the issue (exact for convex bodies);
the face form holds for any polyhedron.

Outer integral: tensor composite Gauss-Legendre, panels graded geometrically towards every face
coordinate of the source box (the eps-layers of dt at faces, edges and corners), with the
bodies' symmetries (octants, permutations of axes) folded. Two refinement levels are reported;
their agreement is the stated accuracy.

Checks (run first): the half-space profile 4 pi/(3 eps) - pi/(d + eps) + pi eps/(3 (d + eps)^2)
inside and pi/(D + eps) - pi eps/(3 (D + eps)^2) outside (a box of half-size 1e6), and J of a
small box at eps = 0.05 against scipy's adaptive nquad.

    OPENBLAS_NUM_THREADS=1 nice -n 10 studies/continuum_reference.py [--quick] [--json FILE]
"""
import argparse
import json
import math
import sys
import time

import numpy as np

EPS = 1e-3


def psi(t, eps):
    """Psi(t) = 1/(t+eps) - eps/(2 (t+eps)^2): minus the antiderivative of t/(t+eps)^3."""
    s = 1.0 / (t + eps)
    return s - 0.5 * eps * s * s


class Rule:
    """Gauss-Legendre nodes on [0, 1] for the angle integrals."""

    def __init__(self, n):
        x, w = np.polynomial.legendre.leggauss(n)
        self.x = 0.5 * (x + 1.0)
        self.w = 0.5 * w


def wedge(h, p, q, eps, rule):
    """W(h;p,q) = int_0^atan(q/p) [Psi(h) - Psi(sqrt(p^2/cos^2 th + h^2))] dth (arrays, p,q,h >= 0)."""
    out = np.zeros_like(h)
    ok = (p > 0) & (q > 0)
    if not np.any(ok):
        return out
    h, p, q = h[ok], p[ok], q[ok]
    U = np.arcsinh(q / p)
    u = U[:, None] * rule.x[None, :]
    ch = np.cosh(u)
    T = np.sqrt((p[:, None] * ch) ** 2 + (h * h)[:, None])
    integral = U * ((psi(T, eps) / ch) @ rule.w)
    out[ok] = np.arctan2(q, p) * psi(h, eps) - integral
    return out


def corner(a, b, c, eps, rule):
    """K(a,b,c) = int_[0,a]x[0,b]x[0,c] (|x| + eps)^-4 dx for a, b, c >= 0 (arrays)."""
    def G(hh, pp, qq):
        return wedge(hh, pp, qq, eps, rule) + wedge(hh, qq, pp, eps, rule)

    return (a * G(a, b, c) + b * G(b, a, c) + c * G(c, a, b)) / (3.0 * eps)


def J_box(y, lo, hi, eps=EPS, rule=None, chunk=2000):
    """J(y) = int_box (|y - x| + eps)^-4 dx for points y (n x 3), box [lo, hi], y anywhere."""
    rule = rule or Rule(64)
    y = np.atleast_2d(y)
    out = np.empty(len(y))
    for s in range(0, len(y), chunk):
        Y = y[s:s + chunk]
        tot = np.zeros(len(Y))
        for i in (0, 1):
            for j in (0, 1):
                for k in (0, 1):
                    d = np.stack([(hi if b else lo)[ax] - Y[:, ax] for ax, b in enumerate((i, j, k))])
                    sign = np.prod(np.sign(d), axis=0) * (-1) ** (3 - i - j - k)
                    a = np.abs(d)
                    tot += sign * corner(a[0], a[1], a[2], eps, rule)
        out[s:s + chunk] = tot
    return out


def halfspace(d, eps=EPS):
    """Profile of a half-space at signed depth d (d > 0 inside, d < 0 outside at D = -d)."""
    d = np.asarray(d, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return _halfspace(d, eps)


def _halfspace(d, eps):
    inside = 4 * np.pi / (3 * eps) - np.pi / (d + eps) + np.pi * eps / (3 * (d + eps) ** 2)
    D = np.abs(d)
    outside = np.pi / (D + eps) - np.pi * eps / (3 * (D + eps) ** 2)
    return np.where(d >= 0, inside, outside)


def graded_1d(lo, hi, feats, d0, q, n):
    """Composite Gauss-Legendre on [lo, hi], panels graded geometrically (first d0, ratio q)
    on both sides of every feature coordinate."""
    br = {lo, hi}
    L = hi - lo
    for f in feats:
        if lo < f < hi:
            br.add(f)
        for sgn in (-1, 1):
            t = d0
            while t < 2 * L:
                x = f + sgn * t
                if lo < x < hi:
                    br.add(x)
                t *= q
    br = np.array(sorted(br))
    br = br[np.concatenate([[True], np.diff(br) > 1e-14 * max(1.0, L)])]
    xg, wg = np.polynomial.legendre.leggauss(n)
    a, b = br[:-1], br[1:]
    x = (0.5 * (b - a)[:, None] * (xg[None, :] + 1) + a[:, None]).ravel()
    w = (0.5 * (b - a)[:, None] * wg[None, :]).ravel()
    return x, w


LEVELS = {  # (first panel / eps, grading ratio, Gauss points per panel, angle points)
    1: (1e-2, 3.0, 6, 32),
    2: (2e-3, 2.2, 8, 48),
}


def mean4(points, weights, vol_target, lo, hi, rule, eps=EPS):
    """(1/|Y|) sum w dt_X(y)^4 over outer quadrature points, X the box [lo, hi]."""
    volX = np.prod(np.asarray(hi) - np.asarray(lo))
    J = J_box(points, np.asarray(lo, float), np.asarray(hi, float), eps, rule)
    dt = (J / volX) ** -0.25 - eps
    return float(np.dot(weights, dt ** 4) / vol_target)


def cube_octant_rule(lo, hi, feats, level):
    """Tensor rule on [lo,hi]^3 folded by the permutations of the axes (sorted index triples)."""
    d0, q, n, _ = LEVELS[level]
    x, w = graded_1d(lo, hi, feats, d0 * EPS, q, n)
    m = len(x)
    i, j, k = np.meshgrid(np.arange(m), np.arange(m), np.arange(m), indexing="ij")
    keep = (i <= j) & (j <= k)
    i, j, k = i[keep], j[keep], k[keep]
    mult = np.where((i == j) & (j == k), 1, np.where((i == j) | (j == k), 3, 6))
    pts = np.stack([x[i], x[j], x[k]], axis=1)
    return pts, w[i] * w[j] * w[k] * mult


def rho_cube_self(level):
    rule = Rule(LEVELS[level][3])
    pts, wts = cube_octant_rule(0.0, 0.5, [0.0], level)
    A4 = 8 * mean4(pts, wts, 1.0, [0, 0, 0], [1, 1, 1], rule)
    return A4 ** 0.25, len(pts)


def rho_cube_shift(s, level):
    """Y = X + s e1; A = B by the reflection x1 -> 1 + s - x1 that swaps the two cubes."""
    d0, q, n, nu = LEVELS[level]
    rule = Rule(nu)
    x1, w1 = graded_1d(s, 1 + s, [0.0, 1.0], d0 * EPS, q, n)
    x2, w2 = graded_1d(0.0, 0.5, [0.0], d0 * EPS, q, n)
    m = len(x2)
    j, k = np.meshgrid(np.arange(m), np.arange(m), indexing="ij")
    keep = j <= k
    j, k = j[keep], k[keep]
    w23 = w2[j] * w2[k] * np.where(j == k, 1, 2) * 4
    P = np.stack([np.repeat(x1, len(j)), np.tile(x2[j], len(x1)), np.tile(x2[k], len(x1))], axis=1)
    W = np.repeat(w1, len(j)) * np.tile(w23, len(x1))
    A4 = mean4(P, W, 1.0, [0, 0, 0], [1, 1, 1], rule)
    return A4 ** 0.25, len(P)


def rho_cube_small(side, level):
    """X the unit cube, Y the cube of the given side with the same centre."""
    rule = Rule(LEVELS[level][3])
    g = 0.5 * (1 - side)
    loY, hiY = [g] * 3, [1 - g] * 3
    pA, wA = cube_octant_rule(g, 0.5, [0.0], level)  # outer over Y, inner X
    A4 = 8 * mean4(pA, wA, side ** 3, [0, 0, 0], [1, 1, 1], rule)
    pB, wB = cube_octant_rule(0.0, 0.5, [g], level)  # outer over X, inner Y
    B4 = 8 * mean4(pB, wB, 1.0, loY, hiY, rule)
    A, B = A4 ** 0.25, B4 ** 0.25
    return math.sqrt(0.5 * (A * A + B * B)), len(pA) + len(pB), A, B


def rho_plate(level, dims=(10.0, 2.0, 0.1)):
    d0, q, n, nu = LEVELS[level]
    rule = Rule(nu)
    xs = [graded_1d(0.0, 0.5 * L, [0.0], d0 * EPS, q, n) for L in dims]
    X, Y, Z = np.meshgrid(xs[0][0], xs[1][0], xs[2][0], indexing="ij")
    W = np.einsum("i,j,k->ijk", xs[0][1], xs[1][1], xs[2][1])
    P = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
    vol = float(np.prod(dims))
    A4 = 8 * mean4(P, W.ravel(), vol, [0, 0, 0], list(dims), rule)
    return A4 ** 0.25, len(P)


def checks():
    """Unit tests of the inner integral; returns the largest relative errors."""
    out = {}
    L = 1e6
    lo, hi = np.array([-L, -L, -L]), np.array([L, L, 0.0])
    d = np.array([0.0, 1e-5, 1e-3, 0.01, 0.3, 2.0])
    y_in = np.stack([0 * d, 0 * d, -d], axis=1)
    y_out = np.stack([0 * d, 0 * d, d], axis=1)
    # the far faces of the 2e6 box remove about 5 pi / L (one half-space each)
    corr = 5 * np.pi / L
    e_in = np.abs(J_box(y_in, lo, hi) + corr - halfspace(d)) / halfspace(d)
    e_out = np.abs(J_box(y_out, lo, hi) - halfspace(-d)) / halfspace(-d)
    out["halfspace_inside_max_rel"] = float(e_in.max())
    out["halfspace_outside_max_rel"] = float(e_out[d > 0].max())
    # angle rule convergence at awkward points: near a corner, on an edge plane, far outside
    ys = np.array([[1e-7, 2e-6, 0.3], [0.5, 0.0, 1e-4], [1.3, -0.2, 0.5], [0.5, 0.5, 0.5]])
    j64 = J_box(ys, np.zeros(3), np.ones(3), rule=Rule(64))
    j200 = J_box(ys, np.zeros(3), np.ones(3), rule=Rule(200))
    out["angle_rule_64_vs_200_max_rel"] = float(np.max(np.abs(j64 / j200 - 1)))
    try:
        from scipy import integrate
        e = 0.05
        lo2, hi2 = np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.5, 0.3])
        errs = []
        for y in ([0.2, 0.1, 0.1], [1.1, 0.3, -0.05]):
            f = lambda z, yy, x: (math.sqrt((x - y[0]) ** 2 + (yy - y[1]) ** 2 + (z - y[2]) ** 2) + e) ** -4
            ref, _ = integrate.nquad(f, [[lo2[2], hi2[2]], [lo2[1], hi2[1]], [lo2[0], hi2[0]]],
                                     opts={"epsabs": 0, "epsrel": 1e-10, "limit": 200})
            mine = J_box(np.array([y]), lo2, hi2, eps=e)[0]
            errs.append(abs(mine / ref - 1))
        out["nquad_eps0.05_max_rel"] = float(max(errs))
    except ImportError:
        out["nquad_eps0.05_max_rel"] = None
    return out


ISSUE = {"self": 0.12416, 0.0025: 0.12432, 0.005: 0.12478, 0.01: 0.12653, 0.02: 0.13306,
         0.0625: 0.182, "side0.875": None, "plate": 0.1497}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="level 1 only")
    ap.add_argument("--json", help="write the values to this file")
    ap.add_argument("--cases", default="self,0.0025,0.005,0.01,0.02,0.0625,side0.875,plate",
                    help="comma-separated: self, a shift, side0.875, plate")
    args = ap.parse_args()
    t0 = time.time()
    chk = checks()
    print("checks:", json.dumps(chk), f"({time.time() - t0:.1f} s)", flush=True)
    levels = [1] if args.quick else [1, 2]
    cases = []
    for c in args.cases.split(","):
        if c == "self":
            cases.append((c, rho_cube_self))
        elif c == "side0.875":
            cases.append((c, lambda L: rho_cube_small(0.875, L)[:2]))
        elif c == "plate":
            cases.append((c, rho_plate))
        else:
            cases.append((float(c), (lambda s: lambda L: rho_cube_shift(s, L))(float(c))))
    res = {"checks": chk, "values": {}}
    print("case, level, rho, outer points, seconds, issue value")
    for name, fn in cases:
        vals = []
        for L in levels:
            t = time.time()
            v, npts = fn(L)
            vals.append(v)
            print(f"{name}, {L}, {v:.9f}, {npts}, {time.time() - t:.1f}, {ISSUE.get(name)}", flush=True)
        agree = abs(vals[-1] - vals[0]) / vals[-1] if len(vals) > 1 else None
        res["values"][str(name)] = {"levels": vals, "rel_diff_levels": agree}
        if agree is not None:
            print(f"  {name}: levels agree to {agree:.1e} relative")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
