"""softhd.torch.HausdorffLoss: gradcheck in float64, float32, weights, the target, and
agreement with a plain PyTorch implementation of docs/formulation.md §2 (spec_reference.rho_torch)."""

import pytest

torch = pytest.importorskip(
    "torch", reason="PyTorch is not installed (Debian: apt-get install python3-torch); "
    "the HausdorffLoss tests are skipped")

import softhd
import softhd.torch as st  # noqa: E402
from spec_reference import rho_torch  # noqa: E402


def clouds(n=9, m=7, d=3, dtype=torch.float64, seed=3):
    g = torch.Generator().manual_seed(seed)
    X = torch.rand(n, d, generator=g, dtype=dtype)
    Y = torch.rand(m, d, generator=g, dtype=dtype) + 0.2
    VX = 0.5 + torch.rand(n, generator=g, dtype=dtype)
    VY = 0.5 + torch.rand(m, generator=g, dtype=dtype)
    return X, Y, VX, VY


@pytest.mark.parametrize("d", [2, 3])
def test_gradcheck_every_input(d):
    X, Y, VX, VY = (t.requires_grad_() for t in clouds(d=d))
    loss = st.HausdorffLoss(alpha=4.0, eps=0.05)
    assert torch.autograd.gradcheck(lambda *a: loss(*a), (X, Y, VX, VY), eps=1e-6, atol=1e-8,
                                    rtol=1e-6)


def test_gradcheck_tree_method():
    X, Y, _, _ = clouds(n=30, m=25)
    X.requires_grad_()
    loss = st.HausdorffLoss(eps=0.05, method="tree", tol=1e-12)
    assert torch.autograd.gradcheck(lambda x: loss(x, Y), (X,), eps=1e-6, atol=1e-7, rtol=1e-5)


def test_only_requested_gradients():
    X, Y, VX, VY = clouds()
    X.requires_grad_()
    loss = st.HausdorffLoss()
    loss(X, Y, VX, VY).backward()
    assert X.grad is not None and Y.grad is None and VX.grad is None and VY.grad is None


def test_equals_plain_pytorch_value_and_gradients():
    X, Y, VX, VY = clouds(n=200, m=150)
    params = dict(alpha=6.0, beta=3.0, gamma=2.0, eps=1e-2)
    ours = [t.clone().requires_grad_() for t in (X, Y, VX, VY)]
    ref = [t.clone().requires_grad_() for t in (X, Y, VX, VY)]
    a = st.HausdorffLoss(**params)(*ours)
    b = rho_torch(*ref, **params, chunk=64)
    assert a.item() == pytest.approx(b.item(), rel=1e-12)
    a.backward()
    b.backward()
    for p, q in zip(ours, ref):
        torch.testing.assert_close(p.grad, q.grad, rtol=1e-9, atol=1e-12)


def test_float32_in_float32_out():
    X, Y, VX, _ = clouds(dtype=torch.float32)
    X.requires_grad_()
    VX.requires_grad_()
    value = st.HausdorffLoss()(X, Y, VX)
    assert value.dtype == torch.float32
    value.backward()
    assert X.grad.dtype == torch.float32 and VX.grad.dtype == torch.float32
    X64, Y64, VX64 = X.detach().double().requires_grad_(), Y.double(), VX.detach().double()
    v64 = st.HausdorffLoss()(X64, Y64, VX64)
    v64.backward()
    assert value.item() == pytest.approx(v64.item(), rel=1e-6)
    torch.testing.assert_close(X.grad, X64.grad.float())


def test_chain_rule_through_the_loss():
    X, Y, _, _ = clouds()
    s = torch.tensor(1.5, dtype=torch.float64, requires_grad=True)
    loss = st.HausdorffLoss(eps=0.05)
    (3.0 * loss(s * X, Y)).backward()
    X2 = (s.detach() * X).requires_grad_()
    loss(X2, Y).backward()
    assert s.grad.item() == pytest.approx(3.0 * (X2.grad * X).sum().item(), rel=1e-12)


def test_misuse():
    X, Y, _, _ = clouds()
    with pytest.raises(ValueError, match="nearest"):
        st.HausdorffLoss(method="nearest")
    with pytest.raises(TypeError, match="float32 or float64"):
        st.HausdorffLoss()(X.to(torch.int64), Y)
    with pytest.raises(TypeError, match="torch.Tensor"):
        st.HausdorffLoss()(X.numpy(), Y)
    with pytest.raises(ValueError, match="eps"):
        st.HausdorffLoss(eps=-1.0)(X, Y)
    # Issue 29: NaN gradients at eps=1e-320, a segfault at threads=100000.
    with pytest.raises(ValueError, match="epsilon must be at least 1e-300"):
        st.HausdorffLoss(eps=1e-320)(X, Y)
    with pytest.raises(ValueError, match="threads must be from 0 to 1024"):
        st.HausdorffLoss(threads=100000)(X, Y)


def test_threads_default_to_torchs_count(monkeypatch):
    import softhd

    seen = []
    real = softhd.distance
    def spy(*args, **kwargs):
        seen.append(kwargs["threads"])
        return real(*args, **kwargs)

    monkeypatch.setattr(softhd, "distance", spy)
    X, Y, _, _ = clouds()
    st.HausdorffLoss()(X, Y)
    st.HausdorffLoss(threads=2)(X, Y)
    assert seen == [torch.get_num_threads(), 2]


@pytest.mark.parametrize("form", [dict(distance="scan_to_body"), dict(distance="visible"),
                                  dict(cap=0.3, cap_q=3.0),
                                  dict(distance="visible", cap=0.3)])
def test_gradcheck_distance_forms(form):
    """The forms of docs/formulation.md §8: points, target points and moving volumes."""
    X, Y, VX, VY = clouds()
    X.requires_grad_(), Y.requires_grad_(), VX.requires_grad_()
    visible = torch.tensor([True, False, True, True, False, True, True, False, True])
    loss = st.HausdorffLoss(eps=0.05, **form)
    vis = visible if form.get("distance") == "visible" else None
    assert torch.autograd.gradcheck(lambda x, y, vx: loss(x, y, vx, VY, camera_mask=vis),
                                    (X, Y, VX), eps=1e-6, atol=1e-8, rtol=1e-6)


def test_forms_misuse():
    X, Y, _, VY = clouds()
    loss = st.HausdorffLoss(distance="visible")
    one_zero = torch.tensor([1, 0, 1, 1, 0, 1, 1, 0, 1], dtype=torch.float64)
    assert loss(X, Y, camera_mask=one_zero) == loss(X, Y, camera_mask=one_zero.bool())
    with pytest.raises(TypeError, match="visible is now camera_mask"):
        loss(X, Y, visible=one_zero)
    for value in (0.5, 2.0):  # not a boolean: refused, not read as True
        bad = one_zero.clone()
        bad[1] = value
        with pytest.raises(softhd.InvalidArgument, match="camera_mask must hold booleans"):
            loss(X, Y, camera_mask=bad)
    with pytest.raises(ValueError, match="distance must be"):
        st.HausdorffLoss(distance="both")
    VY.requires_grad_()
    with pytest.raises(NotImplementedError, match="VY needs distance='symmetric'"):
        st.HausdorffLoss(distance="scan_to_body")(X, Y, None, VY)
