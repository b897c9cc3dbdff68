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

# A render-only engine: find_package(hemi) with Embree and the Vulkan loader's package out of reach
# (CMAKE_DISABLE_FIND_PACKAGE_<name>: a find_package of either fails the configure), Vulkan's headers from the
# engine's own copy (Vulkan_INCLUDE_DIR; here the system's, copied). It links hemi::hemi alone, and hemi::baker
# must not be loaded.
file(COPY /usr/include/vulkan /usr/include/vk_video DESTINATION ${WORK_DIR}/engine-vulkan-headers)
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/render-only -DCMAKE_BUILD_TYPE=Release
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DRENDER_ONLY=ON
                        -DCMAKE_DISABLE_FIND_PACKAGE_embree=TRUE -DCMAKE_DISABLE_FIND_PACKAGE_Vulkan=TRUE
                        -DVulkan_INCLUDE_DIR=${WORK_DIR}/engine-vulkan-headers
                RESULT_VARIABLE rc)
if(rc)
    message(FATAL_ERROR "a render-only consumer could not configure without Embree and the Vulkan package (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/render-only RESULT_VARIABLE rc)
if(rc)
    message(FATAL_ERROR "building the render-only consumer failed (${rc})")
endif()
execute_process(COMMAND ${WORK_DIR}/render-only/consumer RESULT_VARIABLE rc)
if(rc)
    message(FATAL_ERROR "the render-only consumer failed (${rc})")
endif()
execute_process(COMMAND ldd ${WORK_DIR}/render-only/consumer OUTPUT_VARIABLE linked RESULT_VARIABLE rc)
if(rc OR linked MATCHES "libembree|libvulkan")
    message(FATAL_ERROR "the render-only consumer links Embree or the Vulkan loader (${rc}):\n${linked}")
endif()
