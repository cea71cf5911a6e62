"""Adam, the update of ``torch.optim.Adam(params, lr, fused=True)``, without torch.optim's machinery.

The chapter's models are tiny, so their training is bound by per-call overhead, not arithmetic
(``benchmarks/pipeline_wallclock.txt``). ``torch.optim.Optimizer.step`` pays some of it on every
update (hooks, parameter groups, grouping tensors by device and dtype), and the first call of any
torch optimizer imports ``torch._dynamo`` (its methods are wrapped to keep the compiler out),
which costs over a second in every process that trains: every ``python -m pusht.dreamer`` run and
every notebook kernel. This class calls the very kernel ``Adam(fused=True)`` calls,
``torch._fused_adam_``, on the same state, so its updates are bit-identical to torch's
(``tests/test_optim.py`` checks it against ``torch.optim.Adam(fused=True)``), and it imports
nothing. It is Adam without weight decay, amsgrad or gradient scaling, which is all the chapter
uses; for anything else, use ``torch.optim.Adam``.
"""

from __future__ import annotations

import torch

_HAS_FUSED_CPU = hasattr(torch, "_fused_adam_") and tuple(
    int(x) for x in torch.__version__.split("+")[0].split(".")[:2] if x.isdigit()) >= (2, 4)


class Adam:
    """``Adam(params, lr)``: ``zero_grad()`` then ``backward()`` then ``step()``, as with torch.optim.

    Like torch's, a parameter whose ``.grad`` is None is skipped by ``step`` (and gets its state
    the first time it has a gradient)."""

    def __init__(self, params, lr: float, betas: tuple = (0.9, 0.999), eps: float = 1e-8):
        self.params = list(params)
        if not self.params:
            raise ValueError("Adam got no parameters to optimise")
        for p in self.params:
            if not isinstance(p, torch.Tensor) or not p.is_floating_point() or p.is_sparse:
                raise TypeError(f"Adam optimises dense floating-point tensors, got {type(p).__name__}"
                                f"{'' if not isinstance(p, torch.Tensor) else ' of ' + str(p.dtype)}")
        if not lr > 0:
            raise ValueError(f"Adam's learning rate must be positive, got {lr}")
        self.lr, self.betas, self.eps = float(lr), (float(betas[0]), float(betas[1])), float(eps)
        self.state: dict = {}          # param -> (exp_avg, exp_avg_sq, step), as torch.optim.Adam keeps
        # torch before 2.4 (Colab may bring one) has no fused CPU kernel: use torch's own Adam there.
        self._torch = None if _HAS_FUSED_CPU else torch.optim.Adam(self.params, lr=self.lr, betas=self.betas,
                                                                   eps=self.eps)

    def zero_grad(self) -> None:
        for p in self.params:
            p.grad = None

    @torch.no_grad()
    def step(self) -> None:
        if self._torch is not None:
            self._torch.step()
            return
        params, grads, exp_avgs, exp_avg_sqs, steps = [], [], [], [], []
        for p in self.params:
            if p.grad is None:
                continue
            state = self.state.get(p)
            if state is None:
                state = self.state[p] = (torch.zeros_like(p, memory_format=torch.preserve_format),
                                         torch.zeros_like(p, memory_format=torch.preserve_format),
                                         torch.zeros((), dtype=torch.float32, device=p.device))
            params.append(p)
            grads.append(p.grad)
            exp_avgs.append(state[0])
            exp_avg_sqs.append(state[1])
            steps.append(state[2])
        if not params:
            return
        torch._foreach_add_(steps, 1)
        torch._fused_adam_(params, grads, exp_avgs, exp_avg_sqs, [], steps, amsgrad=False, lr=self.lr,
                           beta1=self.betas[0], beta2=self.betas[1], weight_decay=0.0, eps=self.eps,
                           maximize=False, grad_scale=None, found_inf=None)
