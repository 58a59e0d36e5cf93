"""The package's types hold together: its modules (``__init__.py``, ``_minimize.py``, ...,
``ray.py``, the adapters ``jax.py``, ``torch.py``, ``scipy.py``) are typed inline, the extension
by ``_native.pyi``, and mypy in strict mode checks the one against the other."""

import os
import subprocess
import sys
import tempfile


def test_mypy_strict_finds_no_issue_in_the_package():
    # Run from an empty folder so that the installed package is checked, not the sources.
    with tempfile.TemporaryDirectory() as folder:
        done = subprocess.run(
            [sys.executable, "-m", "mypy", "--strict", "--no-incremental", "-p", "plateau_free"],
            cwd=folder,
            capture_output=True,
            text=True,
            env={**os.environ, "MYPYPATH": ""},
        )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "no issues found" in done.stdout
