# Shared helpers of the scripts (sourced, not run): installing Debian packages and finding Pythons, idempotently.

# require_packages PACKAGE...: installs the Debian packages that are missing (nothing when all are there).
require_packages() {
  local missing=() package
  for package in "$@"; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    echo "meniscus: installing ${missing[*]}"
    local sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" > /dev/null
  fi
}

# python_for VERSION: prints the path of a CPython VERSION (e.g. 3.13) interpreter: pyenv's, else one on PATH.
python_for() {
  local version="$1" candidate
  for candidate in "$(pyenv root 2>/dev/null || echo "$HOME/.pyenv")"/versions/"$version".*/bin/python"$version"; do
    [ -x "$candidate" ] && { echo "$candidate"; return 0; }
  done
  candidate="$(command -v "python$version" || true)"
  [ -n "$candidate" ] && "$candidate" -c "import venv, ensurepip" 2>/dev/null && { echo "$candidate"; return 0; }
  echo "meniscus: no Python $version found (pyenv install $version, or put python$version with venv on PATH)" >&2
  return 1
}

# venv_with DIR PYTHON REQUIREMENT...: makes a venv with these requirements, once: a stamp file remembers what was
# installed, so a second call costs nothing and a changed requirement list installs again.
venv_with() {
  local dir="$1" python="$2"
  shift 2
  local wanted="$*"
  [ -x "$dir/bin/python" ] || "$python" -m venv "$dir"
  if [ "$(cat "$dir/.meniscus-requirements" 2>/dev/null)" != "$wanted" ]; then
    "$dir/bin/python" -m pip install -q --disable-pip-version-check "$@" 2>&1 | { grep -v "^WARNING: Location" >&2 || true; }
    [ "${PIPESTATUS[0]}" -eq 0 ] || return 1
    echo "$wanted" > "$dir/.meniscus-requirements"
  fi
}

# bpy_venv VERSION: prints the Python of build/venv/bpy-VERSION, a venv with the `bpy` module of that Blender
# version from PyPI (made once). Blender 5.1+ embeds Python 3.13, earlier 4.x and 5.0 Python 3.11.
bpy_venv() {
  local version="$1" python_version=3.11
  case "$version" in 5.0) ;; 5.*|6.*) python_version=3.13 ;; esac
  venv_with "build/venv/bpy-$version" "$(python_for "$python_version")" "bpy==$version.*" >&2
  echo "build/venv/bpy-$version/bin/python"
}

# Build tools every build needs (Debian 12), and those of the two portability builds.
MENISCUS_BUILD_PACKAGES=(build-essential cmake ccache pybind11-dev catch2 libcli11-dev nlohmann-json3-dev zlib1g-dev
                         python3-dev python3-numpy python3-pytest python3-venv)
MENISCUS_CLANG_PACKAGES=(clang libc++-dev libc++abi-dev libomp-dev catch2 libcli11-dev nlohmann-json3-dev zlib1g-dev)
MENISCUS_WINDOWS_PACKAGES=(g++-mingw-w64-x86-64-posix libz-mingw-w64-dev wine64 catch2 libcli11-dev nlohmann-json3-dev)

# ccache hashes the paths under the repository relative to the build folder, so that builds of the same sources in
# other folders of the same depth share objects: the wheels' build folders (scripts/package.sh) reuse the development
# build's core, and other clones of the repository reuse each other's.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$(pwd -P)}"
