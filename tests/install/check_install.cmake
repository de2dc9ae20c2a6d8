# ctest driver of the installed-package check (docs/install.md): installs the build tree into a
# fresh prefix, configures and builds tests/install/consumer against it, and runs the consumer.
# Run as: cmake -DBUILD=<build dir> -DSRC=<source dir> -DWORK=<scratch dir> -P check_install.cmake
file(REMOVE_RECURSE ${WORK})
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
endfunction()
run(${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/prefix)
foreach(f bin/rendulic share/rendulic/plot.py include/rendulic/core/version.hpp
          include/rendulic/dem/dem_system.hpp lib/cmake/rendulic/rendulicConfig.cmake)
  if(NOT EXISTS ${WORK}/prefix/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
# The editable figure script (docs/figures.md) is the one compiled into the binary.
file(READ ${WORK}/prefix/share/rendulic/plot.py installed_plot)
file(READ ${SRC}/app/plot.py source_plot)
if(NOT installed_plot STREQUAL source_plot)
  message(FATAL_ERROR "share/rendulic/plot.py differs from app/plot.py")
endif()
run(${CMAKE_COMMAND} -S ${SRC}/tests/install/consumer -B ${WORK}/consumer
    -DCMAKE_PREFIX_PATH=${WORK}/prefix -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build ${WORK}/consumer -j 2)
run(${WORK}/consumer/consumer)
run(${WORK}/consumer/consumer_dem_only)
message(STATUS "installed package builds, links and runs")
