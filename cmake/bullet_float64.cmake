# Bullet in double precision as one imported target, Bullet::float64. Debian's config file
# gives bare library names and a relative include directory; this makes them a target that
# carries BT_USE_DOUBLE_PRECISION to every user, so no translation unit sees float Bullet.
if(NOT TARGET Bullet::float64)
  find_package(Bullet REQUIRED CONFIGS BulletConfig-float64.cmake)
  add_library(Bullet::float64 INTERFACE IMPORTED)
  set(_bullet_libs "")
  foreach(lib IN ITEMS BulletCollision-float64 LinearMath-float64)
    find_library(_bullet_${lib} NAMES ${lib} REQUIRED)
    list(APPEND _bullet_libs "${_bullet_${lib}}")
  endforeach()
  target_include_directories(Bullet::float64 INTERFACE "${BULLET_ROOT_DIR}/${BULLET_INCLUDE_DIR}")
  target_compile_definitions(Bullet::float64 INTERFACE BT_USE_DOUBLE_PRECISION)
  target_link_libraries(Bullet::float64 INTERFACE ${_bullet_libs})
endif()
