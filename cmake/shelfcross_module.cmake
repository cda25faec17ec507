# shelfcross_module(NAME <name> DEPS <targets...>)
# One folder, one library: <folder>/*.cpp (not test/) become library `shelfcross_<name>` with
# the alias `shelfcross::<name>`, exported for find_package(shelfcross). Headers sit beside the
# sources and are installed under include/shelfcross/<name>/. Sources are globbed with
# CONFIGURE_DEPENDS so a new file needs no edit here.
function(shelfcross_module)
  cmake_parse_arguments(M "" "NAME" "DEPS;PRIVATE_DEPS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/*.cpp")
  file(GLOB headers CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/*.hpp")
  set(target shelfcross_${M_NAME})
  # Modules include each other as "plant/dynamics.hpp" or "flight_sw/tello/sdk_driver.hpp": the
  # source root is the include root (installed: include/shelfcross/<folder>/).
  if(sources)
    add_library(${target} ${sources})
    set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)
    target_include_directories(${target} PUBLIC
      $<BUILD_INTERFACE:${SHELFCROSS_SOURCE_DIR}>
      $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/shelfcross>)
    target_link_libraries(${target} PUBLIC ${M_DEPS} PRIVATE ${M_PRIVATE_DEPS})
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
  else()
    # A module with headers only (or none yet) is an interface library.
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE
      $<BUILD_INTERFACE:${SHELFCROSS_SOURCE_DIR}>
      $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/shelfcross>)
    target_link_libraries(${target} INTERFACE ${M_DEPS})
  endif()
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${M_NAME})
  add_library(shelfcross::${M_NAME} ALIAS ${target})
  install(TARGETS ${target} EXPORT shelfcrossTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  file(RELATIVE_PATH folder "${SHELFCROSS_SOURCE_DIR}" "${CMAKE_CURRENT_SOURCE_DIR}")
  install(FILES ${headers} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/shelfcross/${folder})
endfunction()

# shelfcross_module_tests(NAME <name> DEPS <targets...> [IMAGE_FILE_TESTS <test/x.cpp...>])
# <folder>/test/*.cpp become one GoogleTest executable `<name>_test`, its tests registered with
# CTest one by one. Tests read shipped files through SHELFCROSS_SOURCE_DIR.
# IMAGE_FILE_TESTS: the test sources that read or write image files (cv::imread, cv::imwrite)
# where their room does not: a second program, `<name>_image_test`, which alone links OpenCV's
# image codecs. imgcodecs brings GDAL and about 130 shared libraries that a program loads and
# resolves at every start (about 0.1 s of CPU), and CTest starts a test program once per test.
function(shelfcross_module_tests)
  cmake_parse_arguments(M "" "NAME" "DEPS;IMAGE_FILE_TESTS" ${ARGN})
  if(NOT SHELFCROSS_BUILD_TESTS)
    return()
  endif()
  file(GLOB sources CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/test/*.cpp")
  list(TRANSFORM M_IMAGE_FILE_TESTS PREPEND "${CMAKE_CURRENT_SOURCE_DIR}/")
  list(REMOVE_ITEM sources ${M_IMAGE_FILE_TESTS})
  if(sources)
    _shelfcross_test_program(${M_NAME} ${M_NAME}_test "${sources}" ${M_DEPS})
  endif()
  if(M_IMAGE_FILE_TESTS)
    _shelfcross_test_program(${M_NAME} ${M_NAME}_image_test "${M_IMAGE_FILE_TESTS}" ${M_DEPS} opencv_imgcodecs)
  endif()
  shelfcross_test_costs()
endfunction()

# _shelfcross_test_program(<label> <target> <sources> <deps...>): one GoogleTest program of a
# room, its tests registered one by one under the room's label.
function(_shelfcross_test_program label target sources)
  add_executable(${target} ${sources})
  target_link_libraries(${target} PRIVATE ${ARGN} GTest::gtest GTest::gmock GTest::gtest_main)
  target_compile_definitions(${target} PRIVATE SHELFCROSS_SOURCE_DIR="${SHELFCROSS_SOURCE_DIR}")
  # Designated initialisers that leave members at their defaults are idiomatic C++20.
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-missing-field-initializers)
  shelfcross_test_program(${target})
  gtest_discover_tests(${target} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS ${label})
endfunction()

# shelfcross_test_costs(): CTest reads the long tests' start order (cmake/test_costs.cmake)
# after the tests registered so far in this folder.
function(shelfcross_test_costs)
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${SHELFCROSS_SOURCE_DIR}/cmake/test_costs.cmake")
endfunction()
