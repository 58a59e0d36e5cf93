"""What the Python binding and its adapters (JAX, PyTorch, scipy, Dr.Jit, Ray) cost per call."""
