# cmake -DSOURCE=<repo> -DWORK=<scratch> (-DBUILD=<build dir> | -DCONFIGURE=<options>) -P run.cmake
# installs NovaPhy into WORK/prefix, builds tests/consumer against it with the compiler's default flags and
# runs it. BUILD: the install of a configured and built tree. CONFIGURE: a tree of SOURCE configured in
# WORK/library with those options (a ;-list) and only the installed libraries built, so that a test covers
# the package of an option set other than its own build's.
file(REMOVE_RECURSE ${WORK})
if(DEFINED CONFIGURE)
  set(BUILD ${WORK}/library)
  execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE} -B ${BUILD} -DCMAKE_BUILD_TYPE=Release
                          -DNOVAPHY_BUILD_PYTHON=OFF -DNOVAPHY_BUILD_TESTS=OFF ${CONFIGURE}
                  COMMAND_ERROR_IS_FATAL ANY OUTPUT_QUIET)
  load_cache(${BUILD} READ_WITH_PREFIX library_ NOVAPHY_WITH_MPI)
  set(libraries novaphy_engine)
  if(library_NOVAPHY_WITH_MPI)
    list(APPEND libraries novaphy_mpi)
  endif()
  cmake_host_system_information(RESULT cores QUERY NUMBER_OF_LOGICAL_CORES)
  execute_process(COMMAND ${CMAKE_COMMAND} --build ${BUILD} --parallel ${cores} --target ${libraries}
                  COMMAND_ERROR_IS_FATAL ANY OUTPUT_QUIET)
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/prefix COMMAND_ERROR_IS_FATAL ANY
                OUTPUT_QUIET)

# the headers: the engine's and the kernels', the MPI component's where the package has that component
set(include ${WORK}/prefix/include/novaphy)
foreach(header engine/model/builder.h engine/import/mjcf_import.h engine/solver/solver_featherstone.h kernels/lanes.h)
  if(NOT EXISTS ${include}/${header})
    message(FATAL_ERROR "the installed package lacks ${header}")
  endif()
endforeach()
file(GLOB_RECURSE targets_files ${WORK}/prefix/*/novaphyTargets.cmake)
file(READ "${targets_files}" targets)
string(FIND "${targets}" "novaphy::mpi" has_mpi)
if((has_mpi GREATER -1) AND NOT EXISTS ${include}/engine/mpi/sharded_batch.h)
  message(FATAL_ERROR "the installed package has novaphy::mpi but not engine/mpi/sharded_batch.h")
elseif((has_mpi EQUAL -1) AND EXISTS ${include}/engine/mpi/sharded_batch.h)
  message(FATAL_ERROR "the installed package has engine/mpi/sharded_batch.h but not novaphy::mpi")
endif()

execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE}/tests/consumer -B ${WORK}/build
                        -DCMAKE_PREFIX_PATH=${WORK}/prefix -DCMAKE_BUILD_TYPE=Release COMMAND_ERROR_IS_FATAL ANY
                OUTPUT_QUIET)
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK}/build COMMAND_ERROR_IS_FATAL ANY OUTPUT_QUIET)
execute_process(COMMAND ${WORK}/build/consumer COMMAND_ERROR_IS_FATAL ANY)
if(EXISTS ${WORK}/build/consumer_mpi)
  execute_process(COMMAND ${WORK}/build/consumer_mpi COMMAND_ERROR_IS_FATAL ANY)
endif()

# code compiled for another vector width is stopped, with the library's -march named
if(EXISTS ${WORK}/build/other_arch.txt)
  file(READ ${WORK}/build/other_arch.txt other_arch)
  execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK}/build --target consumer_other_arch
                  RESULT_VARIABLE other_result OUTPUT_VARIABLE other_output ERROR_VARIABLE other_output)
  if(other_result EQUAL 0 OR NOT other_output MATCHES "NovaPhy's library was compiled with ([^,]+), for a target")
    message(FATAL_ERROR "a consumer compiled with -march=${other_arch} was not stopped:\n${other_output}")
  endif()
  message(STATUS "a consumer compiled with -march=${other_arch} is stopped: NovaPhy's library was compiled with "
                 "${CMAKE_MATCH_1}")
endif()
