"""PyTorch: torch.optim.Adam on a staircase, with the gradient from plateau_free.torch.

    python python/examples/torch_adam.py        # needs pip install "plateau-free[torch]"

`f` is flat between integers, so autograd's own gradient would be zero everywhere.
"""

import numpy as np
import torch

import plateau_free.torch

target = np.array([1.0, -2.0])


def f(x):
    return float(np.sum((np.floor(x) - target) ** 2))


g = plateau_free.torch.wrap(f, sigma=0.3, samples=8)
theta = torch.tensor([-2.5, 2.5], dtype=torch.float64, requires_grad=True)
optimizer = torch.optim.Adam([theta], lr=0.05)
for seed in range(300):  # a new seed each step: independent estimates
    optimizer.zero_grad()
    g(theta, seed).backward()
    optimizer.step()
print("PyTorch:", theta.detach().numpy())  # in [1, 2) x [-2, -1)
assert np.array_equal(np.floor(theta.detach().numpy()), target)
