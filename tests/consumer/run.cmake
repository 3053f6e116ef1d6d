# cmake -DSOURCE=<repo> -DBUILD=<build dir> -DWORK=<scratch> -P run.cmake
# installs the built tree into WORK/prefix, builds tests/consumer against it and runs it
file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/prefix COMMAND_ERROR_IS_FATAL ANY
                OUTPUT_QUIET)
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE}/tests/consumer -B ${WORK}/build
                        -DCMAKE_PREFIX_PATH=${WORK}/prefix -DCMAKE_BUILD_TYPE=Release COMMAND_ERROR_IS_FATAL ANY
                OUTPUT_QUIET)
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK}/build COMMAND_ERROR_IS_FATAL ANY OUTPUT_QUIET)
execute_process(COMMAND ${WORK}/build/consumer COMMAND_ERROR_IS_FATAL ANY)
if(EXISTS ${WORK}/build/consumer_mpi)
  execute_process(COMMAND ${WORK}/build/consumer_mpi COMMAND_ERROR_IS_FATAL ANY)
endif()
