# The ctest test package_consumers (see the top-level CMakeLists.txt):
#
#   cmake -DBUILD_DIR=<Glint build tree> -DSOURCE_DIR=<this directory> -DWORK_DIR=<scratch>
#         -DVERSION=<x.y.z> -DLIBDIR=<lib> -DINCLUDEDIR=<include> -DBINDIR=<bin>
#         -DGENERATOR=<generator> -DMAKE_PROGRAM=<make> -DC_COMPILER=<cc> -P run.cmake
#
# 1. installs BUILD_DIR into WORK_DIR/prefix (cmake --install) and checks the layout;
# 2. configures, builds and runs this directory's project with CMAKE_PREFIX_PATH=<prefix>
#    (find_package(glint 0.1 REQUIRED)), checking it found the installed package;
# 3. compiles main.c with the flags of `pkg-config --cflags --libs glint` and runs it.
# Any failure stops the script with an error, which fails the test.
cmake_minimum_required(VERSION 3.16)

foreach(var BUILD_DIR SOURCE_DIR WORK_DIR VERSION LIBDIR INCLUDEDIR BINDIR GENERATOR C_COMPILER)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "run.cmake: -D${var}=... missing")
  endif()
endforeach()
string(REGEX MATCH "^[0-9]+" major "${VERSION}")

# Runs a command; on failure prints its output and stops.
function(run step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "${step} failed (${rc}):\n  ${cmd}\n${out}")
  endif()
  message(STATUS "${step}: ok")
  set(run_output "${out}" PARENT_SCOPE)
endfunction()

function(check condition_text)
  if(NOT (${ARGN}))
    message(FATAL_ERROR "layout: ${condition_text}")
  endif()
endfunction()

function(path_of var dir)
  if(IS_ABSOLUTE "${dir}")
    set(${var} "${dir}" PARENT_SCOPE)
  else()
    set(${var} "${prefix}/${dir}" PARENT_SCOPE)
  endif()
endfunction()

set(prefix "${WORK_DIR}/prefix")
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
path_of(libdir "${LIBDIR}")
path_of(includedir "${INCLUDEDIR}")
path_of(bindir "${BINDIR}")

# --- 1. Install -----------------------------------------------------------------------
run("cmake --install" "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${prefix}")

set(lib "${libdir}/libglint.so.${VERSION}")
check("${lib} is not a regular file" EXISTS "${lib}" AND NOT IS_SYMLINK "${lib}")
foreach(link_target "libglint.so.${major}:libglint.so.${VERSION}" "libglint.so:libglint.so.${major}")
  string(REPLACE ":" ";" link_target "${link_target}")
  list(GET link_target 0 link)
  list(GET link_target 1 target)
  check("${libdir}/${link} is not a symlink" IS_SYMLINK "${libdir}/${link}")
  file(READ_SYMLINK "${libdir}/${link}" actual)
  check("${libdir}/${link} -> ${actual}, not ${target}" actual STREQUAL target)
endforeach()
foreach(file "${includedir}/glint.h" "${includedir}/glint_plugin.h"
             "${libdir}/cmake/glint/glintConfig.cmake"
             "${libdir}/cmake/glint/glintConfigVersion.cmake" "${libdir}/pkgconfig/glint.pc")
  check("${file} missing" EXISTS "${file}")
endforeach()
find_program(READELF readelf)
if(READELF)
  run("readelf -d" "${READELF}" -d "${lib}")
  check("${lib} has no SONAME libglint.so.${major}"
        run_output MATCHES "Library soname: \\[libglint\\.so\\.${major}\\]")
else()
  message(STATUS "readelf not found: SONAME not checked")
endif()
# The installed harness runs (one lobe, fast tier: a fraction of a second).
run("installed glint-verify" "${bindir}/glint-verify" --lobe lambert --fast
    --out "${WORK_DIR}/verify")

# Which libglint.so.<major> the loader picks for a program: must be the installed one.
find_program(LDD ldd)
function(check_loads_installed_lib program)
  if(NOT LDD)
    message(STATUS "ldd not found: library resolution not checked")
    return()
  endif()
  run("ldd ${program}" "${LDD}" "${program}")
  if(NOT run_output MATCHES "libglint\\.so\\.${major} => ([^ ]+)")
    message(FATAL_ERROR "${program} does not load libglint.so.${major}:\n${run_output}")
  endif()
  get_filename_component(loaded "${CMAKE_MATCH_1}" REALPATH)
  get_filename_component(installed "${lib}" REALPATH)
  if(NOT loaded STREQUAL installed)
    message(FATAL_ERROR "${program} loads ${loaded}, not the installed ${installed}")
  endif()
endfunction()

# --- 2. CMake: find_package(glint) ------------------------------------------------------
set(cmake_build "${WORK_DIR}/cmake-build")
set(generator_args -G "${GENERATOR}")
if(MAKE_PROGRAM)
  list(APPEND generator_args "-DCMAKE_MAKE_PROGRAM=${MAKE_PROGRAM}")
endif()
run("configure package_test" "${CMAKE_COMMAND}" -S "${SOURCE_DIR}" -B "${cmake_build}"
    ${generator_args} "-DCMAKE_C_COMPILER=${C_COMPILER}" "-DCMAKE_PREFIX_PATH=${prefix}"
    -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
file(STRINGS "${cmake_build}/CMakeCache.txt" found REGEX "^glint_DIR:PATH=")
string(REGEX REPLACE "^glint_DIR:PATH=" "" found "${found}")
get_filename_component(found "${found}" REALPATH)
get_filename_component(expected "${libdir}/cmake/glint" REALPATH)
if(NOT found STREQUAL expected)
  message(FATAL_ERROR "package_test found glint in '${found}', not in ${expected}")
endif()
run("build package_test" "${CMAKE_COMMAND}" --build "${cmake_build}")
run("run package_test (CMake)" "${cmake_build}/package_test")
message(STATUS "${run_output}")
check_loads_installed_lib("${cmake_build}/package_test")

# --- 3. pkg-config ----------------------------------------------------------------------
find_program(PKG_CONFIG pkg-config)
if(NOT PKG_CONFIG)
  message(FATAL_ERROR "pkg-config not found (Debian: apt-get install pkg-config)")
endif()
set(ENV{PKG_CONFIG_PATH} "${libdir}/pkgconfig")
run("pkg-config --modversion" "${PKG_CONFIG}" --modversion glint)
string(STRIP "${run_output}" pc_version)
if(NOT pc_version STREQUAL VERSION)
  message(FATAL_ERROR "pkg-config says glint ${pc_version}, expected ${VERSION}")
endif()
run("pkg-config --cflags --libs" "${PKG_CONFIG}" --cflags --libs glint)
string(STRIP "${run_output}" pc_flags)
separate_arguments(pc_flags UNIX_COMMAND "${pc_flags}")
run("pkg-config --variable=libdir" "${PKG_CONFIG}" --variable=libdir glint)
string(STRIP "${run_output}" pc_libdir)
set(pc_program "${WORK_DIR}/package_test_pkgconfig")
run("compile package_test (pkg-config)" "${C_COMPILER}" -std=c99 -Wall -Wextra -Wpedantic -Werror
    "${SOURCE_DIR}/main.c" -o "${pc_program}" ${pc_flags} "-Wl,-rpath,${pc_libdir}")
run("run package_test (pkg-config)" "${pc_program}")
message(STATUS "${run_output}")
check_loads_installed_lib("${pc_program}")
