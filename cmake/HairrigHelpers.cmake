# Shared build settings for every hairrig target.
set(HAIRRIG_WARNINGS -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wconversion
    -Wno-sign-conversion)
if(HAIRRIG_WERROR)
  list(APPEND HAIRRIG_WARNINGS -Werror)
endif()
if(HAIRRIG_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  # Under AddressSanitizer Eigen switches to its own aligned malloc, while the
  # uninstrumented libceres frees Eigen buffers with plain free(): one Eigen
  # instantiation allocates, the other frees (ASan: bad-free in BDCSVD). malloc
  # is 16-byte aligned here, so Eigen may use it directly, as libceres does.
  add_compile_definitions(EIGEN_MALLOC_ALREADY_ALIGNED=1)
  add_link_options(-fsanitize=address,undefined)
endif()

# hairrig_add_library(NAME SOURCES ... DEPS ...)
#   One static library per module; includes are rooted at the repository root
#   ("core/camera.h"), so a header's path names its module.
function(hairrig_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_compile_options(${name} PRIVATE ${HAIRRIG_WARNINGS})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
endfunction()

# hairrig_add_test(MODULE NAME SOURCES ... DEPS ... [LABELS ...])
#   A GoogleTest executable registered with ctest as <module>/<name>. Tests run
#   from the repository root so they can reach etc/ and ../shared/. Exit code 77
#   means "skipped" (missing hardware or missing ../shared).
function(hairrig_add_test module name)
  if(NOT HAIRRIG_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "TIMEOUT" "SOURCES;DEPS;LABELS" ${ARGN})
  set(target ${module}_${name})
  add_executable(${target} ${ARG_SOURCES})
  target_compile_options(${target} PRIVATE ${HAIRRIG_WARNINGS})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} hairrig_gtest_main)
  add_test(NAME ${module}/${name} COMMAND ${target} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  if(HAIRRIG_SANITIZE)
    # A liveness bound, not a speed check: sanitizer builds run the simulated
    # rig's renders several times slower.
    math(EXPR ARG_TIMEOUT "${ARG_TIMEOUT} * 3")
  endif()
  set_tests_properties(${module}/${name} PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT ${ARG_TIMEOUT}
                       LABELS "${module};${ARG_LABELS}")
endfunction()
