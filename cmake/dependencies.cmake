# Third-party dependencies, each taken from the first place that has it:
#   1. the installed package (Debian: libcli11-dev, nlohmann-json3-dev, catch2, zlib1g-dev);
#   2. header-only libraries found under MENISCUS_DEPENDENCY_INCLUDE_DIRS (cross builds, e.g. scripts/build_windows.sh,
#      reuse Debian's architecture-independent headers this way);
#   3. a download at configure time (MENISCUS_FETCH_DEPENDENCIES, on by default): what the hosted wheel builds on
#      Windows and macOS use, where none of these is installed.
# Each ends up as one target: meniscus::cli11, meniscus::json, meniscus::catch2, ZLIB::ZLIB.
include_guard(GLOBAL)
include(FetchContent)

set(MENISCUS_DEPENDENCY_INCLUDE_DIRS "" CACHE STRING "Folders with header-only dependencies (CLI/, nlohmann/, catch2/)")
option(MENISCUS_FETCH_DEPENDENCIES "Download dependencies that are not installed" ON)

function(_meniscus_interface_target alias include_dir)
  string(REPLACE "::" "_" name "${alias}")
  add_library(${name} INTERFACE IMPORTED GLOBAL)
  target_include_directories(${name} INTERFACE "${include_dir}")
  add_library(${alias} ALIAS ${name})
endfunction()

# meniscus_header_only(<alias> <package> <package target> <probe header> <archive url> <include dir in archive>)
function(meniscus_header_only alias package package_target probe url archive_include)
  if(TARGET ${alias})
    return()
  endif()
  find_package(${package} CONFIG QUIET)
  if(TARGET ${package_target})
    add_library(${alias} ALIAS ${package_target})
    return()
  endif()
  if(MENISCUS_DEPENDENCY_INCLUDE_DIRS)
    find_path(_meniscus_${package}_include ${probe} PATHS ${MENISCUS_DEPENDENCY_INCLUDE_DIRS} NO_DEFAULT_PATH
              NO_CMAKE_FIND_ROOT_PATH)
    if(_meniscus_${package}_include)
      _meniscus_interface_target(${alias} "${_meniscus_${package}_include}")
      return()
    endif()
  endif()
  if(NOT MENISCUS_FETCH_DEPENDENCIES)
    message(FATAL_ERROR "${package} not found: install it, point MENISCUS_DEPENDENCY_INCLUDE_DIRS at its headers, "
                        "or allow MENISCUS_FETCH_DEPENDENCIES")
  endif()
  message(STATUS "${package} not installed: downloading ${url}")
  string(TOLOWER "meniscus_dep_${package}" content)
  set(source_dir ${CMAKE_BINARY_DIR}/_deps/${content}-src)
  if(NOT EXISTS ${source_dir}/${archive_include})
    FetchContent_Populate(${content} QUIET URL ${url} SOURCE_DIR ${source_dir}
                          SUBBUILD_DIR ${CMAKE_BINARY_DIR}/_deps/${content}-subbuild)
  endif()
  _meniscus_interface_target(${alias} "${source_dir}/${archive_include}")
endfunction()

meniscus_header_only(meniscus::cli11 CLI11 CLI11::CLI11 CLI/CLI.hpp
                     https://github.com/CLIUtils/CLI11/archive/refs/tags/v2.4.2.tar.gz include)
meniscus_header_only(meniscus::json nlohmann_json nlohmann_json::nlohmann_json nlohmann/json.hpp
                     https://github.com/nlohmann/json/releases/download/v3.11.3/include.zip include)

function(meniscus_find_catch2)
  meniscus_header_only(meniscus::catch2 Catch2 Catch2::Catch2 catch2/catch.hpp
                       https://github.com/catchorg/Catch2/archive/refs/tags/v2.13.10.tar.gz single_include)
endfunction()

# zlib: the installed library, else zlib's own CMake build from its release archive (static).
macro(meniscus_find_zlib)
  find_package(ZLIB QUIET)
  if(NOT ZLIB_FOUND)
    if(NOT MENISCUS_FETCH_DEPENDENCIES)
      message(FATAL_ERROR "zlib not found (install zlib1g-dev) and MENISCUS_FETCH_DEPENDENCIES is off")
    endif()
    message(STATUS "zlib not installed: building it from its release archive")
    set(ZLIB_BUILD_EXAMPLES OFF CACHE BOOL "" FORCE)
    set(zlib_source ${CMAKE_BINARY_DIR}/_deps/meniscus_dep_zlib-src)
    set(zlib_binary ${CMAKE_BINARY_DIR}/_deps/meniscus_dep_zlib-build)
    if(NOT EXISTS ${zlib_source}/zlib.h)
      FetchContent_Populate(meniscus_dep_zlib QUIET
                            URL https://github.com/madler/zlib/releases/download/v1.3.1/zlib-1.3.1.tar.gz
                            SOURCE_DIR ${zlib_source} SUBBUILD_DIR ${CMAKE_BINARY_DIR}/_deps/meniscus_dep_zlib-subbuild)
    endif()
    add_subdirectory(${zlib_source} ${zlib_binary} EXCLUDE_FROM_ALL)
    target_include_directories(zlibstatic INTERFACE ${zlib_source} ${zlib_binary})
    add_library(ZLIB::ZLIB ALIAS zlibstatic)
  endif()
endmacro()

# Registers a Catch2 executable with CTest: one CTest test per test case where the Catch module can list them (a
# native build, or a cross build with an emulator), otherwise the whole executable as one test.
function(meniscus_register_catch_tests target)
  find_file(_meniscus_catch_module Catch.cmake PATHS /usr/lib/cmake/Catch2 ${Catch2_DIR} NO_CMAKE_FIND_ROOT_PATH)
  if(_meniscus_catch_module AND (NOT CMAKE_CROSSCOMPILING OR CMAKE_CROSSCOMPILING_EMULATOR))
    include(${_meniscus_catch_module})
    catch_discover_tests(${target})
  else()
    add_test(NAME ${target} COMMAND ${target})
  endif()
endfunction()
