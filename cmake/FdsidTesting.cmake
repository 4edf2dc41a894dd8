# fdsid_discover_tests(TARGET LABELS l1;l2;... [WORKING_DIRECTORY dir] [SLOW_ONLY] [SLOW test1 ...] [LONG test1 ...])
#
# gtest_discover_tests with a list of ctest labels. gtest_discover_tests
# (CMake 3.25) flattens list-valued PROPERTIES ("LABELS a;b" becomes LABELS = a
# plus a bogus property b), so the labels are set again from a CTest include file
# that runs after the discovered tests (<target>_TESTS) are defined.
#
# SLOW names tests (Suite.Name) that take minutes under the coverage + ASan/UBSan
# build (Monte Carlo loops, the 50-digit reference at -O1 under ASan): they get
# the label `slow` instead of `quick`, so the Release run of the whole suite
# runs them and the sanitizer/coverage run (`ctest -L quick`) does not.
#
# SLOW_ONLY: every test of TARGET is in SLOW. Such a binary is built only with
# FDSID_BUILD_SLOW_ONLY_TESTS (CMakeLists.txt; the sanitizer/coverage stage of
# scripts/test-all.sh turns it off, since it runs no slow test); a test that
# is not in SLOW then fails the test discovery, so a quick test added to such
# a binary cannot silently go unrun by that stage.
#
# LONG names quick tests that take a large share of the sanitizer/coverage run
# (FrfConsistency.GErrorShrinksLikeOneOverSqrtF: ~150 s of a ~500 s·proc
# suite). They get COST 1000, so ctest -j2 starts them first even in a fresh
# build dir, where it has no Testing/Temporary/CTestCostData.txt yet: started
# last, the longest test ran alone on one core for two minutes (CI: 323 s of
# tests where the cost data of a second run gave ~260 s).
#
# Every test gets TIMEOUT 600 s: 4x the longest quick test under the sanitizers
# (that LONG test, ~150 s) and 10x the longest slow test in Release (~60 s). A
# property whose random seed found a failing case shrinks it with the 50-digit
# reference in every step, which under ASan can take hours (seen once in CI):
# the timeout turns that into a failure with the test's output, whose
# "Using configuration: seed=..." line (scripts/test-all.sh sets RC_PARAMS)
# reproduces it.
include(GoogleTest)
function(fdsid_discover_tests target)
  cmake_parse_arguments(ARG "SLOW_ONLY" "WORKING_DIRECTORY" "LABELS;SLOW;LONG" ${ARGN})
  if(NOT ARG_WORKING_DIRECTORY)
    set(ARG_WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
  endif()
  gtest_discover_tests(${target} WORKING_DIRECTORY ${ARG_WORKING_DIRECTORY} DISCOVERY_TIMEOUT 120)
  set(labels "${ARG_LABELS}")
  set(slow_labels "${ARG_LABELS}")
  list(REMOVE_ITEM slow_labels quick)
  list(APPEND slow_labels slow)
  set(file ${CMAKE_CURRENT_BINARY_DIR}/${target}_labels.cmake)
  set(slow_only_check "")
  if(ARG_SLOW_ONLY)
    string(CONCAT slow_only_check
      "    if(i EQUAL -1)\n"
      "      message(FATAL_ERROR \"fdsid_discover_tests(${target}): SLOW_ONLY, but \${t} is not in SLOW: name it there or move it to a binary with quick tests\")\n"
      "    endif()\n")
  endif()
  # LABELS set twice on one test accumulate here, so each test is set once.
  file(WRITE ${file}
    "if(DEFINED ${target}_TESTS)\n"
    "  set(slow ${ARG_SLOW})\n"
    "  set(long ${ARG_LONG})\n"
    "  foreach(t IN LISTS slow long)\n"
    "    list(FIND ${target}_TESTS \${t} i)\n"
    "    if(i EQUAL -1)\n"
    "      message(FATAL_ERROR \"fdsid_discover_tests(${target}): SLOW/LONG test \${t} does not exist\")\n"
    "    endif()\n"
    "  endforeach()\n"
    "  foreach(t IN LISTS ${target}_TESTS)\n"
    "    set_tests_properties(\${t} PROPERTIES TIMEOUT 600)\n"
    "    list(FIND slow \${t} i)\n"
    "${slow_only_check}"
    "    if(i EQUAL -1)\n"
    "      set_tests_properties(\${t} PROPERTIES LABELS \"${labels}\")\n"
    "    else()\n"
    "      set_tests_properties(\${t} PROPERTIES LABELS \"${slow_labels}\")\n"
    "    endif()\n"
    "  endforeach()\n"
    "  foreach(t IN LISTS long)\n"
    "    set_tests_properties(\${t} PROPERTIES COST 1000)\n"
    "  endforeach()\n"
    "endif()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${file})
endfunction()
