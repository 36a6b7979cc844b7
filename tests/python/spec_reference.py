"""Independent implementations of the regularised Hausdorff distance of docs/formulation.md §2
(docs/formulation.md §2), written from the formulas, not from the library:

- rho_numpy: NumPy, float64, all pairs at once (small clouds; the tests' oracle);
- rho_torch: plain PyTorch, float64, chunked cdist + logsumexp, autograd for every input
  (the "plain PyTorch implementation" the issue compares HausdorffLoss with).

    I_X(y) = ((1/|X|) sum_i V_i phi(|y - x_i|)^alpha)^(1/alpha),  phi(t) = 1/(t + eps)
    d_X(y) = 1/I_X(y) - eps
    A = ((1/|Y|) sum_j W_j d_X(y_j)^beta)^(1/beta),  B likewise with X and Y swapped
    rho = ((A^gamma + B^gamma)/2)^(1/gamma)
"""

import numpy as np


def _directed_numpy(P, VP, Q, VQ, alpha, beta, eps):
    """The mean over Q of the regularised distance to P: A when P = X, Q = Y."""
    r = np.sqrt(((Q[:, None, :] - P[None, :, :]) ** 2).sum(axis=2))  # |Q| by |P|
    log_terms = np.log(VP / VP.sum())[None, :] - alpha * np.log(r + eps)
    top = log_terms.max(axis=1, keepdims=True)
    log_s = top[:, 0] + np.log(np.exp(log_terms - top).sum(axis=1))  # log sum_i (V_i/|P|) phi^a
    d = np.exp(-log_s / alpha) - eps  # 1/I - eps
    return ((VQ / VQ.sum()) * d ** beta).sum() ** (1.0 / beta)


def rho_numpy(X, Y, VX=None, VY=None, alpha=4.0, beta=4.0, gamma=2.0, eps=1e-3):
    """(rho, A, B) of docs/formulation.md §2, NumPy float64 (small clouds)."""
    X, Y = np.asarray(X, float), np.asarray(Y, float)
    VX = np.ones(len(X)) if VX is None else np.asarray(VX, float)
    VY = np.ones(len(Y)) if VY is None else np.asarray(VY, float)
    A = _directed_numpy(X, VX, Y, VY, alpha, beta, eps)
    B = _directed_numpy(Y, VY, X, VX, alpha, beta, eps)
    return ((A ** gamma + B ** gamma) / 2.0) ** (1.0 / gamma), A, B


def _directed_torch(P, VP, Q, VQ, alpha, beta, eps, chunk):
    import torch

    log_w = torch.log(VP / VP.sum())
    parts = []
    for start in range(0, Q.shape[0], chunk):
        r = torch.cdist(Q[start:start + chunk], P)
        log_s = torch.logsumexp(log_w[None, :] - alpha * torch.log(r + eps), dim=1)
        parts.append(torch.exp(-log_s / alpha) - eps)
    d = torch.cat(parts)
    return ((VQ / VQ.sum()) * d ** beta).sum() ** (1.0 / beta)


def rho_torch(X, Y, VX=None, VY=None, alpha=4.0, beta=4.0, gamma=2.0, eps=1e-3, chunk=1024):
    """rho of docs/formulation.md §2 in plain PyTorch (differentiable in every tensor argument)."""
    import torch

    VX = torch.ones(X.shape[0], dtype=X.dtype) if VX is None else VX
    VY = torch.ones(Y.shape[0], dtype=Y.dtype) if VY is None else VY
    A = _directed_torch(X, VX, Y, VY, alpha, beta, eps, chunk)
    B = _directed_torch(Y, VY, X, VX, alpha, beta, eps, chunk)
    return ((A ** gamma + B ** gamma) / 2.0) ** (1.0 / gamma)


def hausdorff_numpy(X, Y):
    """(H, max_j dist(y_j, X), max_i dist(x_i, Y)): the exact Hausdorff distance, brute force."""
    r = np.sqrt(((np.asarray(Y)[:, None, :] - np.asarray(X)[None, :, :]) ** 2).sum(axis=2))
    a, b = r.min(axis=1).max(), r.min(axis=0).max()
    return max(a, b), a, b
