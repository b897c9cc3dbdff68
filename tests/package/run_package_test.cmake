# Installs the built hemi into a fresh prefix, configures and builds a separate project against it with
# find_package(hemi), and runs that project. Invoked by CTest with -DBUILD_DIR, -DSOURCE_DIR, -DWORK_DIR.
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
    message(FATAL_ERROR "cmake --install failed (${rc})")
endif()
# The two command-line tools are part of the package.
foreach(tool hemi-bake hemi-render)
    execute_process(COMMAND ${WORK_DIR}/prefix/bin/${tool} --help RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
    if(rc)
        message(FATAL_ERROR "the installed ${WORK_DIR}/prefix/bin/${tool} does not run (${rc})")
    endif()
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -DCMAKE_BUILD_TYPE=Release
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix
                RESULT_VARIABLE rc)
if(rc)
    message(FATAL_ERROR "configuring the consumer project with find_package(hemi) failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/build RESULT_VARIABLE rc)
if(rc)
    message(FATAL_ERROR "building the consumer project failed (${rc})")
endif()
execute_process(COMMAND ${WORK_DIR}/build/consumer RESULT_VARIABLE rc)
if(rc)
    message(FATAL_ERROR "the consumer program failed (${rc})")
endif()
# The link interface does not force the Vulkan loader (hemi loads its entry points at run time): the
# exported targets name only Vulkan's headers, and the consumer, which makes a hemi::gpu::Device and draws
# nothing with Vulkan itself, runs without linking libvulkan.
file(GLOB targets_files ${WORK_DIR}/prefix/lib*/cmake/hemi/hemiTargets.cmake)
file(READ ${targets_files} targets)
if(targets MATCHES "Vulkan::Vulkan" OR targets MATCHES "libvulkan")
    message(FATAL_ERROR "the installed package's link interface forces the Vulkan loader")
endif()
execute_process(COMMAND ldd ${WORK_DIR}/build/consumer OUTPUT_VARIABLE linked RESULT_VARIABLE rc)
if(rc OR linked MATCHES "libvulkan")
    message(FATAL_ERROR "the consumer links the Vulkan loader (${rc}):\n${linked}")
endif()
