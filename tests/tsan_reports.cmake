# cmake -P script for ThreadSanitizer builds. MODE=clear: empties DIR, where
# TSAN_OPTIONS log_path puts the reports. MODE=check: prints every report in
# DIR and fails if there is one.
if(MODE STREQUAL "clear")
  file(REMOVE_RECURSE ${DIR})
  file(MAKE_DIRECTORY ${DIR})
  return()
endif()
file(GLOB reports ${DIR}/report*)
if(NOT reports)
  message(STATUS "ThreadSanitizer: no report")
  return()
endif()
foreach(report ${reports})
  file(READ ${report} text)
  message("${report}:\n${text}")
endforeach()
list(LENGTH reports count)
message(FATAL_ERROR "ThreadSanitizer: ${count} processes reported (above)")
