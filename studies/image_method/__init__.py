"""The image method (``least_squares``) on the path tracer's tasks: docs/results/image-method.md."""
