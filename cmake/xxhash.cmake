# xxHash (Debian libxxhash-dev) as one imported target, xxHash::xxhash. Debian ships no CMake
# config for it, only the header and the shared library.
if(NOT TARGET xxHash::xxhash)
  find_path(XXHASH_INCLUDE_DIR xxhash.h REQUIRED)
  find_library(XXHASH_LIBRARY xxhash REQUIRED)
  add_library(xxHash::xxhash INTERFACE IMPORTED)
  target_include_directories(xxHash::xxhash INTERFACE "${XXHASH_INCLUDE_DIR}")
  target_link_libraries(xxHash::xxhash INTERFACE "${XXHASH_LIBRARY}")
endif()
