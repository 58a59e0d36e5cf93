"""The examples of docs/integrations.md run: the one Python block of each adapter's section
(JAX, PyTorch, scipy, nevergrad, Dr.Jit / Mitsuba), executed as written, each ending in its own assertion."""

from __future__ import annotations

import os
import re

import pytest

PAGE = os.path.join(os.path.dirname(__file__), "..", "..", "docs", "integrations.md")


def section_examples(heading):
    """The ```python blocks of the section `## heading` of the page."""
    with open(PAGE, encoding="utf-8") as page:
        text = page.read()
    sections = re.split(r"^## ", text, flags=re.MULTILINE)
    (section,) = [s for s in sections if s.startswith(heading + "\n")]
    return re.findall(r"^```python\n(.*?)^```", section, flags=re.MULTILINE | re.DOTALL)


@pytest.mark.parametrize("heading", ["JAX", "PyTorch", "scipy", "nevergrad", "Dr.Jit / Mitsuba"])
def test_the_sections_example_runs(heading):
    (example,) = section_examples(heading)
    exec(compile(example, f"{PAGE} ({heading})", "exec"), {"__name__": "__example__"})
