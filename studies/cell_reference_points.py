#!/usr/bin/python3
"""Reference values of the unit cube's inner integral J(y) = int_cube (|y - x| + eps)^-4 dx
(eps = 1e-3) at 250 points, for `tools/bench_body_integral accuracy FILE` (formulation §2.8):
150 uniform in [-0.3, 1.3]^3 and 100 within 3 eps of a face (inside and outside), numpy seed 3,
by the box code of studies/continuum_reference.py (corner boxes, 96 angle points).

    /usr/bin/python3 studies/cell_reference_points.py OUT.txt     (x y z J per line)
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from continuum_reference import J_box, Rule  # noqa: E402

if len(sys.argv) != 2:
    sys.exit(__doc__)
rng = np.random.default_rng(3)
P = [rng.uniform(-0.3, 1.3, (150, 3))]
Q = rng.uniform(0, 1, (100, 3))
ax = rng.integers(0, 3, 100)
off = rng.uniform(-3e-3, 3e-3, 100)
Q[np.arange(100), ax] = np.where(rng.integers(0, 2, 100) == 1, 1 + off, off)
P.append(Q)
P = np.vstack(P)
J = J_box(P, np.zeros(3), np.ones(3), 1e-3, Rule(96))
np.savetxt(sys.argv[1], np.column_stack([P, J]), fmt="%.17g")
