# The CTest test consumer:find_package: installs the build tree into BUILD_DIR/install, then
# configures, builds and runs tests/consumer (find_package(embody), one body solved) against it.
# Only the consumer's one source file compiles; the project is not rebuilt.
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=.../tests/consumer -DCXX=... [-DLAUNCHER=ccache] -P run_consumer.cmake
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "consumer: ${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(output "${out}" PARENT_SCOPE)
endfunction()

set(prefix "${BUILD_DIR}/install")
set(consumer "${BUILD_DIR}/consumer")
file(REMOVE_RECURSE "${prefix}")
run("cmake --install" "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${prefix}")
run("configure" "${CMAKE_COMMAND}" -S "${SOURCE_DIR}" -B "${consumer}" -DCMAKE_BUILD_TYPE=Release
    "-DCMAKE_PREFIX_PATH=${prefix}" "-DCMAKE_CXX_COMPILER=${CXX}" "-DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER}")
run("build" "${CMAKE_COMMAND}" --build "${consumer}")
run("solve_one_body" "${consumer}/solve_one_body")
message(STATUS "consumer: ${output}")
