# Warnings for hemi's own targets only (third-party headers come in as SYSTEM includes).
function(hemi_set_warnings target)
    if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
        target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                                 -Wno-missing-field-initializers)
    elseif(MSVC)
        target_compile_options(${target} PRIVATE /W4)
    endif()
endfunction()

# A library of hemi's package: its export name, and as a shared library (BUILD_SHARED_LIBS) a SONAME that
# changes with the minor version (0.x: the minor version is the ABI, as the package's SameMinorVersion says)
# and only hemi's own symbols exported (cmake/hemi.map).
function(hemi_library_properties target export_name)
    set_target_properties(${target} PROPERTIES VERSION ${PROJECT_VERSION}
        SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR} EXPORT_NAME ${export_name})
    get_target_property(type ${target} TYPE)
    if(type STREQUAL "SHARED_LIBRARY")
        target_link_options(${target} PRIVATE "LINKER:--version-script=${PROJECT_SOURCE_DIR}/cmake/hemi.map")
        set_property(TARGET ${target} APPEND PROPERTY LINK_DEPENDS ${PROJECT_SOURCE_DIR}/cmake/hemi.map)
        # Built and installed, hemi's libraries find each other beside themselves (libhemi.so needs
        # libhemi_core.so). Installed, the RUNPATH is "$ORIGIN" alone (.ci/shared_library checks it); in the
        # build tree CMake leaves an empty entry after it, room for the install-time rewrite.
        set_target_properties(${target} PROPERTIES INSTALL_RPATH "$ORIGIN" BUILD_RPATH "$ORIGIN")
    endif()
endfunction()
