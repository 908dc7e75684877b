#!/usr/bin/env bash
# The reference implementation in its own venv (build/venv-bench, on top of Debian's Python and numpy): pysplashsurf
# from PyPI, pinned so that comparisons stay comparable. Created and filled once; sourced by the bench scripts.
dpkg-query -W -f='${Status}' python3-venv 2>/dev/null | grep -q "install ok installed" || \
  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv > /dev/null; }
[ -x build/venv-bench/bin/python ] || /usr/bin/python3 -m venv --system-site-packages build/venv-bench
build/venv-bench/bin/python -c "import pysplashsurf" 2>/dev/null || build/venv-bench/bin/pip install -q pysplashsurf==0.14.1.0
