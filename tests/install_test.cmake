# Install.ConsumerBuildsAgainstInstalledTree: `cmake --install` of this build
# tree into a scratch prefix, then tests/consumer/ (a project of its own) is
# configured against it with find_package(fdsid), built, and run. Included from
# tests/CMakeLists.txt; label `install` (not `quick`: the sanitizer build's
# flags would have to reach the consumer too).
add_test(NAME Install.ConsumerBuildsAgainstInstalledTree
  COMMAND ${CMAKE_COMMAND}
    -DBUILD_DIR=${PROJECT_BINARY_DIR}
    -DSOURCE_DIR=${PROJECT_SOURCE_DIR}/tests/consumer
    -DWORK_DIR=${PROJECT_BINARY_DIR}/install-test
    -DGENERATOR=${CMAKE_GENERATOR}
    -DCXX=${CMAKE_CXX_COMPILER}
    -P ${CMAKE_CURRENT_LIST_DIR}/install_test_run.cmake)
set_tests_properties(Install.ConsumerBuildsAgainstInstalledTree PROPERTIES LABELS "install" TIMEOUT 600)
