# Build time of the sanitizer tree (ENAVI_SANITIZE). CI builds it from scratch, with no compiler
# cache, after the Release tree and its tests, and runs the unit, fault and fuzz tests in it within
# its 30 minutes; docs/reliability.md ("CI's time") has the measurements. The Release build is
# left as it is.
#
# Unity builds (CMAKE_UNITY_BUILD; on here unless set on the command line): a target's sources
# are compiled in batches of up to 8, each batch one translation unit, so the third-party headers
# they share (Eigen, OMPL, Bullet, nlohmann/json, spdlog, CLI11) are parsed, and their inline
# functions instrumented and compiled, once per batch instead of once per file. A source that does
# not combine with the others of its target is named in enavi_unity_exclusions() with the reason.
if(NOT DEFINED CMAKE_UNITY_BUILD)
  set(CMAKE_UNITY_BUILD ON)
endif()

# Test sources (enavi_add_test) compile at -O0: they only drive the code under test, which stays
# at -O1, and instrumenting and optimising each test file's gtest and Eigen instantiations at -O1
# costs a third more compile time than at -O0.
set(ENAVI_TEST_COMPILE_OPTIONS -O0)

# lld links the instrumented binaries (about 100 of them, each with the sanitizer runtimes).
find_program(ENAVI_LLD NAMES ld.lld)
if(ENAVI_LLD)
  add_link_options(-fuse-ld=lld)
endif()

# Sources that do not combine in a unity batch (each defines a file-local helper or constant that
# another source of its target defines too): each is compiled on its own.
function(enavi_unity_exclusions)
  set(exclusions
      enavi_adapt navstack/adapt/resolution_adapter.cc          # RequireNonNegative
      enavi_perception navstack/perception/occupancy_map.cc     # Require
      enavi_perception navstack/perception/points.cc            # Require
      enavi_report server/report/top_down.cc)                   # kPi
  while(exclusions)
    list(POP_FRONT exclusions target source)
    set_source_files_properties(${PROJECT_SOURCE_DIR}/${source} TARGET_DIRECTORY ${target}
                                PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
  endwhile()
endfunction()
