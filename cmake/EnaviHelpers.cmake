# enavi_add_test(<name> SOURCES a.cc [b.cc] LIBS enavi::x [...] [LABELS unit] [LOCK name] [SERIAL]
#                [COST seconds])
# One line per test binary; every TEST in it is registered with CTest. LOCK serialises the tests
# that share a host resource (cgroups, CPU-share measurements) under `ctest -j`; SERIAL runs each
# of them with no other test at all (measurements that need every host CPU). COST: about how long
# its longest test takes; CTest starts costlier tests first when it has no timings of its own (a
# fresh checkout, as in CI), so that long tests holding a LOCK do not run last with a core idle.
function(enavi_add_test name)
  cmake_parse_arguments(ARG "SERIAL" "LOCK;COST" "SOURCES;LIBS;LABELS" ${ARGN})
  if(NOT ARG_SOURCES)
    set(ARG_SOURCES ${name}.cc)
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main)
  target_compile_options(${name} PRIVATE ${ENAVI_TEST_COMPILE_OPTIONS})
  target_compile_definitions(${name} PRIVATE
    ENAVI_SOURCE_DIR="${PROJECT_SOURCE_DIR}" ENAVI_BINARY_DIR="${PROJECT_BINARY_DIR}")
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests)
  if(NOT ARG_LABELS)
    set(ARG_LABELS unit)
  endif()
  # tests_<label> builds every test binary of a label (scripts/build.sh --sanitize: only those).
  foreach(label ${ARG_LABELS})
    if(NOT TARGET tests_${label})
      add_custom_target(tests_${label})
    endif()
    add_dependencies(tests_${label} ${name})
  endforeach()
  set(props LABELS "${ARG_LABELS}")
  if(ENAVI_SANITIZE)
    # The sanitizer environment comes in through `env` on the test's command line: handed to
    # gtest_discover_tests as PROPERTIES ENVIRONMENT, a list keeps only its first variable (CMake
    # issue 23120), and LSAN_OPTIONS, the suppressions, never reached a test or its children.
    set_target_properties(${name} PROPERTIES CROSSCOMPILING_EMULATOR "env;${ENAVI_SANITIZER_ENV}")
  endif()
  if(ARG_LOCK)
    list(APPEND props RESOURCE_LOCK ${ARG_LOCK})
  endif()
  if(ARG_SERIAL)
    list(APPEND props RUN_SERIAL TRUE)
  endif()
  if(ARG_COST)
    list(APPEND props COST ${ARG_COST})
  endif()
  gtest_discover_tests(${name} PROPERTIES ${props} DISCOVERY_TIMEOUT 60)
endfunction()
