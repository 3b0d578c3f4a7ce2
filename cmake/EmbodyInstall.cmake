# The installed package: `cmake --install build --prefix DIR` puts the headers (include/embody/),
# the static libraries (lib/) and lib/cmake/embody/embodyConfig.cmake, so another project does
#   find_package(embody REQUIRED)
#   target_link_libraries(app PRIVATE embody::runtime)   # or embody::ik, embody::avatar, ...
# (docs/api.md; tests/consumer builds and runs such a project against an installed tree).
# The product libraries install themselves (embody_library / embody_install_library in
# EmbodyCompilerOptions.cmake); the helper targets below are only named in their link interface.
include(CMakePackageConfigHelpers)

embody_install_library(embody_warnings)
if(NOT EMBODY_IK_ONLY)
  foreach(helper embody_stb embody_tinygltf embody_shaders)
    embody_install_library(${helper})
  endforeach()
endif()

install(EXPORT embodyTargets NAMESPACE embody:: DESTINATION lib/cmake/embody FILE embodyTargets.cmake)
configure_package_config_file("${CMAKE_SOURCE_DIR}/cmake/embodyConfig.cmake.in"
                              "${CMAKE_BINARY_DIR}/generated/embodyConfig.cmake"
                              INSTALL_DESTINATION lib/cmake/embody)
write_basic_package_version_file("${CMAKE_BINARY_DIR}/generated/embodyConfigVersion.cmake"
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES "${CMAKE_BINARY_DIR}/generated/embodyConfig.cmake"
              "${CMAKE_BINARY_DIR}/generated/embodyConfigVersion.cmake"
        DESTINATION lib/cmake/embody)
