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
  if(name IN_LIST ENAVI_ASAN_CI_TESTS)
    list(APPEND ARG_LABELS asan_ci)
  endif()
  # tests_<label> builds every test binary of a label (scripts/build.sh --sanitize: only those).
  foreach(label ${ARG_LABELS})
    if(NOT TARGET tests_${label})
      add_custom_target(tests_${label})
    endif()
    add_dependencies(tests_${label} ${name})
  endforeach()
  # gtest_discover_tests writes its properties out flat, so a second label would read as a
  # property name: the tests get the first here and all of them from a file CTest includes after
  # the discovered list (<name>_TESTS).
  list(GET ARG_LABELS 0 first_label)
  set(props LABELS ${first_label})
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
  list(LENGTH ARG_LABELS label_count)
  if(label_count GREATER 1)
    set(relabel "${CMAKE_CURRENT_BINARY_DIR}/${name}_labels.cmake")
    file(WRITE "${relabel}" "if(DEFINED ${name}_TESTS)\n  set_tests_properties(\${${name}_TESTS} PROPERTIES LABELS \"${ARG_LABELS}\")\nendif()\n")
    set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${relabel}")
  endif()
endfunction()
