#!/usr/bin/python3
"""Collocation against two cell-integrated discretisations of rho~ (boxes on hex grids).

Bodies are boxes meshed by hex grids of spacing h (cubic cells). Three ways to compute rho~
(alpha = beta = 4, gamma = 2, eps = 1e-3, formulation section 2):

  colloc-c / colloc-n   the library's collocation on the cell centres (V = h^3) or on the grid's
                        nodes with lumped (trapezoid) volumes, all pairs.
  split-c / split-n     (a) split kernel: at the outer body's nodes
                        J(y) = sum_i V_i (|y - x_i| + a)^-4 + P_eps(sd(y)) - P_a(sd(y)), a = c_a h_src,
                        sources the cell centres (-c) or the lumped nodes (-n).
  bnd                   (b) in boundary form: the same integral by the divergence theorem over the
                        source's boundary facets (Gauss g^2 per facet, the near facets exact).
  near                  (b) cell integration: J(y) = sum over the source cells of a Gauss rule
                        (g^3 points), the cells within c_near h_src of y integrated exactly instead
                        (the closed-form radial / Gauss angle rule of continuum_reference.py: the
                        near-singular quadrature of a boundary-element code).

P_eps is the half-space profile (formulation 2.8), sd the source body's signed distance.
The outer integral of the cell methods is the same for all: the expensive J is evaluated only at
sample points of the outer body (method suffix /n its nodes, /c its cell centres, /g its cells'
2x2x2 Gauss points), and inside each outer cell J at the quadrature points is rebuilt from a
trilinear interpolation through the samples: J = R + P_eps(sd) with R = J_s - P_eps(sd_s)
(default), or with --mult J = P_eps(sd) exp(R), R = log(J_s / P_eps(sd_s)) (scale-free where J
is small, outside the source). d~^4 is integrated by 2 Gauss points per axis per cell, graded
geometrically (first panel eps/50, ratio 4, 4 points per panel) along an axis where a face of
the source crosses or touches the cell (the eps-layer: "cut cells").

Cases: the unit cube against itself for every pair of resolutions, the translations
0.0025..0.02, the ranking (cube of side 0.875, cube shifted by one spacing), the plate
10 x 2 x 0.1 against itself. Reference values: continuum_reference.py --json (read with --ref).

The runs behind docs/formulation.md section 2.8 (docs/bench/cell_quadrature.csv):
    export OPENBLAS_NUM_THREADS=1; cd studies
    ./continuum_reference.py --json /tmp/cells/ref.json   # and --cases 0.0625 --json .../ref2.json
    ./cell_quadrature.py --suite shift --methods colloc-c,colloc-n,split-n/n,split-c/c,near/c
    ./cell_quadrature.py --suite rank  --methods colloc-c,colloc-n,split-n/n,split-c/c,near/c
    ./cell_quadrature.py --suite self --ns 4,8,12,16,32,64 --cap 1.4e9 \
        --methods colloc-c,colloc-n,split-n/n,split-c/c,near/c
    ./cell_quadrature.py --suite plate --cap 2.1e9 --methods colloc-c,colloc-n,split-n/n,split-c/c,near/c,near/g
    ./cell_quadrature.py --mult --suite rank --cap 3e9 --methods split-n/n,split-c/c,near/c,near/g
    ./cell_quadrature.py --mult --suite shift --cap 3e9 --shifts 0,0.01,0.02 --methods near/g
    ./cell_quadrature.py --mult --suite shift --methods near/c
    ./cell_quadrature.py --mult --suite self --cap 1.6e9 --ns 4,8,16 --methods near/g
    ./cell_quadrature.py --mult --suite plate --cap 1.6e9 --methods near/g
    ./cell_quadrature.py --mult --g 3 --suite self --ns 8,16 --cap 3e9 --methods bnd/c,bnd/g
    ./cell_quadrature.py --mult --g 3 --suite rank --cap 3e9 --methods bnd/g
    ./cell_quadrature.py --mult --g 3 --suite shift --cap 3e9 --shifts 0,0.01,0.02 --methods bnd/g
    ./cell_quadrature.py --mult --g 3 --suite plate --cap 2e7 --methods bnd/g
Output: CSV rows case, hX, hY, method, rho, ref, err_pct, pairs (kernel evaluations of the pair
sums), near_cells (exact near-cell or near-facet integrals), outer_points, cpu_s.
"""
import argparse
import csv
import itertools
import math
import sys
import time

