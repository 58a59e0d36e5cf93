"""The README's example: minimize a staircase, flat almost everywhere, from values alone.

    python python/examples/minimize.py
"""

import numpy as np

import plateau_free

# The squared distance of the rounded point to an integer target: every plain gradient is zero.
target = np.array([1.0, -2.0, 3.0])


def stairs(x):
    return float(np.sum((np.floor(x + 0.5) - target) ** 2))


# The default method: a budget of evaluations, no step size, no learning rate.
best = plateau_free.minimize(stairs, [0.0, 0.0, 0.0], budget=2000, seed=1)
print("minimize:", best.x, best.fun, best.nfev, best.message)
assert best.fun == 0.0

# The paper's loop (plateau-free gradient, Adam, annealed sigma) with its own settings.
paper = plateau_free.minimize(stairs, [0.0, 0.0, 0.0], method="plateau", sigma0=0.5,
                              iterations=300, lr=0.05, samples=8, seed=1)
print("paper's loop:", paper.x, paper.fun, paper.nfev)
