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

# enavi_add_method(<name> FUNCTIONS <Fn> [...] HEADER <h> SOURCES a.cc a.h [...] [LIBS enavi::x ...])
# A navigation method's folder (README "A new navigation method"): its library enavi_<name>
# (alias enavi::<name>) on the method interface, and the functions its HEADER declares, each
# returning one navstack::MethodInfo, queued for the next enavi_method_list() in registration order.
function(enavi_add_method name)
  cmake_parse_arguments(ARG "" "HEADER" "FUNCTIONS;SOURCES;LIBS" ${ARGN})
  if(NOT ARG_FUNCTIONS OR NOT ARG_HEADER OR NOT ARG_SOURCES)
    message(FATAL_ERROR "enavi_add_method(${name}): FUNCTIONS, HEADER and SOURCES are required")
  endif()
  add_library(enavi_${name} ${ARG_SOURCES})
  add_library(enavi::${name} ALIAS enavi_${name})
  target_link_libraries(enavi_${name} PUBLIC enavi::method_api ${ARG_LIBS})
  file(RELATIVE_PATH header "${PROJECT_SOURCE_DIR}" "${CMAKE_CURRENT_SOURCE_DIR}/${ARG_HEADER}")
  set_property(GLOBAL APPEND PROPERTY ENAVI_QUEUED_METHOD_LIBRARIES enavi_${name})
  set_property(GLOBAL APPEND PROPERTY ENAVI_QUEUED_METHOD_HEADERS "${header}")
  set_property(GLOBAL APPEND PROPERTY ENAVI_QUEUED_METHOD_FUNCTIONS ${ARG_FUNCTIONS})
endfunction()

# enavi_method_list(<library> FUNCTION <Name>)
# A library defining `std::vector<navstack::MethodInfo> navstack::<Name>()`: the MethodInfo of every
# method enavi_add_method() queued since the last list, in the order they were added (generated
# at configure time; written only when it changes, so a reconfigure rebuilds nothing).
function(enavi_method_list library)
  cmake_parse_arguments(ARG "" "FUNCTION" "" ${ARGN})
  get_property(libraries GLOBAL PROPERTY ENAVI_QUEUED_METHOD_LIBRARIES)
  get_property(headers GLOBAL PROPERTY ENAVI_QUEUED_METHOD_HEADERS)
  get_property(functions GLOBAL PROPERTY ENAVI_QUEUED_METHOD_FUNCTIONS)
  if(NOT ARG_FUNCTION OR NOT functions)
    message(FATAL_ERROR "enavi_method_list(${library}): needs FUNCTION and at least one enavi_add_method() before it")
  endif()
  set(includes "")
  foreach(header ${headers})
    string(APPEND includes "#include \"${header}\"\n")
  endforeach()
  list(TRANSFORM functions APPEND "()")
  list(JOIN functions ", " calls)
  set(source "${CMAKE_CURRENT_BINARY_DIR}/${library}.cc")
  file(CONFIGURE OUTPUT "${source}" @ONLY CONTENT
"// Generated by enavi_method_list(${library}) (cmake/EnaviHelpers.cmake) from the methods'
// enavi_add_method() calls: do not edit.
#include <vector>

#include \"navstack/methods/method.h\"
${includes}
namespace enavi::navstack {

std::vector<MethodInfo> ${ARG_FUNCTION}() { return {${calls}}; }

}  // namespace enavi::navstack
")
  add_library(${library} "${source}")
  target_link_libraries(${library} PUBLIC enavi::method_api PRIVATE ${libraries})
  set_property(GLOBAL PROPERTY ENAVI_QUEUED_METHOD_LIBRARIES "")
  set_property(GLOBAL PROPERTY ENAVI_QUEUED_METHOD_HEADERS "")
  set_property(GLOBAL PROPERTY ENAVI_QUEUED_METHOD_FUNCTIONS "")
endfunction()