import numpy as np

from continuum_reference import EPS, Rule, corner, graded_1d, halfspace

REF = {"self": 0.124155377, 0.0025: None, 0.005: None, 0.01: None, 0.02: None, 0.0625: None,
       "side0.875": None, "plate": None}  # filled from continuum_reference.py's output (--ref)


class Grid:
    """A box [lo, hi] meshed by n = (nx, ny, nz) cubic cells of spacing h."""

    def __init__(self, lo, hi, h):
        self.lo = np.asarray(lo, float)
        self.hi = np.asarray(hi, float)
        self.n = np.rint((self.hi - self.lo) / h).astype(int)
        self.h = h
        assert np.allclose(self.n * h, self.hi - self.lo), (lo, hi, h)
        self.vol = float(np.prod(self.hi - self.lo))

    def axes_nodes(self):
        return [self.lo[a] + self.h * np.arange(self.n[a] + 1) for a in range(3)]

    def centres(self):
        ax = [self.lo[a] + self.h * (np.arange(self.n[a]) + 0.5) for a in range(3)]
        P = np.stack(np.meshgrid(*ax, indexing="ij"), -1).reshape(-1, 3)
        return P, np.full(len(P), self.h ** 3)

    def nodes(self):
        ax = self.axes_nodes()
        P = np.stack(np.meshgrid(*ax, indexing="ij"), -1).reshape(-1, 3)
        w1 = [np.full(len(a), self.h) for a in ax]
        for w in w1:
            w[0] = w[-1] = 0.5 * self.h
        W = np.einsum("i,j,k->ijk", *w1).ravel()
        return P, W

    def gauss(self, g):
        xg, wg = np.polynomial.legendre.leggauss(g)
        ax, ww = [], []
        for a in range(3):
            c = self.lo[a] + self.h * (np.arange(self.n[a]) + 0.5)
            ax.append((c[:, None] + 0.5 * self.h * xg[None, :]).ravel())
            ww.append(np.tile(0.5 * self.h * wg, self.n[a]))
        P = np.stack(np.meshgrid(*ax, indexing="ij"), -1).reshape(-1, 3)
        return P, np.einsum("i,j,k->ijk", *ww).ravel()


def sd_box(y, lo, hi):
    """Signed distance to the box, positive inside."""
    d_in = np.minimum(y - lo, hi - y)
    inside = np.all(d_in >= 0, axis=1)
    out = np.sqrt(np.sum(np.maximum(0, np.maximum(lo - y, y - hi)) ** 2, axis=1))
    return np.where(inside, d_in.min(axis=1), -out)


def P(sd, a):
    return halfspace(sd, a)


COUNT = {"pairs": 0, "near_cells": 0}


