"""Makes the staged package (build/python) importable and gives tests the shared data and the CLI."""
import os
import pathlib
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BUILD = pathlib.Path(os.environ.get("MENISCUS_BUILD", ROOT / "build"))
sys.path.insert(0, str(BUILD / "python"))
SHARED = ROOT.parent / "shared" / "data"


@pytest.fixture
def shared():
    return SHARED


@pytest.fixture
def cli():
    return str(BUILD / "bin" / "meniscus")
