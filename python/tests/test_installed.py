"""The package under test is the one users install: the wheel built from this repository, with
the version written once in the workspace's Cargo.toml, not the source tree."""

import importlib.metadata
import re
import sysconfig
from pathlib import Path

import plateau_free

REPO = Path(__file__).resolve().parents[2]


def cargo_version() -> str:
    """The workspace's version ([workspace.package] in the root Cargo.toml)."""
    manifest = (REPO / "Cargo.toml").read_text()
    section = manifest[manifest.index("[workspace.package]"):]
    match = re.search(r'^version = "([^"]+)"', section, re.MULTILINE)
    assert match, "no version in [workspace.package]"
    return match.group(1)


def test_the_import_is_the_installed_distribution_not_the_sources():
    where = Path(plateau_free.__file__).resolve()
    assert where.parent.name == "plateau_free"
    assert where.parent.parent == Path(sysconfig.get_paths()["platlib"]).resolve(), where
    assert REPO / "python" not in where.parents, f"imported from the source tree: {where}"
    # The extension sits beside the Python modules, built for the stable ABI.
    assert (where.parent / "_native.abi3.so").is_file()


def test_one_version_everywhere():
    version = cargo_version()
    assert plateau_free.__version__ == version
    assert importlib.metadata.version("plateau-free") == version


def test_the_wheel_is_abi3_and_declares_its_licenses_and_extras():
    dist = importlib.metadata.distribution("plateau-free")
    tags = [line for line in (dist.read_text("WHEEL") or "").splitlines() if line.startswith("Tag:")]
    assert tags and all("-abi3-" in tag and tag.startswith("Tag: cp39-") for tag in tags), tags
    meta = dist.metadata
    assert meta["License-Expression"] == "MIT OR Apache-2.0"
    assert sorted(meta.get_all("License-File") or []) == ["LICENSE-APACHE", "LICENSE-MIT"]
    assert {"ray", "mitsuba", "jax", "torch", "scipy", "nevergrad", "test"} <= set(meta.get_all("Provides-Extra") or [])
    assert any(req.startswith("numpy") for req in dist.requires or [])