def kernel_sum(Y, X, V, a, budget=3_000_000):
    """sum_i V_i (|y - x_i| + a)^-4 for every y (all pairs, chunked)."""
    out = np.empty(len(Y))
    c = max(1, budget // max(1, len(X)))
    for s in range(0, len(Y), c):
        Yc = Y[s:s + c]
        d2 = (Yc[:, 0, None] - X[None, :, 0]) ** 2
        d2 += (Yc[:, 1, None] - X[None, :, 1]) ** 2
        d2 += (Yc[:, 2, None] - X[None, :, 2]) ** 2
        t = 1.0 / (np.sqrt(d2) + a)
        t *= t
        out[s:s + c] = (t * t) @ V
    COUNT["pairs"] += len(Y) * len(X)
    return out


def J_boxes(y, lo, hi, eps, rule):
    """Exact int over per-point boxes [lo_k, hi_k] of (|y_k - x| + eps)^-4."""
    tot = np.zeros(len(y))
    for i, j, k in itertools.product((0, 1), repeat=3):
        d = np.stack([(hi if b else lo)[:, ax] - y[:, ax] for ax, b in enumerate((i, j, k))])
        sign = np.prod(np.sign(d), axis=0) * (-1) ** (3 - i - j - k)
        ad = np.abs(d)
        tot += sign * corner(ad[0], ad[1], ad[2], eps, rule)
    return tot


def J_near(Y, src, g=2, c_near=1.5, nu=20):
    """Method (b): Gauss g^3 on every source cell, exact on the cells within c_near h of y."""
    XG, WG = src.gauss(g)
    J = kernel_sum(Y, XG, WG, EPS)
    rule = Rule(nu)
    xg, wg = np.polynomial.legendre.leggauss(g)
    base = np.floor((Y - src.lo) / src.h).astype(int)
    m = int(math.ceil(c_near)) + 1
    for off in itertools.product(range(-m, m + 1), repeat=3):
        idx = base + np.array(off)
        ok = np.all((idx >= 0) & (idx < src.n), axis=1)
        lo = src.lo + src.h * idx
        hi = lo + src.h
        dist = np.sqrt(np.sum(np.maximum(0, np.maximum(lo - Y, Y - hi)) ** 2, axis=1))
        ok &= dist < c_near * src.h
        if not np.any(ok):
            continue
        y, l, u = Y[ok], lo[ok], hi[ok]
        exact = J_boxes(y, l, u, EPS, rule)
        # the Gauss rule's share of these cells, to be replaced
        gpts = [(l[:, a, None] + 0.5 * src.h * (xg[None, :] + 1)) for a in range(3)]
        gw = 0.5 * src.h * wg
        approx = np.zeros(len(y))
        for p, q, r in itertools.product(range(g), repeat=3):
            dd = np.sqrt((gpts[0][:, p] - y[:, 0]) ** 2 + (gpts[1][:, q] - y[:, 1]) ** 2
                         + (gpts[2][:, r] - y[:, 2]) ** 2)
            approx += gw[p] * gw[q] * gw[r] * (dd + EPS) ** -4
        J[ok] += exact - approx
        COUNT["near_cells"] += int(ok.sum())
    return J


def rect_integral(h, u1, u2, v1, v2, eps, rule):
    """int_[u1,u2]x[v1,v2] (sqrt(u^2 + v^2 + h^2) + eps)^-3 du dv (foot of y at the origin),
    by signed corner rectangles with the closed-form radial integral (continuum_reference)."""
    from continuum_reference import wedge

    def Gs(p, q):
        ap, aq = np.abs(p), np.abs(q)
        return np.sign(p) * np.sign(q) * (wedge(h, ap, aq, eps, rule) + wedge(h, aq, ap, eps, rule))

    return Gs(u2, v2) - Gs(u1, v2) - Gs(u2, v1) + Gs(u1, v1)


def J_boundary(Y, src, g=2, c_near=1.5, nu=20):
    """Method (b) in boundary form: J(y) = (1/(3 eps)) sum over the source's boundary facets of
    h_f int_facet (r + eps)^-3 dA (divergence theorem, h_f = n_f.(x - y)); Gauss g^2 per facet,
    the facets within c_near h of y exact."""
    xg, wg = np.polynomial.legendre.leggauss(g)
    rule = Rule(nu)
    h = src.h
    J = np.zeros(len(Y))
    for ax in range(3):
        b1, b2 = [a for a in range(3) if a != ax]
        for side in (0, 1):
            c = src.hi[ax] if side else src.lo[ax]
            hf = (c - Y[:, ax]) if side else (Y[:, ax] - c)
            # Gauss points of every facet of this face
            u = (src.lo[b1] + h * (np.arange(src.n[b1])[:, None] + 0.5 + 0.5 * xg[None, :])).ravel()
            v = (src.lo[b2] + h * (np.arange(src.n[b2])[:, None] + 0.5 + 0.5 * xg[None, :])).ravel()
            wu = np.tile(0.5 * h * wg, src.n[b1])
            wv = np.tile(0.5 * h * wg, src.n[b2])
            U, V = np.meshgrid(u, v, indexing="ij")
            X = np.zeros((U.size, 3))
            X[:, ax], X[:, b1], X[:, b2] = c, U.ravel(), V.ravel()
            W = np.outer(wu, wv).ravel()
            # (r + eps)^-3 = ((r + eps)^-4)^(3/4): use the 4th-power pair sum with exponent 3
            J += hf * kernel_sum_p(Y, X, W, EPS, 3)
            # near facets: exact minus their Gauss share
            base = np.floor((Y[:, [b1, b2]] - src.lo[[b1, b2]]) / h).astype(int)
            m = int(math.ceil(c_near)) + 1
            for o1 in range(-m, m + 1):
                for o2 in range(-m, m + 1):
                    i1, i2 = base[:, 0] + o1, base[:, 1] + o2
                    ok = (i1 >= 0) & (i1 < src.n[b1]) & (i2 >= 0) & (i2 < src.n[b2])
                    l1 = src.lo[b1] + h * i1
                    l2 = src.lo[b2] + h * i2
                    du = np.maximum(0, np.maximum(l1 - Y[:, b1], Y[:, b1] - l1 - h))
                    dv = np.maximum(0, np.maximum(l2 - Y[:, b2], Y[:, b2] - l2 - h))
                    ok &= np.sqrt(du ** 2 + dv ** 2 + hf ** 2) < c_near * h
                    ok &= hf != 0
                    if not np.any(ok):
                        continue
                    y1, y2, hh = Y[ok, b1], Y[ok, b2], np.abs(hf[ok])
                    ex = rect_integral(hh, l1[ok] - y1, l1[ok] + h - y1, l2[ok] - y2, l2[ok] + h - y2,
                                       EPS, rule)
                    ap = np.zeros(len(hh))
                    for p in range(g):
                        for q in range(g):
                            r = np.sqrt((l1[ok] + 0.5 * h * (1 + xg[p]) - y1) ** 2
                                        + (l2[ok] + 0.5 * h * (1 + xg[q]) - y2) ** 2 + hh ** 2)
                            ap += 0.25 * h * h * wg[p] * wg[q] * (r + EPS) ** -3
                    J[ok] += hf[ok] * (ex - ap)
                    COUNT["near_cells"] += int(ok.sum())
    return J / (3 * EPS)


def kernel_sum_p(Y, X, V, a, p, budget=3_000_000):
    """sum_i V_i (|y - x_i| + a)^-p for every y (all pairs, chunked)."""
    out = np.empty(len(Y))
    c = max(1, budget // max(1, len(X)))
    for s in range(0, len(Y), c):
        Yc = Y[s:s + c]
        d2 = (Yc[:, 0, None] - X[None, :, 0]) ** 2
        d2 += (Yc[:, 1, None] - X[None, :, 1]) ** 2
        d2 += (Yc[:, 2, None] - X[None, :, 2]) ** 2
        out[s:s + c] = ((np.sqrt(d2) + a) ** -p) @ V
    COUNT["pairs"] += len(Y) * len(X)
    return out


def outer_rule_1d(lo, n, h, feats, d0, q, ng):
    """Per cell along one axis: (cell index, local coordinate in [0,1], weight); cells whose
    span (widened by h/2) holds a source face coordinate get the graded rule."""
    xg, wg = np.polynomial.legendre.leggauss(2)
    cells, xi, w = [], [], []
    for i in range(n):
        a, b = lo + i * h, lo + (i + 1) * h
        near = [f for f in feats if a - 0.5 * h <= f <= b + 0.5 * h]
        if near:
            x, ww = graded_1d(a, b, near, d0, q, ng)
        else:
            x, ww = a + 0.5 * h * (xg + 1), 0.5 * h * wg
        cells.append(np.full(len(x), i))
        xi.append((x - a) / h)
        w.append(ww)
    return np.concatenate(cells), np.concatenate(xi), np.concatenate(w)


SAMPLES = {  # where the expensive J is evaluated, in units of h from the grid's lower corner
    "n": lambda n: np.arange(n + 1.0),                      # the nodes
    "c": lambda n: np.arange(n) + 0.5,                      # the cell centres
    "g": lambda n: (np.arange(n)[:, None] + 0.5 + np.array([-0.5, 0.5]) / math.sqrt(3)).ravel(),
}


def sample_points(grid, at):
    ax = [grid.lo[a] + grid.h * SAMPLES[at](grid.n[a]) for a in range(3)]
    return np.stack(np.meshgrid(*ax, indexing="ij"), -1).reshape(-1, 3)


def layer(sd, b):
    """The eps-layer of the profile, P_eps(sd) - P_b(sd) (b = 0: P_eps alone): what the samples
    cannot resolve; it decays like pi (b - eps)/sd^2 away from the surface."""
    return P(sd, EPS) - (P(sd, b) if b > 0 else 0.0)


def outer_mean4(outer, Rs, src_lo, src_hi, src_vol, at="n", b=0.0, d0=EPS / 50, q=4.0, ng=4,
                mult=False):
    """(1/|Y|) int_Y d~^4: R = J - P_eps(sd) given at the sample points (at = n/c/g), interpolated
    piecewise trilinearly (extrapolated beyond the outermost samples), P_eps(sd) exact at every
    quadrature point of the outer cells."""
    rules = [outer_rule_1d(outer.lo[a], outer.n[a], outer.h, [src_lo[a], src_hi[a]], d0, q, ng)
             for a in range(3)]
    R = Rs.reshape(tuple(len(SAMPLES[at](outer.n[a])) for a in range(3)))
    lin = []
    for a in range(3):
        smp = SAMPLES[at](outer.n[a])
        cell, xi, w = rules[a]
        u = cell + xi
        iL = np.clip(np.searchsorted(smp, u) - 1, 0, len(smp) - 2)
        t = (u - smp[iL]) / (smp[iL + 1] - smp[iL])
        lin.append((iL, t, w, outer.lo[a] + outer.h * u))
    (ix, tx, wx, Yx), (iy, ty, wy, Yy), (iz, tz, wz, Yz) = lin
    total, npts = 0.0, 0
    step = max(1, 2_000_000 // (len(iy) * len(iz)))
    for s in range(0, len(ix), step):
        sl = slice(s, s + step)
        val = np.zeros((len(ix[sl]), len(iy), len(iz)))
        for a, b, c in itertools.product((0, 1), repeat=3):
            la = tx[sl] if a else 1 - tx[sl]
            lb = ty if b else 1 - ty
            lc = tz if c else 1 - tz
            val += (R[np.ix_(ix[sl] + a, iy + b, iz + c)]
                    * la[:, None, None] * lb[None, :, None] * lc[None, None, :])
        pts = np.stack(np.broadcast_arrays(Yx[sl, None, None], Yy[None, :, None],
                                           Yz[None, None, :]), -1).reshape(-1, 3)
        if mult:  # J = P_eps(sd) exp(R): R = log(J / P_eps(sd)), scale-free outside the body
            J = P(sd_box(pts, src_lo, src_hi), EPS) * np.exp(val.ravel())
        else:
            J = val.ravel() + layer(sd_box(pts, src_lo, src_hi), b)
        dt = (J / src_vol) ** -0.25 - EPS
        W = (wx[sl, None, None] * wy[None, :, None] * wz[None, None, :]).ravel()
        total += float(W @ dt ** 4)
        npts += len(pts)
    return total / outer.vol, npts


def directed(method, src, outer, opt):
    """A^4 = (1/|Y|) int_Y d~_X^4 (X = src, Y = outer) by the given method; returns (A^4, points)."""
    if method.startswith("colloc"):
        X, V = src.centres() if method.endswith("c") else src.nodes()
        Y, W = outer.centres() if method.endswith("c") else outer.nodes()
        S = kernel_sum(Y, X, V, EPS)
        dt = (S / V.sum()) ** -0.25 - EPS
        return float(W @ dt ** 4) / W.sum(), len(Y)
    inner, at = method.rsplit("/", 1)
    Y = sample_points(outer, at)
    sd = sd_box(Y, src.lo, src.hi)
    if inner.startswith("split"):
        X, V = src.centres() if inner.endswith("c") else src.nodes()
        a = opt.c_a * src.h
        Jn = kernel_sum(Y, X, V, a) + P(sd, EPS) - P(sd, a)
    elif inner == "bnd":
        Jn = J_boundary(Y, src, g=opt.g, c_near=opt.c_near, nu=opt.nu)
    elif inner == "near":
        Jn = J_near(Y, src, g=opt.g, c_near=opt.c_near, nu=opt.nu)
    else:
        raise ValueError(method)
    b = opt.c_b * outer.h
    Rn = np.log(Jn / P(sd, EPS)) if opt.mult else Jn - layer(sd, b)
    return outer_mean4(outer, Rn, src.lo, src.hi, src.vol, at=at, b=b, mult=opt.mult)


def rho(method, X, Y, opt):
    A4, n1 = directed(method, X, Y, opt)
    B4, n2 = directed(method, Y, X, opt)
    A, B = A4 ** 0.25, B4 ** 0.25
    return math.sqrt(0.5 * (A * A + B * B)), n1 + n2


METHODS = ["colloc-c", "colloc-n", "split-c/n", "split-n/n", "near/n", "near/c", "near/g"]


def run_case(writer, case, ref, X, Y, opt, methods):
    for m in methods:
        npair = len(X.nodes()[0]) * len(Y.nodes()[0])
        if m.startswith("near"):
            npair *= opt.g ** 3 * (8 if m.endswith("/g") else 1)
        if npair > opt.cap or (m.endswith("/c") and min(X.n.min(), Y.n.min()) < 2):
            continue  # too many pairs; or centres cannot interpolate across one cell
        COUNT["pairs"] = COUNT["near_cells"] = 0
        t = time.process_time()
        v, npts = rho(m, X, Y, opt)
        dt = time.process_time() - t
        err = (v / ref - 1) if ref else float("nan")
        row = [case, f"{X.h:.5g}", f"{Y.h:.5g}", m, f"{v:.6f}", f"{ref:.6f}" if ref else "",
               f"{100 * err:+.3f}", COUNT["pairs"], COUNT["near_cells"], npts, f"{dt:.2f}"]
        writer.writerow(row)
        sys.stdout.flush()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--suite", default="all")
    ap.add_argument("--cap", type=float, default=4e8, help="largest pair count per direction")
    ap.add_argument("--c-a", dest="c_a", type=float, default=1.0, help="a = c_a h (split)")
    ap.add_argument("--c-b", dest="c_b", type=float, default=0.0,
                    help="outer layer P_eps - P_b, b = c_b h_outer (0: P_eps alone)")
    ap.add_argument("--mult", action="store_true",
                    help="interpolate log(J / P_eps(sd)) instead of J - P_eps(sd)")
    ap.add_argument("--g", type=int, default=2, help="far Gauss points per axis (near)")
    ap.add_argument("--c-near", dest="c_near", type=float, default=1.5)
    ap.add_argument("--nu", type=int, default=20, help="angle points of the exact cells")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--ns", default="4,8,12,16,24,32,64", help="cube cells per side")
    here = __import__("os").path.dirname(__import__("os").path.abspath(__file__))
    ap.add_argument("--ref", default=here + "/../docs/bench/continuum_reference.json",
                    help="continuum_reference.py --json outputs (comma-separated)")
    ap.add_argument("--shifts", default="0,0.0025,0.005,0.01,0.02")
    ap.add_argument("--csv")
    opt = ap.parse_args()
    import json
    for f in opt.ref.split(","):
        try:
            vals = json.load(open(f))["values"]
        except (OSError, KeyError, ValueError):
            continue
        for k, v in vals.items():
            REF[float(k) if k[0].isdigit() else k] = v["levels"][-1]
    methods = opt.methods.split(",")
    out = open(opt.csv, "w") if opt.csv else sys.stdout
    w = csv.writer(out)
    w.writerow(["case", "hX", "hY", "method", "rho", "ref", "err_pct", "pairs", "near_cells",
                "outer_points", "cpu_s"])
    ns = [int(s) for s in opt.ns.split(",")]
    unit = ([0, 0, 0], [1, 1, 1])
    if opt.suite in ("self", "all"):
        for nx, ny in itertools.product(ns, ns):
            if nx <= ny:
                run_case(w, "self", REF["self"], Grid(*unit, 1 / nx), Grid(*unit, 1 / ny), opt, methods)
    if opt.suite in ("shift", "all"):
        for n2 in (16, 12):
            for s in [float(v) for v in opt.shifts.split(",")]:
                Y = Grid([s, 0, 0], [1 + s, 1, 1], 1 / n2)
                run_case(w, f"shift{s}", REF[s] if s else REF["self"], Grid(*unit, 1 / 16), Y, opt, methods)
    if opt.suite in ("rank", "all"):
        for n2 in (16, 12):
            h = 1 / 16
            run_case(w, "rank-side0.875", REF["side0.875"], Grid(*unit, h),
                     Grid([0.0625] * 3, [0.9375] * 3, h if n2 == 16 else 0.875 / 11), opt, methods)
            run_case(w, "rank-shift1/16", REF[0.0625], Grid(*unit, h), Grid([h, 0, 0], [1 + h, 1, 1], 1 / n2), opt, methods)
    if opt.suite in ("plate", "all"):
        for hx, hy in ((0.1, 0.1), (0.1, 0.05), (0.05, 0.05)):
            run_case(w, "plate", REF["plate"], Grid([0, 0, 0], [10, 2, 0.1], hx),
                     Grid([0, 0, 0], [10, 2, 0.1], hy), opt, methods)
    return 0


if __name__ == "__main__":
    sys.exit(main())
