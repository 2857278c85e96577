# Asset targets for projects that use clothbake (installed with the package; docs/batch.md,
# "CMake"). Each asset is one add_custom_command with a DEPFILE written by `clothbake bake
# --depfile`, so that the fabric, every map image or WIF draft it reads and the clothbake
# executable are dependencies (Ninja and Unix Makefiles; CMake >= 3.20), and a byte-identical
# rebake keeps the file's mtime (restat).

# clothbake_add_asset(NAME FABRIC f.toml OUTPUT x.cbk [SCENE s.toml] [OPTIONS bake options...]
#                     [DEPENDS files...])
# A target NAME (part of ALL) that bakes f.toml into x.cbk (relative OUTPUT: in the current binary
# folder). With SCENE the bake keeps only what that scene can query (`bake --scene`,
# docs/scene-plans.md); the scene file is then a dependency too (the depfile names it). The
# target's property CLOTHBAKE_ASSET holds the asset's absolute path.
function(clothbake_add_asset name)
  cmake_parse_arguments(ARG "" "FABRIC;OUTPUT;SCENE" "OPTIONS;DEPENDS" ${ARGN})
  if(NOT ARG_FABRIC OR NOT ARG_OUTPUT)
    message(FATAL_ERROR "clothbake_add_asset(${name}): FABRIC and OUTPUT are required")
  endif()
  if(NOT TARGET clothbake::clothbake)
    message(FATAL_ERROR "clothbake_add_asset: no clothbake::clothbake executable in the package")
  endif()
  get_filename_component(fabric "${ARG_FABRIC}" ABSOLUTE)
  get_filename_component(output "${ARG_OUTPUT}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
  get_filename_component(output_dir "${output}" DIRECTORY)
  file(MAKE_DIRECTORY "${output_dir}")
  set(scene_args)
  set(scene_dep)
  if(ARG_SCENE)
    get_filename_component(scene "${ARG_SCENE}" ABSOLUTE)
    set(scene_args --scene "${scene}")
    set(scene_dep "${scene}")
  endif()
  if(CMAKE_GENERATOR MATCHES "Ninja")
    # Ninja restats the output: a byte-identical rebake (mtime kept) stops there.
    set(stamp "${output}")
    set(outputs "${output}")
    set(touch_stamp)
  else()
    # Make has no restat: a bake that leaves a byte-identical asset (and its mtime) alone would
    # run again on every build. A stamp touched after each bake is what Make compares; targets
    # that use the asset still see its kept mtime.
    set(stamp "${output}.stamp")
    set(outputs "${stamp}" "${output}")
    set(touch_stamp COMMAND ${CMAKE_COMMAND} -E touch "${stamp}")
  endif()
  add_custom_command(OUTPUT ${outputs}
    COMMAND clothbake::clothbake bake "${fabric}" -o "${output}" --depfile "${output}.d" --quiet
      ${scene_args} ${ARG_OPTIONS}
    ${touch_stamp}
    DEPENDS "${fabric}" ${scene_dep} clothbake::clothbake ${ARG_DEPENDS}
    DEPFILE "${output}.d"
    COMMENT "clothbake: baking ${name}"
    VERBATIM)
  add_custom_target(${name} ALL DEPENDS "${stamp}")
  set_target_properties(${name} PROPERTIES CLOTHBAKE_ASSET "${output}")
endfunction()

# clothbake_add_fabric_library(NAME DIR [OPTIONS ...]): one asset target NAME_<stem> per DIR/*.toml
# (outputs in the binary folder NAME/<stem>.cbk) and a target NAME that depends on all of them.
# The list of fabrics is read at configure time (re-run CMake after adding a fabric).
function(clothbake_add_fabric_library name dir)
  cmake_parse_arguments(ARG "" "" "OPTIONS" ${ARGN})
  get_filename_component(dir "${dir}" ABSOLUTE)
  file(GLOB fabrics CONFIGURE_DEPENDS "${dir}/*.toml")
  list(SORT fabrics)
  set(targets)
  foreach(fabric IN LISTS fabrics)
    get_filename_component(stem "${fabric}" NAME_WE)
    clothbake_add_asset(${name}_${stem} FABRIC "${fabric}" OUTPUT "${name}/${stem}.cbk"
      OPTIONS ${ARG_OPTIONS})
    list(APPEND targets ${name}_${stem})
  endforeach()
  add_custom_target(${name} ALL DEPENDS ${targets})
endfunction()
