# Command-line tests of the fdsid executable: they run build/fdsid as a child
# process and check its exit status, stdout and stderr (contracts: exit 2 on bad
# input with one line on stderr naming the file, line/field and what is wrong).
# Included from tests/CMakeLists.txt.
add_executable(cli_test ${CMAKE_CURRENT_LIST_DIR}/cli_test.cpp)
target_link_libraries(cli_test PRIVATE GTest::gtest_main nlohmann_json::nlohmann_json)
target_compile_definitions(cli_test PRIVATE
  FDSID_EXE="$<TARGET_FILE:fdsid>"
  FDSID_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
# The tests execute fdsid, so it must be built first.
add_dependencies(cli_test fdsid)

# CheckAccepts… runs the 50-digit reference on five candidates: 2.5 min under
# ASan + coverage; CheckRejects… covers the same oracle path there.
fdsid_discover_tests(cli_test LABELS cli unit quick WORKING_DIRECTORY ${PROJECT_BINARY_DIR}
  SLOW Cli.CheckAcceptsASimilarityTransformOfTheTrueSystem)

# identify-frf, simulate-records and reproduce fig1/fig2 (Pintelon 2002); links
# fdsid_fast only to compute the test systems' true FRF and poles.
add_executable(cli_frf_test ${CMAKE_CURRENT_LIST_DIR}/cli_frf_test.cpp)
target_link_libraries(cli_frf_test PRIVATE fdsid_fast fdsid_test_linalg GTest::gtest_main nlohmann_json::nlohmann_json)
target_compile_definitions(cli_frf_test PRIVATE FDSID_EXE="$<TARGET_FILE:fdsid>" FDSID_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
add_dependencies(cli_frf_test fdsid)
fdsid_discover_tests(cli_frf_test LABELS cli unit quick WORKING_DIRECTORY ${PROJECT_BINARY_DIR})

# docs/failure-modes.md: its figures are drawn by docs/make-figures.sh (the
# `docs` target); this runs the script into a scratch folder so that every
# command the walkthrough cites keeps working. Release suite only (label docs,
# not quick: the Monte Carlo reproductions take ~20 s).
add_test(NAME DocsFigures
  COMMAND ${CMAKE_COMMAND} -E env bash ${PROJECT_SOURCE_DIR}/docs/make-figures.sh $<TARGET_FILE:fdsid>
          ${PROJECT_BINARY_DIR}/docs-figures-test)
set_tests_properties(DocsFigures PROPERTIES LABELS "docs;cli" TIMEOUT 600)

# --plot on every command that draws a figure, and the terminal-only progress.
add_executable(cli_plot_test ${CMAKE_CURRENT_LIST_DIR}/cli_plot_test.cpp)
target_link_libraries(cli_plot_test PRIVATE GTest::gtest_main)
target_compile_definitions(cli_plot_test PRIVATE
  FDSID_EXE="$<TARGET_FILE:fdsid>"
  FDSID_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
add_dependencies(cli_plot_test fdsid)
fdsid_discover_tests(cli_plot_test LABELS cli unit quick WORKING_DIRECTORY ${PROJECT_BINARY_DIR})

# fdsid conformance over fixtures/certified: fdsid as the candidate passes every
# case; wrong and broken candidates fail theirs (exit 1), bad input exits 2.
add_executable(cli_conformance_test ${CMAKE_CURRENT_LIST_DIR}/cli_conformance_test.cpp)
target_link_libraries(cli_conformance_test PRIVATE GTest::gtest_main nlohmann_json::nlohmann_json)
target_compile_definitions(cli_conformance_test PRIVATE FDSID_EXE="$<TARGET_FILE:fdsid>" FDSID_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
add_dependencies(cli_conformance_test fdsid)
fdsid_discover_tests(cli_conformance_test LABELS cli unit quick WORKING_DIRECTORY ${PROJECT_BINARY_DIR})

# README.md's examples (review finding 24: its outputs went stale): every
# transcript block runs in a scratch folder and must print what the README
# shows (scripts/readme-examples.py). Release suite only (label docs): the
# examples include Monte Carlo reproductions.
find_program(FDSID_PYTHON3 python3 REQUIRED)
add_test(NAME ReadmeExamples
  COMMAND ${FDSID_PYTHON3} ${PROJECT_SOURCE_DIR}/scripts/readme-examples.py $<TARGET_FILE:fdsid>
          ${PROJECT_SOURCE_DIR}/README.md)
set_tests_properties(ReadmeExamples PROPERTIES LABELS "docs;cli" TIMEOUT 900)
