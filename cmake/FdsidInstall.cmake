# `cmake --install build [--prefix DIR]` puts in place:
#   bin/fdsid                                   the command-line tool
#   lib/libfdsid_fast.a, lib/libfdsid_reference.a
#   include/fdsid/*.hpp, include/fdsid/reference/*.hpp
#   lib/cmake/fdsid/fdsidConfig.cmake (+ version, targets)
# so that another project writes
#   find_package(fdsid 0.1 REQUIRED)
#   target_link_libraries(app PRIVATE fdsid::fast)        # or fdsid::reference
# (tests/consumer/ is such a project; the `install` ctest label builds it
# against a fresh install of this build tree). The plot library is private to
# the executable and is not installed.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# A library of the package: its archive, its public headers (the folder
# INCLUDE_ROOT/fdsid), and its name fdsid::EXPORT_NAME.
function(fdsid_install_library target export_name include_root)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${export_name})
  install(TARGETS ${target} EXPORT fdsidTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(DIRECTORY ${include_root}/fdsid
    DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.hpp")
endfunction()

fdsid_install_library(fdsid_fast fast ${PROJECT_SOURCE_DIR}/fast/include)
if(TARGET fdsid_reference)
  fdsid_install_library(fdsid_reference reference ${PROJECT_SOURCE_DIR}/reference/include)
endif()
if(TARGET fdsid)
  install(TARGETS fdsid RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

set(FDSID_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/fdsid)
install(EXPORT fdsidTargets NAMESPACE fdsid:: DESTINATION ${FDSID_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/fdsidConfig.cmake.in
  ${PROJECT_BINARY_DIR}/fdsidConfig.cmake INSTALL_DESTINATION ${FDSID_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/fdsidConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/fdsidConfig.cmake ${PROJECT_BINARY_DIR}/fdsidConfigVersion.cmake
  DESTINATION ${FDSID_CMAKE_DIR})
