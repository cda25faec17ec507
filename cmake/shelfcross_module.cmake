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

# shelfcross_module_tests(NAME <name> DEPS <targets...>)
# <folder>/test/*.cpp become one GoogleTest executable `<name>_test`, its tests registered with
# CTest one by one. Tests read shipped files through SHELFCROSS_SOURCE_DIR.
function(shelfcross_module_tests)
  cmake_parse_arguments(M "" "NAME" "DEPS" ${ARGN})
  if(NOT SHELFCROSS_BUILD_TESTS)
    return()
  endif()
  file(GLOB sources CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/test/*.cpp")
  if(NOT sources)
    return()
  endif()
  add_executable(${M_NAME}_test ${sources})
  target_link_libraries(${M_NAME}_test PRIVATE ${M_DEPS} GTest::gtest GTest::gmock GTest::gtest_main)
  target_compile_definitions(${M_NAME}_test PRIVATE SHELFCROSS_SOURCE_DIR="${SHELFCROSS_SOURCE_DIR}")
  # Designated initialisers that leave members at their defaults are idiomatic C++20.
  target_compile_options(${M_NAME}_test PRIVATE -Wall -Wextra -Wno-missing-field-initializers)
  shelfcross_test_program(${M_NAME}_test)
  gtest_discover_tests(${M_NAME}_test DISCOVERY_TIMEOUT 60 PROPERTIES LABELS ${M_NAME})
  shelfcross_test_costs()
endfunction()

# shelfcross_test_costs(): CTest reads the long tests' start order (cmake/test_costs.cmake)
# after the tests registered so far in this folder.
function(shelfcross_test_costs)
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${SHELFCROSS_SOURCE_DIR}/cmake/test_costs.cmake")
endfunction()
