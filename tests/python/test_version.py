"""One version, set in CMakeLists.txt: the wheel's metadata rule, the built core and CHANGELOG.md follow it (the add-on's
manifest and bl_info are checked in test_packaging.py's test_one_version_everywhere)."""
import pathlib
import re

import meniscus

ROOT = pathlib.Path(__file__).resolve().parents[2]
VERSION = re.search(r"^project\(meniscus VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text(), re.M).group(1)


def test_built_core_reports_cmakes_version():
    assert meniscus.__version__ == VERSION


def test_wheel_takes_its_version_from_cmake():
    pyproject = (ROOT / "pyproject.toml").read_text()
    assert 'dynamic = ["version"]' in pyproject
    rule = re.search(r"^regex = '(.*)'$", pyproject, re.M).group(1)
    assert re.search(rule, (ROOT / "CMakeLists.txt").read_text()).group("value") == VERSION


def test_changelog_has_the_current_version_and_unreleased():
    headings = re.findall(r"^## \[([^\]]+)\]", (ROOT / "CHANGELOG.md").read_text(), re.M)
    assert headings[0] == "Unreleased", headings
    assert VERSION in headings, f"CHANGELOG.md has no section for {VERSION}: {headings}"
    released = [tuple(map(int, h.split("."))) for h in headings[1:]]
    assert released == sorted(released, reverse=True), "releases newest first"
