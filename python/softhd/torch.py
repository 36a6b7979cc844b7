"""softhd.torch: the regularised Hausdorff distance as a PyTorch loss with its exact gradient.

    loss = softhd.torch.HausdorffLoss(alpha=4, eps=1e-3)
    value = loss(X, Y)            # X (N, d), Y (M, d) CPU tensors; optional volumes VX, VY
    value.backward()              # X.grad = d rho / d X (exact, docs/formulation.md §2)

The value and gradients come from the C++ library (one call of softhd.distance per forward;
a second one, with the clouds swapped, only when VY requires a gradient: rho is symmetric in
the two clouds, so d rho / d VY is the volume gradient of rho(Y, X)). Gradients are computed
in the forward pass for exactly the inputs that require them. Tensors are read without a copy
when they are contiguous float64; float32 inputs are converted to float64 for the computation
and the value and gradients returned as float32. Double backward is not supported.
"""

import numpy as np
import torch

import softhd as _softhd


def _array(t, name):
    if not isinstance(t, torch.Tensor):
        raise TypeError(f"{name} must be a torch.Tensor, got {type(t).__name__}")
    if t.device.type != "cpu":
        raise ValueError(f"{name} must be a CPU tensor (softhd computes on the CPU), got {t.device}")
    if t.dtype not in (torch.float32, torch.float64):
        raise TypeError(f"{name} must be float32 or float64, got {t.dtype}")
    return t.detach().to(torch.float64).contiguous().numpy()


def _tensor(a, like):
    return torch.from_numpy(np.ascontiguousarray(a)).to(like.dtype)


class HausdorffFunction(torch.autograd.Function):
    """rho_H(X, Y) with volumes VX, VY (None: all 1) as an autograd Function.

    apply(X, Y, VX, VY, options): options is a dict of softhd.distance keyword arguments
    (alpha, beta, gamma, eps, method, tol, threads, distance, cap, cap_q, camera_mask).
    """

    @staticmethod
    def forward(ctx, X, Y, VX, VY, options):
        need_x, need_y, need_vx, need_vy = ctx.needs_input_grad[:4]
        x, y = _array(X, "X"), _array(Y, "Y")
        vx = None if VX is None else _array(VX, "VX")
        vy = None if VY is None else _array(VY, "VY")
        r = _softhd.distance(x, y, vx, vy, gradient=need_x, gradient_volumes=need_vx,
                             gradient_target=need_y, **options)
        ctx.grads = [
            _tensor(r.gradient, X) if need_x else None,
            _tensor(r.gradient_target, Y) if need_y else None,
            _tensor(r.gradient_volumes, VX) if need_vx else None,
            None,
        ]
        if need_vy:  # rho(X, Y) = rho(Y, X): d rho / d VY is the moving-volume gradient swapped
            if options.get("distance", "symmetric") != "symmetric":
                raise NotImplementedError(
                    "d rho / d VY needs distance='symmetric' (the one-sided and visible forms "
                    "are not symmetric in X and Y); make VY a constant")
            swapped = _softhd.distance(y, x, vy, vx, gradient_volumes=True, **options)
            ctx.grads[3] = _tensor(swapped.gradient_volumes, VY)
        return torch.tensor(r.rho, dtype=X.dtype)

    @staticmethod
    @torch.autograd.function.once_differentiable
    def backward(ctx, grad_output):
        grads = [None if g is None else grad_output * g for g in ctx.grads]
        return (*grads, None)


class HausdorffLoss(torch.nn.Module):
    """The regularised Hausdorff distance rho_H (docs/formulation.md §2) as a loss module.

    alpha, beta, gamma, eps: the functional's parameters (paper defaults 4, 4, 2, 1e-3; eps is
    an absolute length). method: "exact" (all pairs) or "tree" (every kernel sum within
    relative tolerance tol). threads: OpenMP threads; 0 (default): torch.get_num_threads(), the
    count PyTorch itself uses (importing torch may lower the process's OpenMP default, e.g. to 1
    on a machine whose cores are hyperthreads of one physical core).

    distance, cap, cap_q: the form of docs/formulation.md §8 (as softhd.distance): "symmetric"
    (default), "scan_to_body" (rho = A: Y is a partial scan, the hidden parts of X are not
    punished) or "visible" (B over the points of X marked in forward's ``camera_mask``); cap > 0
    applies the soft cap psi_c(d) = (d^-q + c^-q)^(-1/q), q = cap_q, to every field value.

    forward(X, Y, VX=None, VY=None, camera_mask=None): X (N, d) and Y (M, d) CPU tensors
    (d = 2 or 3), float32 or float64; VX (N,) and VY (M,) optional positive volumes (weights;
    only their ratios matter); camera_mask (N,): the points of X a camera sees, booleans or 0/1
    (tensor or array; other values raise softhd.InvalidArgument; the retired keyword visible
    raises TypeError naming camera_mask), with distance="visible" only, held fixed (no gradient). Returns a
    0-dimensional tensor of X's dtype; gradients flow to every input that requires one (points,
    target points, and either set of weights; VY only for the symmetric form, the others raise
    NotImplementedError for it).
    """

    def __init__(self, alpha=4.0, beta=4.0, gamma=2.0, eps=1e-3, method="exact", tol=1e-6,
                 threads=0, distance="symmetric", cap=0.0, cap_q=4.0):
        super().__init__()
        if method == "nearest":
            raise ValueError("method 'nearest' has no gradient; use softhd.hausdorff_nearest")
        if distance not in ("symmetric", "scan_to_body", "visible"):
            raise ValueError(f"distance must be 'symmetric', 'scan_to_body' or 'visible', "
                             f"got {distance!r}")
        self.options = dict(alpha=alpha, beta=beta, gamma=gamma, eps=eps, method=method, tol=tol,
                            threads=threads, distance=distance, cap=cap, cap_q=cap_q)

    def forward(self, X, Y, VX=None, VY=None, camera_mask=None, visible=None):
        options = dict(self.options)
        if options["threads"] == 0:
            options["threads"] = torch.get_num_threads()
        _softhd._retired_visible(visible)
        if camera_mask is not None:
            if isinstance(camera_mask, torch.Tensor):
                camera_mask = camera_mask.detach().cpu().numpy()
            options["camera_mask"] = camera_mask  # booleans or 0/1 (softhd.distance refuses others)
        return HausdorffFunction.apply(X, Y, VX, VY, options)

    def extra_repr(self):
        return ", ".join(f"{k}={v}" for k, v in self.options.items())
