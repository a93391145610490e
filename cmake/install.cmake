# `cmake --install build --prefix P` (docs/design.md §4 "Install"): the raycell command and its
# plot scripts, and for programs of their own that read and write traces, the trace schema, the
# headers and the static libraries raycell_traces and raycell_base, exported as the CMake
# package `raycell` (find_package(raycell) gives raycell::traces). Nothing else: no tests,
# benchmarks or other modules' libraries. Included at the end of the top-level CMakeLists.txt;
# tests/install checks it with a consumer project built against an installed tree.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(RAYCELL_INSTALL_INCLUDEDIR ${CMAKE_INSTALL_INCLUDEDIR}/raycell)
set(RAYCELL_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/raycell)

install(TARGETS raycell RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# `raycell study` and `raycell suite` look for them next to its binary, then in
# <bindir>/../share/raycell; the suite's scene files likewise in share/raycell/scenes.
install(PROGRAMS tools/plot_study.py tools/plot_accuracy.py tools/plot_suite.py tools/plot_scale.py
        DESTINATION ${CMAKE_INSTALL_DATADIR}/raycell)
if(EXISTS ${PROJECT_SOURCE_DIR}/scenes)
  install(DIRECTORY scenes/ DESTINATION ${CMAKE_INSTALL_DATADIR}/raycell/scenes
          FILES_MATCHING PATTERN "*.toml")
endif()

# The headers keep the paths they include each other by ("traces/ray_batch.h",
# "base/typed_id.h"), under include/raycell. Every header of traces/ (columns.h includes the
# generated trace.capnp.h), the schema, and the base/ headers they include, with check.h for
# InputError, which every reader and writer throws.
install(DIRECTORY traces/ DESTINATION ${RAYCELL_INSTALL_INCLUDEDIR}/traces
        FILES_MATCHING PATTERN "*.h" PATTERN "trace.capnp")
install(FILES ${PROJECT_BINARY_DIR}/traces/trace.capnp.h
        DESTINATION ${RAYCELL_INSTALL_INCLUDEDIR}/traces)
install(FILES base/check.h base/hash.h base/typed_id.h
        DESTINATION ${RAYCELL_INSTALL_INCLUDEDIR}/base)

set_target_properties(raycell_base PROPERTIES EXPORT_NAME base)
set_target_properties(raycell_traces PROPERTIES EXPORT_NAME traces)
install(TARGETS raycell_traces raycell_base EXPORT raycellTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${RAYCELL_INSTALL_INCLUDEDIR})
install(EXPORT raycellTargets NAMESPACE raycell:: DESTINATION ${RAYCELL_INSTALL_CMAKEDIR})

configure_package_config_file(cmake/raycellConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/raycellConfig.cmake
                              INSTALL_DESTINATION ${RAYCELL_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/raycellConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/raycellConfig.cmake
              ${PROJECT_BINARY_DIR}/raycellConfigVersion.cmake
        DESTINATION ${RAYCELL_INSTALL_CMAKEDIR})
