# Installation and the CMake package: find_package(hemi) + target_link_libraries(app hemi::hemi)
# (hemi::core for math + io alone, hemi::baker for the offline side); bin/ gets hemi-bake and hemi-render.
include(CMakePackageConfigHelpers)

set(HEMI_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/hemi)
# Two export sets: hemiTargets (hemi::core, hemi::hemi: what an engine renders with) and hemiBakerTargets
# (hemi::baker, which needs Embree), so that a render-only engine's find_package(hemi) needs no Embree.
set(hemi_install_destinations
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
    INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS hemi_core hemi EXPORT hemiTargets ${hemi_install_destinations})
# Shared libraries: the installed tools find hemi's libraries beside them, wherever the prefix is moved.
if(BUILD_SHARED_LIBS)
    file(RELATIVE_PATH hemi_bin_to_lib ${CMAKE_INSTALL_FULL_BINDIR} ${CMAKE_INSTALL_FULL_LIBDIR})
    foreach(tool hemi-render hemi-bake)
        if(TARGET ${tool})
            set_target_properties(${tool} PROPERTIES INSTALL_RPATH "$ORIGIN/${hemi_bin_to_lib}")
        endif()
    endforeach()
endif()
if(TARGET hemi_baker)
    install(TARGETS hemi_baker EXPORT hemiBakerTargets ${hemi_install_destinations})
    install(DIRECTORY ${PROJECT_SOURCE_DIR}/baker/include/hemi DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
    install(EXPORT hemiBakerTargets NAMESPACE hemi:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/hemi)
endif()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/engine/include/hemi DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
# hemi's GLSL library (hemi/hemi.glsl, docs/glsl.md) and the shared C++/GLSL headers, for engines' own shaders.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/shaders/include/hemi DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${HEMI_GENERATED_INCLUDE_DIR}/hemi DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}) # generated basis list
install(EXPORT hemiTargets NAMESPACE hemi:: DESTINATION ${HEMI_INSTALL_CMAKEDIR})

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/hemiConfig.cmake.in
    ${PROJECT_BINARY_DIR}/hemiConfig.cmake INSTALL_DESTINATION ${HEMI_INSTALL_CMAKEDIR}
    PATH_VARS CMAKE_INSTALL_INCLUDEDIR)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/hemiConfigVersion.cmake
    VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/hemiConfig.cmake ${PROJECT_BINARY_DIR}/hemiConfigVersion.cmake
    DESTINATION ${HEMI_INSTALL_CMAKEDIR})
