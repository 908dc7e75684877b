#!/usr/bin/env bash
# Makes build/venv/farm (once): the job runners the farm tests drive, Open Job Description's `openjd` and Dask
# distributed, from PyPI. It sees the system's site packages, so that numpy is Debian's, the one the built module
# (build/python) is compiled against. Prints the venv's Python.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib.sh
# One maker at a time: pytest's workers (-n) import test_farm.py and test_farm_dask.py at once, and a second
# `python -m venv` over a half-made venv left it without pip.
mkdir -p build/venv
exec 9> build/venv/.farm.lock
flock 9
[ -x build/venv/farm/bin/python ] || /usr/bin/python3 -m venv --system-site-packages build/venv/farm
venv_with build/venv/farm /usr/bin/python3 "openjd-cli==0.8.0" "dask[distributed]==2026.8.0" >&2
echo build/venv/farm/bin/python
