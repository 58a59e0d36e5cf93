"""The examples of python/examples run and end as they say, each in its own process; and
python/examples/README.md names every one of them.

JAX and PyTorch are pinned in python/requirements-test.txt, so their examples always run;
Mitsuba's is skipped without mitsuba, unless PLATEAU_FREE_REQUIRE_MITSUBA=1 (as scripts/test-all
sets it) makes that a failure."""

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "python" / "examples"
REQUIRE_MITSUBA = os.environ.get("PLATEAU_FREE_REQUIRE_MITSUBA") == "1"


def run(name, *args, timeout=600):
    p = subprocess.run([sys.executable, str(EXAMPLES / name), *args], capture_output=True,
                       text=True, timeout=timeout, cwd=EXAMPLES)
    assert p.returncode == 0, p.stdout + p.stderr
    return p.stdout


needs_mitsuba = pytest.mark.skipif(
    importlib.util.find_spec("mitsuba") is None and not REQUIRE_MITSUBA,
    reason="mitsuba is not installed (scripts/install-mitsuba)",
)


def test_the_readme_names_every_example_and_there_are_at_most_five():
    examples = sorted(p.name for p in EXAMPLES.glob("*.py"))
    readme = (EXAMPLES / "README.md").read_text()
    assert 0 < len(examples) <= 5
    assert [e for e in examples if f"`{e}`" not in readme] == []


def test_minimize_reaches_the_bottom_of_the_staircase():
    out = run("minimize.py")
    assert "minimize:" in out and "paper's loop:" in out


def test_ask_tell_gives_minimize_s_result():
    assert "ask and tell:" in run("ask_tell.py")


def test_jax_pipeline_reaches_the_target():
    assert "JAX:" in run("jax_pipeline.py")


def test_torch_adam_reaches_the_target_box():
    assert "PyTorch:" in run("torch_adam.py")


@needs_mitsuba
def test_mitsuba_shadow_finds_the_target_in_its_default_400_renders():
    # The example asserts the target's very image (loss 0.0); with 200 renders the search
    # ends a few thousandths away.
    out = run("mitsuba_shadow.py")
    assert "start: loss" in out and re.search(r"after \d+ renders", out), out
