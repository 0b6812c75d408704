# ctest driver (cmake -P): install the lodrt component of a build tree into a scratch prefix, then
# configure, build and run the consumer project in this folder against that prefix only.
# Inputs: LODRT_BUILD_DIR, LODRT_CONFIG, CONSUMER_SOURCE_DIR, WORK_DIR, CXX_COMPILER, NINJA.
foreach(var LODRT_BUILD_DIR CONSUMER_SOURCE_DIR WORK_DIR CXX_COMPILER NINJA)
    if(NOT DEFINED ${var})
        message(FATAL_ERROR "run_install_test.cmake: ${var} is not set")
    endif()
endforeach()

file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")

function(run_step name)
    execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "${name} failed (${rc}):\n${out}\n${err}")
    endif()
    set(step_output "${out}" PARENT_SCOPE)
endfunction()

set(config_args)
if(LODRT_CONFIG)
    set(config_args --config "${LODRT_CONFIG}")
endif()
run_step(install "${CMAKE_COMMAND}" --install "${LODRT_BUILD_DIR}" --prefix "${prefix}" --component lodrt ${config_args})
if(NOT EXISTS "${prefix}/include/lodrt/lodrt.h")
    message(FATAL_ERROR "install did not place include/lodrt/lodrt.h under ${prefix}")
endif()

run_step(configure "${CMAKE_COMMAND}" -S "${CONSUMER_SOURCE_DIR}" -B "${WORK_DIR}/build" -G Ninja
    "-DCMAKE_MAKE_PROGRAM=${NINJA}" "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}" -DCMAKE_BUILD_TYPE=Release
    "-DCMAKE_PREFIX_PATH=${prefix}" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
# The package must come from the scratch prefix, never from the build tree or the system.
string(FIND "${step_output}" "lodrt_DIR=${prefix}/" found)
if(found EQUAL -1)
    message(FATAL_ERROR "lodrt was not found under ${prefix}:\n${step_output}")
endif()

run_step(build "${CMAKE_COMMAND}" --build "${WORK_DIR}/build")
run_step(run "${WORK_DIR}/build/lodrt_install_consumer")
message(STATUS "${step_output}")
if(NOT step_output MATCHES "GLB ok")
    message(FATAL_ERROR "consumer printed an unexpected result: ${step_output}")
endif()
