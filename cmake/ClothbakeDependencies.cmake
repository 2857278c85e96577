# All third-party dependencies, from Debian packages (scripts/setup installs them). Only what some
# target links: FLANN and zstd were required here once and never linked (docs/architecture.md).
find_package(Threads REQUIRED)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(TBB REQUIRED)
find_package(fmt REQUIRED)
find_package(spdlog REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(tomlplusplus REQUIRED)
find_package(CLI11 REQUIRED)
find_package(OpenEXR REQUIRED)
find_package(OpenImageIO REQUIRED)
find_package(embree 3 REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(XXHASH REQUIRED IMPORTED_TARGET libxxhash)
# Test-only: GoogleTest, and CGAL for the exact cross-check of Embree's hits (tests/raycast).
if(CLOTHBAKE_BUILD_TESTS)
  find_package(GTest REQUIRED)
  find_package(CGAL REQUIRED)
endif()
if(CLOTHBAKE_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()

# Debian's OpenImageIO exports /usr/include/opencv4 as an include directory although OpenCV is an
# optional dependency that is not installed; CMake then refuses to use the target. Drop include
# directories that do not exist rather than pulling in OpenCV.
foreach(_prop INTERFACE_INCLUDE_DIRECTORIES INTERFACE_SYSTEM_INCLUDE_DIRECTORIES)
  get_target_property(_dirs OpenImageIO::OpenImageIO ${_prop})
  if(_dirs)
    set(_kept "")
    foreach(_d ${_dirs})
      if(EXISTS "${_d}" OR _d MATCHES "^\\$<")
        list(APPEND _kept "${_d}")
      endif()
    endforeach()
    set_target_properties(OpenImageIO::OpenImageIO PROPERTIES ${_prop} "${_kept}")
  endif()
endforeach()
