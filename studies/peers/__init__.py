"""Other optimisers on the same problems: pycma and nevergrad (docs/results/compare.md, docs/results/nevergrad.md)."""
