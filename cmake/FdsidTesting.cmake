# fdsid_discover_tests(TARGET LABELS l1;l2;... [WORKING_DIRECTORY dir])
#
# gtest_discover_tests with a list of ctest labels. gtest_discover_tests
# (CMake 3.25) flattens list-valued PROPERTIES ("LABELS a;b" becomes LABELS = a
# plus a bogus property b), so the labels are set again from a CTest include file
# that runs after the discovered tests (<target>_TESTS) are defined.
include(GoogleTest)
function(fdsid_discover_tests target)
  cmake_parse_arguments(ARG "" "WORKING_DIRECTORY" "LABELS" ${ARGN})
  if(NOT ARG_WORKING_DIRECTORY)
    set(ARG_WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
  endif()
  gtest_discover_tests(${target} WORKING_DIRECTORY ${ARG_WORKING_DIRECTORY} DISCOVERY_TIMEOUT 120)
  set(labels "${ARG_LABELS}")
  set(file ${CMAKE_CURRENT_BINARY_DIR}/${target}_labels.cmake)
  file(WRITE ${file}
    "if(DEFINED ${target}_TESTS)\n"
    "  set_tests_properties(\${${target}_TESTS} PROPERTIES LABELS \"${labels}\")\n"
    "endif()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${file})
endfunction()
