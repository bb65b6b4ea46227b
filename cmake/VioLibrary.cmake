# vio_add_library(NAME DEPS dep...)
#
# One CMake library per top-level folder: sources are every src/*.cc of the
# folder, the public header surface is include/vio/<folder>/.  Warnings are
# errors-in-spirit: the build is expected to be -Wall -Wextra clean.
function(vio_add_library name)
  cmake_parse_arguments(ARG "" "" "DEPS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/*.cc)
  if(sources)
    add_library(${name} STATIC ${sources})
    target_include_directories(${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
    target_link_libraries(${name} PUBLIC ${ARG_DEPS})
    vio_set_warnings(${name})
    vio_set_unity_build(${name})
  else()  # header-only so far
    add_library(${name} INTERFACE)
    target_include_directories(${name} INTERFACE ${CMAKE_CURRENT_SOURCE_DIR}/include)
    target_link_libraries(${name} INTERFACE ${ARG_DEPS})
  endif()
endfunction()

function(vio_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra)
endfunction()

# VIO_UNITY_BUILD (top-level CMakeLists.txt).
function(vio_set_unity_build target)
  if(VIO_UNITY_BUILD)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE ${VIO_UNITY_BUILD_BATCH_SIZE})
  endif()
endfunction()
