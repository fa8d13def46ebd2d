# RELIEF_FUZZ=ON: every library of the build gets libFuzzer's coverage
# instrumentation plus AddressSanitizer and UndefinedBehaviorSanitizer, so a
# fuzz target sees (and is guided by) the code it reaches, not only its own.
# Only clang has libFuzzer; clang < 16 cannot compile <expected> from libstdc++ 12.
if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang" OR CMAKE_CXX_COMPILER_VERSION VERSION_LESS 16)
  message(FATAL_ERROR "RELIEF_FUZZ needs clang >= 16 (Debian: clang-19 libclang-rt-19-dev; "
    "-DCMAKE_CXX_COMPILER=clang++-19), not ${CMAKE_CXX_COMPILER_ID} ${CMAKE_CXX_COMPILER_VERSION}")
endif()
add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined
  -fno-omit-frame-pointer -gline-tables-only)
add_link_options(-fsanitize=address,undefined)
