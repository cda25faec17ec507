# What makes the build fast, in one place for every target (docs/getting-started.md, "Building
# by hand"): batches of sources compiled as one (a unity build), a compiler cache when one is
# installed, and precompiled third-party headers.
# Included by the top-level CMakeLists.txt before its subdirectories; shelfcross_speed_up_targets()
# runs after them, over every target they defined.

# A unity build, on unless the user sets CMAKE_UNITY_BUILD: each target's sources compiled in
# batches of CMAKE_UNITY_BUILD_BATCH_SIZE (8 by default) as one translation unit, so that the
# heavy headers (Eigen, OpenCV, the standard library) are parsed, and their inline functions and
# templates instantiated and optimised, once per batch instead of once per file. Files in one
# batch share a namespace scope: names in anonymous namespaces must differ across a target's
# files. GCC's -Wsubobject-linkage assumes that a class defined in an included file is defined
# in a header, which a batch's sources are not (a source's Impl with a member of a type local to
# that source), so it is off in a unity build.
if(NOT DEFINED CMAKE_UNITY_BUILD)
  set(CMAKE_UNITY_BUILD ON)
endif()
if(CMAKE_UNITY_BUILD AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  add_compile_options($<$<COMPILE_LANGUAGE:CXX>:-Wno-subobject-linkage>)
endif()

# Off by default: it saves 14 to 30 % of a file's compile time (the sources spend most of it
# optimising, not parsing), but with GCC 12 a precompiled header loses the compiler's silence on
# warnings inside the standard library, which -Werror makes errors, and it writes about 150 MB
# per target (docs/getting-started.md, "Building by hand").
option(SHELFCROSS_PCH "Precompile the heavy third-party headers of each target (OpenCV, Eigen, ...)" OFF)

# ccache, when it is installed and the user has not chosen a launcher (an empty
# -DCMAKE_CXX_COMPILER_LAUNCHER= turns it off). A translation unit that reads a precompiled header
# is cached only when ccache may ignore the header's __DATE__/__TIME__ and its macros' values
# (ccache's manual, "Precompiled headers"); neither can change what this build's headers compile
# to, so the launcher says so.
find_program(SHELFCROSS_CCACHE_PROGRAM ccache)
mark_as_advanced(SHELFCROSS_CCACHE_PROGRAM)
foreach(lang IN ITEMS C CXX)
  if(SHELFCROSS_CCACHE_PROGRAM AND NOT DEFINED CMAKE_${lang}_COMPILER_LAUNCHER
     AND NOT DEFINED ENV{CMAKE_${lang}_COMPILER_LAUNCHER})
    set(CMAKE_${lang}_COMPILER_LAUNCHER
        "${CMAKE_COMMAND};-E;env;CCACHE_SLOPPINESS=pch_defines,time_macros;${SHELFCROSS_CCACHE_PROGRAM}")
  elseif(SHELFCROSS_PCH AND "${CMAKE_${lang}_COMPILER_LAUNCHER}" MATCHES "(^|/)ccache$")
    # The user's own plain ccache: it refuses to cache what reads a precompiled header unless
    # its configuration allows it.
    message(STATUS "${lang}: ccache caches the files that read a precompiled header only with "
                   "`sloppiness = pch_defines,time_macros` in its configuration (ccache.conf)")
  endif()
endforeach()

# The third-party headers worth precompiling: each costs a second or more of parsing in every
# translation unit that reads it (g++ -ftime-report), which a precompiled header pays once per
# target.
set(SHELFCROSS_HEAVY_HEADERS_REGEX
    "^(opencv2/.*|Eigen/.*|btBulletCollisionCommon\\.h|spdlog/.*|nlohmann/json\\.hpp|CLI/CLI\\.hpp|gtest/gtest\\.h|gmock/gmock\\.h|benchmark/benchmark\\.h|boost/math/.*|yaml-cpp/yaml\\.h)$")
# A target with fewer sources than this compiles its headers fewer times than a precompiled
# header costs to write and read back.
set(SHELFCROSS_PCH_MIN_SOURCES 2)

# _shelfcross_heavy_includes(<file> <out>): the heavy third-party headers <file> reads, itself
# or through the project's headers ("verification/cosim/cosim.hpp", "shelfcross/time.hpp"),
# in the order it reads them. Memoised per file in a global property.
function(_shelfcross_heavy_includes file out)
  get_property(known GLOBAL PROPERTY "SHELFCROSS_HEAVY:${file}" SET)
  if(known)
    get_property(result GLOBAL PROPERTY "SHELFCROSS_HEAVY:${file}")
    set(${out} "${result}" PARENT_SCOPE)
    return()
  endif()
  set_property(GLOBAL PROPERTY "SHELFCROSS_HEAVY:${file}" "")  # an include cycle ends here
  set(result "")
  file(STRINGS "${file}" lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"][^>\"]+[>\"]")
  get_filename_component(dir "${file}" DIRECTORY)
  foreach(line IN LISTS lines)
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*[<\"]([^>\"]+)[>\"].*" "\\1" name "${line}")
    set(found "")
    foreach(root IN ITEMS "${dir}" "${SHELFCROSS_SOURCE_DIR}" "${SHELFCROSS_SOURCE_DIR}/include")
      if(NOT found AND EXISTS "${root}/${name}" AND NOT IS_DIRECTORY "${root}/${name}")
        set(found "${root}/${name}")
      endif()
    endforeach()
    if(found)
      _shelfcross_heavy_includes("${found}" nested)
      list(APPEND result ${nested})
    elseif(name MATCHES "${SHELFCROSS_HEAVY_HEADERS_REGEX}")
      list(APPEND result "${name}")
    endif()
  endforeach()
  list(REMOVE_DUPLICATES result)
  set_property(GLOBAL PROPERTY "SHELFCROSS_HEAVY:${file}" "${result}")
  set(${out} "${result}" PARENT_SCOPE)
endfunction()

# shelfcross_test_program(<target>): a test program's own sources are compiled at -O1 in the
# optimised builds (release -O3, the fuzz preset's -O2). A test's time goes to the libraries it
# links, which keep their level; its own sources are mostly GoogleTest's macros and set-up, which
# -O3 spends a quarter to a half more compile time on than -O1. The arithmetic is the same
# either way (no -ffast-math: IEEE operations in the source's order at every level), so a test
# computes what it computed before. The debug preset keeps its own level.
set(SHELFCROSS_TEST_OPTIMIZATION "-O1" CACHE STRING "Optimisation of test programs' own sources in optimised builds (empty: the build type's)")
mark_as_advanced(SHELFCROSS_TEST_OPTIMIZATION)
function(shelfcross_test_program target)
  if(SHELFCROSS_TEST_OPTIMIZATION)
    target_compile_options(${target} PRIVATE
      "$<$<AND:$<COMPILE_LANGUAGE:CXX>,$<CONFIG:Release,RelWithDebInfo,MinSizeRel>>:${SHELFCROSS_TEST_OPTIMIZATION}>")
  endif()
endfunction()

# _shelfcross_targets_under(<dir> <out>): every target defined in <dir> and its subdirectories.
function(_shelfcross_targets_under dir out)
  get_property(targets DIRECTORY "${dir}" PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY "${dir}" PROPERTY SUBDIRECTORIES)
  foreach(sub IN LISTS subdirs)
    _shelfcross_targets_under("${sub}" nested)
    list(APPEND targets ${nested})
  endforeach()
  set(${out} "${targets}" PARENT_SCOPE)
endfunction()

# shelfcross_speed_up_targets(): with SHELFCROSS_PCH, gives every C++ library and program of the
# project, whichever folder defines it, a precompiled header of the heavy third-party headers its
# own sources read.
# A target's precompiled header holds only headers at least one of its sources reads anyway, so
# it adds no dependency; SHELFCROSS_PCH=OFF builds without (each file then has to include what it
# uses on its own, which the fuzz preset's build, with the same sources, also shows).
function(shelfcross_speed_up_targets)
  if(NOT SHELFCROSS_PCH)
    return()
  endif()
  _shelfcross_targets_under("${CMAKE_CURRENT_SOURCE_DIR}" targets)
  foreach(target IN LISTS targets)
    get_target_property(type ${target} TYPE)
    if(NOT type MATCHES "^(STATIC_LIBRARY|SHARED_LIBRARY|MODULE_LIBRARY|OBJECT_LIBRARY|EXECUTABLE)$")
      continue()
    endif()
    get_target_property(sources ${target} SOURCES)
    get_target_property(source_dir ${target} SOURCE_DIR)
    set(cxx_sources "")
    set(other_sources FALSE)
    foreach(source IN LISTS sources)
      if(source MATCHES "\\.cpp$")
        if(NOT IS_ABSOLUTE "${source}")
          set(source "${source_dir}/${source}")
        endif()
        list(APPEND cxx_sources "${source}")
      elseif(source MATCHES "\\.(c|cc|cxx)$")
        set(other_sources TRUE)
      endif()
    endforeach()
    list(LENGTH cxx_sources count)
    if(other_sources OR count LESS SHELFCROSS_PCH_MIN_SOURCES)
      continue()
    endif()

    set(heavy "")
    foreach(source IN LISTS cxx_sources)
      _shelfcross_heavy_includes("${source}" read)
      list(APPEND heavy ${read})
    endforeach()
    list(REMOVE_DUPLICATES heavy)
    if(heavy)
      list(TRANSFORM heavy PREPEND "<")
      list(TRANSFORM heavy APPEND ">")
      target_precompile_headers(${target} PRIVATE ${heavy})
    endif()
  endforeach()
endfunction()
