# A Catch2 test whose name holds ';' is split by CMake's list handling into tests that match nothing and
# "pass" without running. Fails when any TEST_CASE name under tests/ contains one.
file(GLOB_RECURSE sources "${TESTS_DIR}/*.cpp")
set(bad "")
foreach(f ${sources})
  file(STRINGS "${f}" lines REGEX "TEST_CASE\\(\"[^\"]*;")
  if(lines)
    list(APPEND bad "${f}")
  endif()
endforeach()
if(bad)
  message(FATAL_ERROR "TEST_CASE names with ';' (ctest would not run them): ${bad}")
endif()
message(STATUS "test names ok")
