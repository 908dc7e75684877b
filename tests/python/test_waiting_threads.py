"""Busy machines: the CLI and the Python package make waiting OpenMP threads spin briefly, then sleep, unless the user
chose a policy (native/core/base/waiting.h says why). What the runtime read is what the process started with, so the
checks read it back from the CLI's --stats and from a fresh Python process."""
import importlib.util
import json
import os
import re
import subprocess
import sys

import pytest

from conftest import BUILD, ROOT

POLICY_VARIABLES = ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "KMP_BLOCKTIME")


def environment_without_policy(**extra):
    env = {k: v for k, v in os.environ.items() if k not in POLICY_VARIABLES}
    env.update(extra)
    return env


def cli_wait_settings(cli, tmp_path, shared, env):
    stats = tmp_path / "stats.json"
    subprocess.run([cli, "reconstruct", str(shared / "splashsurf" / "double_dam_break_frame_26_4732_particles.vtk"),
                    "-o", str(tmp_path / "surface.ply"), "-r", "0.025", "-c", "1.0", "-n", "2",
                    "--stats", str(stats)], check=True, env=env, capture_output=True)
    return json.loads(stats.read_text())["openmp_wait"]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the restart with GOMP_SPINCOUNT is Linux's")
def test_cli_waits_briefly_when_the_user_chose_nothing(cli, tmp_path, shared):
    settings = cli_wait_settings(cli, tmp_path, shared, environment_without_policy())
    assert settings["GOMP_SPINCOUNT"] == "10000"
    assert settings["OMP_WAIT_POLICY"] is None


def test_cli_keeps_the_users_policy(cli, tmp_path, shared):
    settings = cli_wait_settings(cli, tmp_path, shared, environment_without_policy(OMP_WAIT_POLICY="ACTIVE"))
    assert settings["OMP_WAIT_POLICY"] == "ACTIVE"
    assert settings["GOMP_SPINCOUNT"] is None


@pytest.mark.parametrize("user_setting, expected", [({}, "10000"), ({"GOMP_SPINCOUNT": "500"}, "500"),
                                                    ({"OMP_WAIT_POLICY": "PASSIVE"}, None)])
def test_python_package_sets_the_spin_before_the_core_loads(user_setting, expected):
    code = ("import os, sys; import meniscus; "
            "print(os.environ.get('GOMP_SPINCOUNT'), 'meniscus._core' in sys.modules)")
    env = environment_without_policy(PYTHONPATH=str(BUILD / "python"), **user_setting)
    out = subprocess.run([sys.executable, "-c", code], check=True, env=env, capture_output=True, text=True).stdout.split()
    assert out == [str(expected), "True"]


def test_the_python_values_are_the_cores():
    header = (ROOT / "native" / "core" / "base" / "waiting.h").read_text()
    spin_count = re.search(r'kBarrierSpinCount\s*=\s*"(\d+)"', header)
    block_milliseconds = re.search(r"kBarrierBlockMilliseconds\s*=\s*(\d+)\s*;", header)
    assert spin_count and block_milliseconds, "waiting.h no longer defines its constants as this test expects"
    # Loaded by its path, as the Blender add-on loads it (the package would load the core).
    spec = importlib.util.spec_from_file_location("waiting_under_test", ROOT / "python" / "meniscus" / "waiting.py")
    waiting = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(waiting)
    assert waiting.BARRIER_SPIN_COUNT == spin_count.group(1)
    assert waiting.BARRIER_BLOCK_MILLISECONDS == int(block_milliseconds.group(1))
    environment = {}
    waiting.wait_briefly_at_barriers(environment)
    assert environment == {"GOMP_SPINCOUNT": spin_count.group(1), "KMP_BLOCKTIME": block_milliseconds.group(1)}
