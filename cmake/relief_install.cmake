# Install and export rules: another CMake project finds an installed relief
# with find_package(relief) and links relief::tiles, relief::ingest, ...
# (docs/building.md). tests/install/ checks it end to end.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(RELIEF_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/relief)

# A relief library: public headers in the module's include/, installed with
# the library and exported as relief::<name> (also its name inside the build).
function(relief_library target name)
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  # The headers use std::expected: every consumer compiles as C++23.
  target_compile_features(${target} PUBLIC cxx_std_23)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  add_library(relief::${name} ALIAS ${target})
  install(TARGETS ${target} EXPORT reliefTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()

# Where loadable modules are installed (relief/base/module.h looks there).
set(RELIEF_MODULE_INSTALL_SUBDIR ${CMAKE_INSTALL_LIBDIR}/relief)

# A module that `consumer` loads at run time with relief::load_module_symbol:
# installed in RELIEF_MODULE_INSTALL_SUBDIR, its path in the build tree
# passed to the consumer as PREFIX_MODULE_BUILD_PATH.
function(relief_loadable_module consumer module prefix)
  set_target_properties(${module} PROPERTIES CXX_VISIBILITY_PRESET hidden)
  install(TARGETS ${module} LIBRARY DESTINATION ${RELIEF_MODULE_INSTALL_SUBDIR})
  target_compile_definitions(${consumer} PRIVATE
    ${prefix}_MODULE_BUILD_PATH="$<TARGET_FILE:${module}>")
  add_dependencies(${consumer} ${module})
endfunction()

# The export set, reliefConfig.cmake and its version file; call once, after
# every relief_library().
function(relief_install_package)
  # Static libraries carry their private dependencies as link-only entries of
  # the export: reliefConfig.cmake must then find them too (shared ones hide them).
  if(BUILD_SHARED_LIBS)
    set(RELIEF_STATIC_LIBS OFF)
  else()
    set(RELIEF_STATIC_LIBS ON)
  endif()
  install(EXPORT reliefTargets NAMESPACE relief:: DESTINATION ${RELIEF_CMAKE_DIR})
  configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/reliefConfig.cmake.in
    ${PROJECT_BINARY_DIR}/reliefConfig.cmake INSTALL_DESTINATION ${RELIEF_CMAKE_DIR})
  # 0.x: a minor version may break the API.
  write_basic_package_version_file(${PROJECT_BINARY_DIR}/reliefConfigVersion.cmake
    COMPATIBILITY SameMinorVersion)
  install(FILES ${PROJECT_BINARY_DIR}/reliefConfig.cmake ${PROJECT_BINARY_DIR}/reliefConfigVersion.cmake
    DESTINATION ${RELIEF_CMAKE_DIR})
endfunction()
