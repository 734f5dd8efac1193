# What another project sees of viewpose (issue 21): `cmake --install` of the tested build into a
# fresh prefix, the examples built against it as a standalone project and run, and viewpose taken in
# by add_subdirectory. Run by ctest (package.install_and_examples) with
#   -DBUILD=<build dir> -DSOURCE=<source dir> -DWORK=<scratch dir> -DCXX=<compiler>
cmake_minimum_required(VERSION 3.22)
file(REMOVE_RECURSE ${WORK})
set(prefix ${WORK}/prefix)

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()

run(${CMAKE_COMMAND} --install ${BUILD} --prefix ${prefix})
foreach(f bin/viewpose include/viewpose/recognize/recognizer.hpp include/viewpose/core/file.hpp
          lib/cmake/viewpose/viewposeConfig.cmake lib/cmake/viewpose/viewposeConfigVersion.cmake
          lib/cmake/viewpose/viewposeTargets.cmake)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "cmake --install left out ${f}")
  endif()
endforeach()
file(GLOB_RECURSE module ${prefix}/lib/python*/viewpose*.so)
if(NOT module)
  message(FATAL_ERROR "cmake --install left out the Python module")
endif()
run(${prefix}/bin/viewpose --version)

# The examples, as their README says to build them.
run(${CMAKE_COMMAND} -S ${SOURCE}/examples -B ${WORK}/examples -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_CXX_COMPILER=${CXX})
run(${CMAKE_COMMAND} --build ${WORK}/examples -j 2)
run(${WORK}/examples/recognize_buffer)
if(NOT out MATCHES "can  score")
  message(FATAL_ERROR "recognize_buffer found no can:\n${out}")
endif()
message(STATUS "recognize_buffer: ${out}")
run(${WORK}/examples/build_database ${WORK}/mug.vpdb mug)
run(${prefix}/bin/viewpose db info ${WORK}/mug.vpdb)
if(NOT out MATCHES "mug")
  message(FATAL_ERROR "the database build_database wrote holds no mug:\n${out}")
endif()

# live_camera on a recording (no camera here): a simulated frame of the mug, replayed.
run(${prefix}/bin/viewpose simulate --preset seed-experiment --model mug --orientations 1 --distances 0.8 -o ${WORK}/mug_frames)
run(${WORK}/examples/live_camera ${WORK}/mug.vpdb recording:${WORK}/mug_frames/test/000001)
if(NOT out MATCHES "mug  score")
  message(FATAL_ERROR "live_camera found no mug in the recording:\n${out}")
endif()

# A version that does not match is refused by find_package.
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE}/tests/package/subdirectory -B ${WORK}/wrong_version
                -DCMAKE_PREFIX_PATH=${prefix} -DVIEWPOSE_SOURCE=${SOURCE} -DWANT_VERSION=99.0
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
if(rc EQUAL 0)
  message(FATAL_ERROR "find_package(viewpose 99.0) accepted version 0.1")
endif()

# add_subdirectory: the libraries only, the caller's flags kept (the project checks itself).
run(${CMAKE_COMMAND} -S ${SOURCE}/tests/package/subdirectory -B ${WORK}/subdirectory -DVIEWPOSE_SOURCE=${SOURCE}
    -DCMAKE_CXX_COMPILER=${CXX})
