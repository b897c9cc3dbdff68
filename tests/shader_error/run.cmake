# Configures and builds tests/shader_error; passes only if the build fails and glslang's message names
# broken.comp and its line 5.
file(REMOVE_RECURSE ${WORK_DIR})
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR} -DHEMI_CMAKE_DIR=${HEMI_CMAKE_DIR}
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
    message(FATAL_ERROR "configuring the shader-error project failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0)
    message(FATAL_ERROR "a shader with a syntax error built successfully")
endif()
if(NOT "${out}${err}" MATCHES "broken\\.comp:5")
    message(FATAL_ERROR "the build failed but did not name broken.comp:5:\n${out}${err}")
endif()
message(STATUS "build failed as it should, naming broken.comp:5")
