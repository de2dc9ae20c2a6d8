# Writes the build identity header (core/version.hpp.in) at build time, not configure time, so
# a results file never names a commit older than the binary that wrote it (a configure-time
# stamp went stale with every later commit). "-dirty" marks a build from uncommitted changes.
# configure_file rewrites the header only when its text changes, so an unchanged revision
# recompiles nothing. Run as: cmake -DSRC=... -DOUT=... -DPROJECT_VERSION=... -P version.cmake
execute_process(COMMAND git describe --always --dirty --abbrev=12 --exclude=*
                WORKING_DIRECTORY ${SRC}
                OUTPUT_VARIABLE RENDULIC_GIT_SHA OUTPUT_STRIP_TRAILING_WHITESPACE
                ERROR_QUIET)
if(NOT RENDULIC_GIT_SHA)
  set(RENDULIC_GIT_SHA "unknown")
endif()
configure_file(${SRC}/core/version.hpp.in ${OUT} @ONLY)
