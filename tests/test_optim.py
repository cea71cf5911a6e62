"""pusht.optim.Adam: torch's fused Adam update, without torch.optim's per-step and import overhead."""

import subprocess
import sys

import pytest
import torch

from pusht.optim import Adam


def _train(make_opt, steps=40):
    torch.manual_seed(0)
    net = torch.nn.Sequential(torch.nn.Linear(6, 12), torch.nn.Tanh(), torch.nn.Linear(12, 3))
    late = torch.nn.Parameter(torch.randn(4))          # gets no gradient for the first 10 steps
    params = list(net.parameters()) + [late]
    opt = make_opt(params)
    gen = torch.Generator().manual_seed(1)
    for i in range(steps):
        x = torch.randn(16, 6, generator=gen)
        loss = net(x).pow(2).mean() + (late.pow(2).sum() if i >= 10 else 0.0)
        opt.zero_grad()
        loss.backward()
        opt.step()
    return [p.detach().clone() for p in params]


def test_updates_are_bit_identical_to_torch_fused_adam():
    ours = _train(lambda ps: Adam(ps, lr=3e-3))
    torch_s = _train(lambda ps: torch.optim.Adam(ps, lr=3e-3, fused=True))
    assert all(torch.equal(a, b) for a, b in zip(ours, torch_s))
    # and training did move the parameters (a test that compares two no-ops would pass too)
    untrained = _train(lambda ps: Adam(ps, lr=3e-3), steps=0)
    assert not torch.equal(ours[0], untrained[0])


def test_a_parameter_without_gradient_is_left_alone():
    a, b = torch.nn.Parameter(torch.ones(3)), torch.nn.Parameter(torch.ones(3))
    opt = Adam([a, b], lr=0.1)
    opt.zero_grad()
    (a * 2).sum().backward()
    opt.step()
    assert torch.equal(b.detach(), torch.ones(3)) and not torch.equal(a.detach(), torch.ones(3))
    assert b.grad is None and b not in opt.state


def test_training_imports_no_compiler():
    """torch.optim's first step imports torch._dynamo (over a second per process); ours must not."""
    code = ("import sys, torch\nfrom pusht.optim import Adam\n"
            "p = torch.nn.Parameter(torch.ones(2)); o = Adam([p], lr=1e-2)\n"
            "o.zero_grad(); p.sum().backward(); o.step()\n"
            "print('torch._dynamo' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize("params, lr, match", [
    ([], 1e-3, "no parameters"),
    ([torch.zeros(2, dtype=torch.long)], 1e-3, "floating-point"),
    (["w"], 1e-3, "floating-point"),
    ([torch.nn.Parameter(torch.zeros(2))], 0.0, "learning rate"),
    ([torch.nn.Parameter(torch.zeros(2))], float("nan"), "learning rate"),
])
def test_bad_arguments_get_a_clear_error(params, lr, match):
    with pytest.raises((TypeError, ValueError), match=match):
        Adam(params, lr=lr)
